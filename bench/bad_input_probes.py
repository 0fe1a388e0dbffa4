#!/usr/bin/env python3
"""Runs every bad-input probe of docs/reference/cli.md ("Results that are not usable", "Limits", "Output
files") against the built `ident` and prints, per probe, its exit code, CPU seconds, peak resident memory
(from /usr/bin/time -v) and the first stderr line; then checks that no input or pre-existing file was
modified or removed.

  /usr/bin/python3 bench/bad_input_probes.py [--ident build/bin/ident] [--datasets datasets]

Exit code 1 if a probe exits 0 with a result it should refuse, takes more than 2 CPU seconds or 200 MB
before its error, or changes a file it was given.
"""
import argparse
import csv
import hashlib
import math
import os
import shutil
import subprocess
import sys
import tempfile


def scaled(src, dst, su, sy):
    rows = list(csv.reader(open(src)))
    with open(dst, "w") as f:
        f.write(",".join(rows[0]) + "\n")
        for r in rows[1:]:
            if r:
                f.write("%s,%r,%r\n" % (r[0], float(r[1]) * su, float(r[2]) * sy))


def digest(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest() if os.path.lexists(path) else None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ident", default="build/bin/ident")
    ap.add_argument("--datasets", default="datasets")
    a = ap.parse_args()
    ident = os.path.abspath(a.ident)
    tmp = tempfile.mkdtemp(prefix="ident-probes-")
    dryer = os.path.join(a.datasets, "dryer.csv")
    d = os.path.join(tmp, "d.csv")
    shutil.copy(dryer, d)
    keep = os.path.join(tmp, "keep.csv")
    open(keep, "w").write("precious\n")
    ragged = os.path.join(tmp, "ragged.csv")
    open(ragged, "w").write("t,u,y\n1,2,3\n4,5\n")
    scaled(dryer, os.path.join(tmp, "e90.csv"), 1e90, 1e90)
    scaled(dryer, os.path.join(tmp, "em90.csv"), 1e-90, 1e-90)
    scaled(dryer, os.path.join(tmp, "em200.csv"), 1e-200, 1e-200)
    scaled(dryer, os.path.join(tmp, "mixed.csv"), 1e-100, 1e100)
    with open(os.path.join(tmp, "wide.csv"), "w") as f:
        f.write(",".join("c%d" % i for i in range(100000)) + "\n")
        f.write(",".join("1" for _ in range(100000)) + "\n")
    with open(os.path.join(tmp, "cell.csv"), "w") as f:
        f.write("u,y\n" + "1" * 100_000_000 + ",2\n")
    os.symlink(keep, os.path.join(tmp, "link.csv"))
    os.mkdir(os.path.join(tmp, "adir"))
    A = "--output y --input u --na 2 --nb 2 --nk 3"
    probes = [  # (name, command, may it exit 0?)
        ("trace = data file", f"fit {d} {A} --trace {d}", False),
        ("trace = existing file, ragged data", f"fit {ragged} {A} --trace {keep}", False),
        ("trace through a symbolic link, ragged data", f"fit {ragged} {A} --trace {tmp}/link.csv", False),
        ("trace on a device", f"fit {d} {A} --trace /dev/null", False),
        ("mems --csv X --trace X", f"mems --steps 400 --grid-points 16 --t-mean 1 --csv {keep} --trace {keep}", False),
        ("cauchy on dryer x 1e-90", f"fit {tmp}/em90.csv {A} --estimator cauchy", True),
        ("compare on dryer x 1e-90", f"compare {tmp}/em90.csv {A} --estimators rls,cauchy,student:3", True),
        ("student --dof 1e80", f"fit dryer {A} --estimator student --dof 1e80", True),
        ("rls --forgetting 0.5", f"fit dryer {A} --forgetting 0.5", False),
        ("u x 1e-100, y x 1e100", f"fit {tmp}/mixed.csv {A}", False),
        ("mems --h 1e-300", "mems --h 1e-300", False),
        ("--json > /dev/full", f"fit dryer {A} --json > /dev/full", False),
        ("closed stdout", f"fit dryer {A} --json >&-", False),
        ("mems --csv /dev/full", "mems --steps 400 --grid-points 16 --t-mean 1 --csv /dev/full", False),
        ("--na 2000", "fit dryer --output y --input u --na 2000", False),
        ("--na 5000", "fit dryer --output y --input u --na 5000", False),
        ("100 000 columns", f"fit {tmp}/wide.csv --output c1 --input c2", False),
        ("/dev/zero as data", f"fit /dev/zero {A}", False),
        ("a 100 MB cell", f"fit {tmp}/cell.csv --output y --input u", False),
        ("--lock-in-window 2147483647", f"fit dryer {A} --estimator cauchy --lock-in-window 2147483647", False),
        ("data x 1e-200", f"fit {tmp}/em200.csv {A}", False),
        ("--dof 1e-300", f"fit dryer {A} --estimator student --dof 1e-300", False),
        ("--prior DIR", f"fit dryer {A} --prior {tmp}/adir", False),
        ("--delta with rls", f"fit dryer {A} --delta 0", False),
        ("compare rls,,cauchy", f"compare dryer {A} --estimators rls,,cauchy", False),
        ("compare, one estimator failing", f"compare {tmp}/e90.csv {A} --estimators rls,cauchy", True),
    ]
    watched = [dryer, d, keep, ragged, os.path.join(tmp, "link.csv")]
    before = {p: digest(p) for p in watched}
    failures = 0
    print("| probe | exit | CPU s | max RSS MB | stderr (first 110 characters) |")
    print("|---|---|---|---|---|")
    for name, command, may_succeed in probes:
        timing = os.path.join(tmp, "time.txt")
        if ">" in command:  # the redirection applies to ident itself, not to /usr/bin/time
            shell = f"/usr/bin/time -v -o {timing} sh -c '{ident} {command}'"
        else:
            shell = f"/usr/bin/time -v -o {timing} {ident} {command} > /dev/null"
        r = subprocess.run(["bash", "-c", shell], capture_output=True, text=True, errors="replace")
        info = {}
        for line in open(timing):
            if ":" in line:
                k, v = line.rsplit(":", 1)
                info[k.strip()] = v.strip()
        cpu = float(info.get("User time (seconds)", "nan")) + float(info.get("System time (seconds)", "nan"))
        rss = float(info.get("Maximum resident set size (kbytes)", "nan")) / 1024
        code = r.returncode
        err = r.stderr.strip().splitlines()[0] if r.stderr.strip() else ""
        bad = (code == 0 and not may_succeed) or (code != 0 and (cpu > 2 or rss > 200))
        failures += bad
        print(f"| {name} | {code} | {cpu:.2f} | {rss:.0f} | {err[:110].replace('|', '/')}{' **FAIL**' if bad else ''} |")
    after = {p: digest(p) for p in watched}
    changed = [p for p in watched if before[p] != after[p]] + [p for p in watched if not os.path.lexists(p)]
    print(f"\nfiles given to the probes changed or removed: {len(changed)} {changed if changed else ''}")
    shutil.rmtree(tmp)
    return 1 if failures or changed else 0


if __name__ == "__main__":
    sys.exit(main())
