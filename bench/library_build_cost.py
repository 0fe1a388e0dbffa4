#!/usr/bin/python3
"""CPU time of a clean Release build of the library targets alone, at one or more commits: each commit is
checked out into a temporary worktree, configured with the command-line program, tests, benchmarks,
examples, Python package, fuzzers and install rules off (what is left is the library), and built with
`cmake --build -j N` under /usr/bin/time; the figures are user + system CPU seconds and wall seconds of the
build step (the median of --repetitions clean builds), and the ratio of each commit's CPU time to the first's.

    /usr/bin/python3 bench/library_build_cost.py 6db5921 HEAD [--jobs 2] [--repetitions 1] [--with-cli]
                                                 [--json OUT]

--with-cli builds the command-line program too (the library and what it is for: a comparison that does
not depend on which layer the fitting workflow lives in).

Needs git, cmake, ninja and the Debian packages of .ci/debian-packages.
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OFF = ["IDENT_BUILD_TESTS", "IDENT_BUILD_TOOLS", "IDENT_BUILD_BENCHMARKS", "IDENT_BUILD_EXAMPLES",
       "IDENT_BUILD_PYTHON", "IDENT_BUILD_FUZZERS", "IDENT_INSTALL", "IDENT_BUILD_PACKAGE_TESTS"]


def git(*args, cwd=ROOT):
    return subprocess.run(["git", *args], cwd=cwd, check=True, text=True, capture_output=True).stdout.strip()


def build_once(source, build, jobs, off):
    """(CPU seconds, wall seconds) of configuring `source` into a fresh `build` and building it."""
    shutil.rmtree(build, ignore_errors=True)
    subprocess.run(["cmake", "-S", source, "-B", build, "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
                    "--no-warn-unused-cli"] + [f"-D{o}=OFF" for o in off],
                   check=True, stdout=subprocess.DEVNULL)
    with tempfile.NamedTemporaryFile(suffix=".time") as times:
        subprocess.run(["/usr/bin/time", "-o", times.name, "-f", "%e %U %S", "cmake", "--build", build, "-j",
                        str(jobs)], check=True, stdout=subprocess.DEVNULL)
        wall, user, system = open(times.name, encoding="utf-8").read().split()[-3:]
    return float(user) + float(system), float(wall)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("commits", nargs="+", help="commits to build (the first is the reference)")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--repetitions", type=int, default=1)
    p.add_argument("--with-cli", action="store_true", help="build the command-line program too")
    p.add_argument("--json", help="write the figures to this file")
    args = p.parse_args()
    off = [o for o in OFF if not (args.with_cli and o == "IDENT_BUILD_TOOLS")]
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for commit in args.commits:
            full = git("rev-parse", commit)
            tree = os.path.join(work, full[:12])
            git("worktree", "add", "--detach", tree, full)
            try:
                runs = [build_once(tree, os.path.join(work, "build-" + full[:12]), args.jobs, off)
                        for _ in range(args.repetitions)]
            finally:
                git("worktree", "remove", "--force", tree)
            rows.append({"commit": full, "cpu_seconds": round(statistics.median(r[0] for r in runs), 1),
                         "wall_seconds": round(statistics.median(r[1] for r in runs), 1)})
    for row in rows:
        row["cpu_ratio_to_first"] = round(row["cpu_seconds"] / rows[0]["cpu_seconds"], 3)
    figures = {"jobs": args.jobs, "repetitions": args.repetitions, "options_off": off, "builds": rows}
    text = json.dumps(figures, indent=1)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            f.write(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
