#!/usr/bin/python3
"""Static records: where each estimator lands against the batch Cauchy maximum-likelihood estimate.

For stackloss, telef and stars_cyg (bundled, rows in file order) it runs
`ident fit RECORD ... --intercept --split 1 --estimator E --json` for least squares (rls), huber, cauchy,
cauchy with --passes 3 and student:3, and reports each θ with its distance to the `cauchy-ml` estimate
relative to least squares' distance, in prediction space ‖Z(θ − θ_ML)‖ (independent of the regressors'
units) and in raw coefficients ‖θ − θ_ML‖. 1 = as far as least squares; below 1 = closer.

Run from the repository root after .ci/setup:
    bench/static_records.py [--ident build/bin/ident]
"""
import argparse
import json
import subprocess

import numpy as np

RECORDS = {
    "stackloss": ("stack_loss", ["air_flow", "water_temp", "acid_conc"]),
    "telef": ("calls", ["year"]),
    "stars_cyg": ("log_light", ["log_Te"]),
}
ESTIMATORS = [("OLS", "rls", []), ("huber", "huber", []), ("cauchy", "cauchy", []),
              ("cauchy --passes 3", "cauchy", ["--passes", "3"]), ("student:3", "student:3", [])]


def fit(ident, record, output, regressors, estimator, extra):
    command = [ident, "fit", record, "--output", output, "--regressors", ",".join(regressors), "--intercept",
               "--split", "1", "--estimator", estimator, "--json"] + extra
    result = subprocess.run(command, capture_output=True, text=True, check=True)
    return np.array(json.loads(result.stdout)["theta"])


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ident", default="build/bin/ident")
    args = p.parse_args()
    print("| record | estimator | θ (intercept first) | prediction space | coefficients |")
    print("|---|---|---|---|---|")
    for record, (output, regressors) in RECORDS.items():
        data = np.genfromtxt(f"datasets/{record}.csv", delimiter=",", names=True)
        Z = np.column_stack([np.ones(len(data))] + [data[r] for r in regressors])
        ml = fit(args.ident, record, output, regressors, "cauchy-ml", [])
        ols = fit(args.ident, record, output, regressors, "rls", [])
        ols_prediction, ols_raw = np.linalg.norm(Z @ (ols - ml)), np.linalg.norm(ols - ml)
        for label, estimator, extra in ESTIMATORS:
            theta = fit(args.ident, record, output, regressors, estimator, extra)
            print(f"| {record} | {label} | {', '.join(f'{v:.5g}' for v in theta)} | "
                  f"{np.linalg.norm(Z @ (theta - ml)) / ols_prediction:.3f} | "
                  f"{np.linalg.norm(theta - ml) / ols_raw:.3f} |")


if __name__ == "__main__":
    main()
