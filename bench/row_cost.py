#!/usr/bin/python3
"""Instructions that `ident fit` executes per row, counted by callgrind: a figure that does not move with the
machine's load (runs differ by well under 0.1 %: the threads' waits for one another), for comparing two builds of
the per-row path where wall times are too noisy to tell a few per cent.
The record is `bench/read_speed.py`'s simulated ARX(2,2,1) record cut to --rows rows (1.5·10^6 by default: past
the CLI's 10^6-row limit for reading a record whole, so the fit streams), fitted by
`ident fit FILE --output y --input u --na 2 --nb 2 --nk 1 --estimator rls`. Printed: each binary's instructions
(all threads: parsing included) and instructions per row, the busiest functions, and with --vs the ratio.

    /usr/bin/python3 bench/row_cost.py [--ident PATH] [--vs OTHER_PATH] [--rows 1500000] [--dir /tmp] [--top 12]

Needs valgrind (Debian: valgrind) and numpy/scipy; a run takes about a minute per 10^6 rows.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from read_speed import IDENT, MODEL, write_record  # noqa: E402


def count(ident, path, top):
    """Total instructions of one fit and its `top` busiest functions (self cost), from callgrind."""
    with tempfile.NamedTemporaryFile(suffix=".callgrind") as out:
        run = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out.name}", ident, "fit", path] +
                             MODEL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, check=True)
        total = int(re.search(r"Collected : (\d+)", run.stderr).group(1))
        report = subprocess.run(["callgrind_annotate", out.name], capture_output=True, text=True, check=True).stdout
    functions = []
    for line in report.splitlines():
        m = re.match(r"\s*([\d,]+) \([\s\d.]+%\)\s+\S*?:(.+?)(?: \[.*\])?$", line)
        if m and "PROGRAM TOTALS" not in line:
            functions.append((int(m.group(1).replace(",", "")), m.group(2)))
    return total, functions[:top]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--ident", default=IDENT)
    parser.add_argument("--vs", help="a second ident binary, counted on the same record")
    parser.add_argument("--rows", type=int, default=1_500_000)
    parser.add_argument("--dir", default=tempfile.gettempdir())
    parser.add_argument("--top", type=int, default=12)
    args = parser.parse_args()
    path = os.path.join(args.dir, f"ident_row_cost_{args.rows}.csv")
    if not os.path.exists(path):
        write_record(path, args.rows)
    totals = []
    for ident in [args.ident] + ([args.vs] if args.vs else []):
        total, functions = count(ident, path, args.top)
        totals.append(total)
        print(f"{ident}: {total:,} instructions, {total / args.rows:.0f} per row")
        for cost, name in functions:
            print(f"  {cost / args.rows:8.1f}  {name[:110]}")
    if args.vs:
        print(f"ratio {args.ident} / {args.vs}: {totals[0] / totals[1]:.4f}")


if __name__ == "__main__":
    main()
