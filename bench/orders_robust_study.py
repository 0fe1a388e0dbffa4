#!/usr/bin/python3
"""Order selection under gross outliers: which ARX structure `ident orders --criterion bic` picks, with least
squares and with the Cauchy likelihood, counted over simulated records.

Each record: y(t) = 1.5 y(t−1) − 0.7 y(t−2) + u(t−1) + 0.5 u(t−2) + e(t), e ~ N(0, 0.1²), u ~ N(0, 1), ROWS rows
from rest; each sample is an outlier with probability 5 %, ±50·0.1 (random sign) added to the measured y
(additive) or to e(t) (innovation). numpy default_rng(seed) draws u, e, the outlier rows and signs. Each record
is ranked by `ident orders FILE --output y --input u --na 1:3 --nb 1:3 --nk 0:2 --split 1 --criterion bic
--json [--estimator cauchy]`; the script prints, per kind and estimator, how often each best structure
(na, nb, nk) came out.

Usage: orders_robust_study.py IDENT_BINARY [--seeds 30] [--rows 400]
"""
import argparse
import collections
import json
import os
import subprocess
import tempfile

import numpy as np


def record(kind, seed, rows):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(rows)
    e = 0.1 * rng.standard_normal(rows)
    outlier = rng.random(rows) < 0.05
    shift = outlier * rng.choice([-1.0, 1.0], rows) * 50 * 0.1
    if kind == "innovation":
        e = e + shift
    y = np.zeros(rows)
    for t in range(rows):
        y[t] = e[t]
        if t >= 1:
            y[t] += 1.5 * y[t - 1] + u[t - 1]
        if t >= 2:
            y[t] += -0.7 * y[t - 2] + 0.5 * u[t - 2]
    return (y + shift if kind == "additive" else y), u


def best(ident, path, estimator):
    args = [ident, "orders", path, "--output", "y", "--input", "u", "--na", "1:3", "--nb", "1:3", "--nk", "0:2",
            "--split", "1", "--criterion", "bic", "--json"] + (["--estimator", estimator] if estimator else [])
    b = json.loads(subprocess.run(args, capture_output=True, text=True, check=True).stdout)["best"]
    return b["na"], b["nb"], b["nk"]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("ident")
    parser.add_argument("--seeds", type=int, default=30)
    parser.add_argument("--rows", type=int, default=400)
    a = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "record.csv")
        for kind in ("additive", "innovation"):
            counts = {"rls": collections.Counter(), "cauchy": collections.Counter()}
            for seed in range(a.seeds):
                y, u = record(kind, seed, a.rows)
                np.savetxt(path, np.column_stack([y, u]), delimiter=",", header="y,u", comments="", fmt="%.17g")
                counts["rls"][best(a.ident, path, None)] += 1
                counts["cauchy"][best(a.ident, path, "cauchy")] += 1
            for name, c in counts.items():
                picks = ", ".join(f"ARX{s}: {n}" for s, n in c.most_common())
                print(f"{kind:10s} {name:6s} {a.seeds} records: {picks}")


if __name__ == "__main__":
    main()
