#!/usr/bin/python3
"""Coverage of the reported standard errors through the command line, end-of-data steps included.

For y = 1 + 2x₁ − x₂ + e, x ~ N(0, I), it writes each replication as CSV, runs
`ident fit FILE --output y --regressors x1,x2 --intercept --split 1 --estimator E --json` and counts how
often θ̂ ± 1.96·theta_std covers the truth (3 intervals a replication): cauchy under Cauchy noise,
student:3 under t₃ noise, and both under Gaussian noise, at n = 100 and 1000. It also counts the
replications whose estimate the end-of-data competition replaced ("end_of_data" restart events).
numpy default_rng(1000 + r) draws replication r.

Run from the repository root after .ci/setup:
    bench/coverage_study.py [--ident build/bin/ident] [--replications 200]
"""
import argparse
import json
import os
import subprocess
import tempfile

import numpy as np

CASES = [("cauchy", "cauchy"), ("student:3", "t3"), ("cauchy", "gaussian"), ("student:3", "gaussian")]
TRUTH = np.array([1.0, 2.0, -1.0])


def replication(rng, noise, n):
    x = rng.standard_normal((n, 2))
    e = {"cauchy": lambda: rng.standard_cauchy(n), "gaussian": lambda: rng.standard_normal(n),
         "t3": lambda: rng.standard_t(3, n)}[noise]()
    return x, TRUTH[0] + x @ TRUTH[1:] + e


def coverage(ident, estimator, noise, n, replications, path):
    covered = adopted = 0
    for r in range(replications):
        x, y = replication(np.random.default_rng(1000 + r), noise, n)
        np.savetxt(path, np.column_stack([np.arange(n), x, y]), delimiter=",", header="k,x1,x2,y",
                   comments="", fmt="%.17g")
        result = subprocess.run([ident, "fit", path, "--output", "y", "--regressors", "x1,x2", "--intercept",
                                 "--split", "1", "--estimator", estimator, "--json"],
                                capture_output=True, text=True, check=True)
        j = json.loads(result.stdout)
        covered += int(np.sum(np.abs(np.array(j["theta"]) - TRUTH) <= 1.96 * np.array(j["theta_std"])))
        adopted += any(e.get("end_of_data") for e in j.get("lock_in", {}).get("events", []))
    return covered / (3 * replications), adopted


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ident", default="build/bin/ident")
    p.add_argument("--replications", type=int, default=200)
    args = p.parse_args()
    print("| estimator | noise | n | coverage | end-of-data replacements |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "replication.csv")
        for estimator, noise in CASES:
            for n in (100, 1000):
                c, a = coverage(args.ident, estimator, noise, n, args.replications, path)
                print(f"| {estimator} | {noise} | {n} | {c:.3f} | {a}/{args.replications} |", flush=True)


if __name__ == "__main__":
    main()
