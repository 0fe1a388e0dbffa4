#!/usr/bin/python3
"""`ident orders` over 600 structures (na, nb 1..10, nk 0..5) against one ARX(10,10,0) `ident fit` on the
same simulated 10^5-row record: wall time of each command, the best of 5 runs.

    /usr/bin/python3 bench/orders_speed.py [--rows 100000] [--json OUT]

Needs a Release build in build/ (build/bin/ident).
"""
import argparse
import json
import os
import subprocess
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
IDENT = os.path.join(ROOT, "build", "bin", "ident")


def best_of(cmd, runs=5):
    best = float("inf")
    for _ in range(runs):
        start = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        best = min(best, time.perf_counter() - start)
    return best


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rows", type=int, default=100_000)
    p.add_argument("--json", help="write the figures to this file")
    args = p.parse_args()
    rng = np.random.default_rng(3)
    u = rng.normal(size=args.rows)
    e = 0.1 * rng.normal(size=args.rows)
    y = np.zeros(args.rows)
    for t in range(2, args.rows):
        y[t] = 1.2 * y[t - 1] - 0.5 * y[t - 2] + 0.8 * u[t - 1] + 0.3 * u[t - 2] + e[t]
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "record.csv")
        np.savetxt(path, np.column_stack([u, y]), delimiter=",", header="u,y", comments="", fmt="%.17g")
        orders = [IDENT, "orders", path, "--output", "y", "--input", "u", "--na", "1:10", "--nb", "1:10", "--nk", "0:5"]
        fit = [IDENT, "fit", path, "--output", "y", "--input", "u", "--na", "10", "--nb", "10", "--nk", "0"]
        figures = {"rows": args.rows, "structures": 600, "orders_seconds": round(best_of(orders), 4),
                   "fit_seconds": round(best_of(fit), 4)}
        best = json.loads(subprocess.run(orders + ["--json"], check=True, capture_output=True, text=True).stdout)["best"]
    figures["ratio"] = round(figures["orders_seconds"] / figures["fit_seconds"], 3)
    figures["best"] = {k: best[k] for k in ("na", "nb", "nk")}
    print(json.dumps(figures, indent=1))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(figures, f, indent=1)


if __name__ == "__main__":
    main()
