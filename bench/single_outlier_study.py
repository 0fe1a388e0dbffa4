#!/usr/bin/python3
"""One outlier in a short record: gas_furnace, ARX(2,2,3), rows 1-148 estimate, 149-296 validate,
`--detrend none`; one ±20σ outlier (σ = the clean least-squares residual std) at every estimation row.

For every position and sign it reports the Cauchy estimate's θ distance ‖θ̂ − θ_LS‖/‖θ_LS‖ to the clean
least-squares θ and its one-step validation fit against least squares on the same corrupted data.

Run from the repository root after .ci/setup:
    bench/single_outlier_study.py [--ident build/bin/ident] [--extra '--passes 3']
"""
import argparse
import json
import os
import subprocess
import tempfile

import numpy as np

MODEL = ["--output", "y", "--input", "u", "--na", "2", "--nb", "2", "--nk", "3", "--detrend", "none", "--json"]


def fit(ident, path, estimator, extra):
    result = subprocess.run([ident, "fit", path, "--estimator", estimator] + MODEL + extra,
                            capture_output=True, text=True, check=True)
    return json.loads(result.stdout)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ident", default="build/bin/ident")
    p.add_argument("--extra", default="", help="more options for the Cauchy fit, e.g. '--passes 3'")
    args = p.parse_args()
    data = np.genfromtxt("datasets/gas_furnace.csv", delimiter=",", names=True)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "gas_furnace.csv")

        def write(y):
            np.savetxt(path, np.c_[data["t"], data["u"], y], delimiter=",", header="t,u,y", comments="",
                       fmt="%.17g")

        write(data["y"])
        clean = fit(args.ident, path, "rls", [])
        theta_ls, sigma = np.array(clean["theta"]), clean["noise_std"]
        worst, misses = 0.0, []
        for row in range(148):
            for sign in (1, -1):
                y = data["y"].copy()
                y[row] += sign * 20 * sigma
                write(y)
                cauchy = fit(args.ident, path, "cauchy", args.extra.split())
                ols = fit(args.ident, path, "rls", [])
                distance = np.linalg.norm(np.array(cauchy["theta"]) - theta_ls) / np.linalg.norm(theta_ls)
                worst = max(worst, distance)
                fits = cauchy["fit_percent"]["one_step"], ols["fit_percent"]["one_step"]
                if distance > 0.3 or fits[0] < fits[1]:
                    misses.append(f"row {row} {'+' if sign > 0 else '-'}: distance {distance:.3f}, "
                                  f"fit {fits[0]:.2f} % vs least squares {fits[1]:.2f} %")
        print(f"σ = {sigma:.4g}; worst θ distance over 296 cases: {worst:.3f}")
        print(f"cases with distance > 0.3 or a fit below least squares: {len(misses)}")
        for m in misses:
            print("  " + m)


if __name__ == "__main__":
    main()
