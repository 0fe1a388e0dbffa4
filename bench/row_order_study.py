#!/usr/bin/python3
"""Row-order study: how far the order of a static record's rows moves a recursive estimate.

For each record, the rows are permuted 20 times (numpy default_rng(0)) and fitted with
`ident fit FILE ... --intercept --split 1 --estimator E --json`; the report gives, per coefficient, the
standard deviation of the estimate over the permutations divided by the median reported `theta_std`,
and its maximum (at most 1: the order moves the estimate by less than its own standard error).
Records: stackloss, telef, stars_cyg (bundled) and 2000 simulated rows y = 1 + 2x₁ − x₂ + e, e ~ t₂.

Run from the repository root after .ci/setup:
    bench/row_order_study.py [--ident build/bin/ident] [--estimator cauchy] [--extra '--passes 3']
"""
import argparse
import json
import os
import subprocess
import tempfile

import numpy as np

RECORDS = {
    "stackloss": ("datasets/stackloss.csv", "--output stack_loss --regressors air_flow,water_temp,acid_conc"),
    "telef": ("datasets/telef.csv", "--output calls --regressors year"),
    "stars_cyg": ("datasets/stars_cyg.csv", "--output log_light --regressors log_Te"),
}


def fit(ident, path, model, estimator, extra):
    command = f"{ident} fit {path} {model} --intercept --split 1 --estimator {estimator} --json {extra}"
    result = subprocess.run(command, shell=True, capture_output=True, text=True, check=True)
    return json.loads(result.stdout)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ident", default="build/bin/ident")
    p.add_argument("--estimator", default="cauchy")
    p.add_argument("--extra", default="", help="more options for ident fit, e.g. '--passes 3'")
    p.add_argument("--permutations", type=int, default=20)
    args = p.parse_args()
    rng = np.random.default_rng(0)
    with tempfile.TemporaryDirectory() as tmp:
        records = dict(RECORDS)
        x = rng.standard_normal((2000, 2))
        y = 1 + 2 * x[:, 0] - x[:, 1] + rng.standard_t(2, 2000)
        simulated = os.path.join(tmp, "simulated_t2.csv")
        np.savetxt(simulated, np.c_[x, y], delimiter=",", header="x1,x2,y", comments="", fmt="%.12g")
        records["simulated_t2_2000"] = (simulated, "--output y --regressors x1,x2")
        print("| record | spread / reported std, per coefficient | max |")
        print("|---|---|---|")
        for name, (path, model) in records.items():
            with open(path) as f:
                header, *rows = f.read().splitlines()
            thetas, stds = [], []
            for k in range(args.permutations):
                permuted = os.path.join(tmp, f"{name}_{k}.csv")
                with open(permuted, "w") as f:
                    f.write(header + "\n" + "\n".join(rows[i] for i in rng.permutation(len(rows))) + "\n")
                j = fit(args.ident, permuted, model, args.estimator, args.extra)
                thetas.append(j["theta"])
                stds.append(j["theta_std"])
            ratio = np.std(thetas, axis=0, ddof=1) / np.median(stds, axis=0)
            print(f"| {name} | {', '.join(f'{r:.3f}' for r in ratio)} | {ratio.max():.3f} |")


if __name__ == "__main__":
    main()
