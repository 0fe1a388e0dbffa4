#!/usr/bin/python3
"""`ident fit` on a long CSV record against a plain fast parse of the same file: a simulated ARX(2,2,1) record
of 10^7 rows and 3 columns (t, u, y; 17 significant digits), fitted streamed by
`ident fit FILE --output y --input u --na 2 --nb 2 --nk 1 --estimator rls`, and parsed by build/bench/fast_parse
(block reads, std::from_chars, the sum of all values printed). Both run in turn REPETITIONS times after an
untimed parse that brings the file into the page cache; the figures are medians of wall and CPU (user + system)
seconds, their ratios, the fit's peak resident memory, and (with strace) how often the fit opens the file and
how many bytes it reads from it, in file sizes.

    /usr/bin/python3 bench/read_speed.py [--rows 10000000] [--dir /tmp] [--repetitions 3] [--ident PATH]
                                         [--json OUT]

Needs a Release build in build/ (build/bin/ident; it builds build/bench/fast_parse) and numpy/scipy; the file
(~570 MB at 10^7 rows) is written once to --dir and reused while its size matches.
"""
import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import tempfile

import numpy as np
from scipy.signal import lfilter

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
IDENT = os.path.join(ROOT, "build", "bin", "ident")
FAST_PARSE = os.path.join(ROOT, "build", "bench", "fast_parse")
MODEL = ["--output", "y", "--input", "u", "--na", "2", "--nb", "2", "--nk", "1", "--estimator", "rls"]


def write_record(path, rows):
    """t = 0.01 k, u white Gaussian, y = ARX(2,2,1) output plus 0.1 white noise; 17 significant digits."""
    rng = np.random.default_rng(27)
    block = 500_000
    state = np.zeros(2)
    with open(path, "w", encoding="ascii") as f:
        f.write("t,u,y\n")
        for start in range(0, rows, block):
            n = min(block, rows - start)
            u = rng.normal(size=n)
            # y(t) = 1.5 y(t-1) - 0.7 y(t-2) + u(t-1) + 0.5 u(t-2) + e(t), filtered block by block
            x, state = lfilter([0, 1.0, 0.5], [1, -1.5, 0.7], u, zi=state)
            y = x + 0.1 * rng.normal(size=n)
            t = 0.01 * np.arange(start, start + n)
            np.savetxt(f, np.column_stack([t, u, y]), delimiter=",", fmt="%.17g")


def timed(cmd):
    """Wall seconds, CPU seconds (user + system), peak RSS in kB and stdout of one run, from /usr/bin/time
    (the program's parent: a child of this Python process would count its memory too)."""
    with tempfile.NamedTemporaryFile(suffix=".time") as times, tempfile.TemporaryFile() as out:
        subprocess.run(["/usr/bin/time", "-o", times.name, "-f", "%e %U %S %M"] + cmd, stdout=out,
                       stderr=subprocess.DEVNULL, check=True)
        wall, user, system, rss = open(times.name, encoding="utf-8").read().split()[-4:]
        out.seek(0)
        text = out.read().decode()
    return float(wall), float(user) + float(system), int(rss), text


def file_reads(cmd, path):
    """Opens of `path` and bytes read from it by `cmd`, from strace (None without strace)."""
    if shutil.which("strace") is None:
        return None
    with tempfile.NamedTemporaryFile(suffix=".strace") as log:
        subprocess.run(["strace", "-f", "-e", "trace=openat,read,pread64,close", "-o", log.name] + cmd, check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        # With -f, a call that another thread interrupts is logged in two lines, "<unfinished ...>" and then
        # "<... read resumed>": the fd is taken from the first, by the thread's pid.
        opens, read_bytes, fds, pending = 0, 0, set(), {}
        name = re.escape(os.path.basename(path))
        with open(log.name, encoding="utf-8", errors="replace") as f:
            for line in f:
                pid, _, call = line.partition(" ")
                m = re.search(r'openat\(AT_FDCWD, "[^"]*' + name + r'", [^)]*\) = (\d+)', call)
                if m:
                    opens += 1
                    fds.add(m.group(1))
                    continue
                m = re.search(r"\b(?:read|pread64)\((\d+), .*<unfinished \.\.\.>$", call)
                if m:
                    pending[pid] = m.group(1)
                    continue
                m = re.search(r"<\.\.\. (?:read|pread64) resumed>.*\) = (\d+)$", call)
                if m:
                    if pending.pop(pid, None) in fds:
                        read_bytes += int(m.group(1))
                    continue
                m = re.search(r"\b(?:read|pread64)\((\d+), .*\) = (\d+)$", call)
                if m and m.group(1) in fds:
                    read_bytes += int(m.group(2))
                    continue
                m = re.search(r"\bclose\((\d+)\)", call)
                if m:
                    fds.discard(m.group(1))
    return {"opens": opens, "bytes_read": read_bytes, "file_sizes_read": round(read_bytes / os.path.getsize(path), 3)}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rows", type=int, default=10_000_000)
    p.add_argument("--dir", default=tempfile.gettempdir(), help="where the record is written (and kept)")
    p.add_argument("--repetitions", type=int, default=3)
    p.add_argument("--ident", default=IDENT, help="the ident program to time (default: build/bin/ident)")
    p.add_argument("--json", help="write the figures to this file")
    args = p.parse_args()
    path = os.path.join(args.dir, f"ident_read_speed_{args.rows}.csv")
    if not os.path.exists(path) or os.path.getsize(path) < 40 * args.rows:
        write_record(path, args.rows)
    # fast_parse is not in the default build (bench/CMakeLists.txt).
    subprocess.run(["cmake", "--build", os.path.join(ROOT, "build"), "--target", "fast_parse"], check=True,
                   stdout=subprocess.DEVNULL)
    fit_cmd = [args.ident, "fit", path] + MODEL
    parse_cmd = [FAST_PARSE, path]
    timed(parse_cmd)  # the file into the page cache
    fit, parse = [], []
    for _ in range(args.repetitions):
        parse.append(timed(parse_cmd))
        fit.append(timed(fit_cmd))
    theta = re.findall(r"^\s+(a1|a2|b1|b2)\s+(\S+)", fit[-1][3], re.M)

    def median(runs, i):
        return round(statistics.median(r[i] for r in runs), 3)

    figures = {
        "rows": args.rows, "input_bytes": os.path.getsize(path), "repetitions": args.repetitions,
        "fit_command": " ".join(["build/bin/ident", "fit", "FILE"] + MODEL),
        "fast_parse_command": "build/bench/fast_parse FILE",
        "fit_wall_seconds": median(fit, 0), "fit_cpu_seconds": median(fit, 1),
        "fast_parse_wall_seconds": median(parse, 0), "fast_parse_cpu_seconds": median(parse, 1),
        "fit_peak_rss_kb": max(r[2] for r in fit), "fast_parse_peak_rss_kb": max(r[2] for r in parse),
        "theta": {k: float(v) for k, v in theta}, "true_theta": {"a1": -1.5, "a2": 0.7, "b1": 1.0, "b2": 0.5},
    }
    figures["wall_ratio"] = round(figures["fit_wall_seconds"] / figures["fast_parse_wall_seconds"], 3)
    figures["cpu_ratio"] = round(figures["fit_cpu_seconds"] / figures["fast_parse_cpu_seconds"], 3)
    figures["fit_file_reads"] = file_reads(fit_cmd, path)
    print(json.dumps(figures, indent=1))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(figures, f, indent=1)


if __name__ == "__main__":
    main()
