#!/usr/bin/python3
"""The Python package's overhead and its speed against statsmodels, measured in one run.

1. update_many per-update cost against the C++ estimator (Google Benchmark BM_LdRls of kh_benchmark,
   RLS with forgetting 0.99) at rho = 4 and 16: 10^6 updates timed in Python, the best of 5 runs.
2. ident.fit (rls, static regression, split 1, no residual analysis: the work RecursiveLS does) on a
   10^6-row DataFrame, the best of 5 runs, against one run of statsmodels RecursiveLS on the same
   regression; the parameters must agree to 1e-8 (relative).

    PYTHONPATH=build/python /usr/bin/python3 bench/python_bindings.py [--rows N] [--json OUT]

Needs a Release build in build/ (build/python; it builds build/bench/kh_benchmark) and python3-statsmodels.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "build", "python"))
import ident  # noqa: E402


def cpp_ns_per_update(rhos):
    """Median CPU ns per update of BM_LdRls/rho over 5 repetitions."""
    with tempfile.NamedTemporaryFile(suffix=".json") as out:
        filt = "BM_LdRls/(" + "|".join(str(r) for r in rhos) + ")$"
        subprocess.run(["cmake", "--build", os.path.join(ROOT, "build"), "--target", "kh_benchmark"], check=True,
                       stdout=subprocess.DEVNULL)  # not in the default build (bench/CMakeLists.txt)
        subprocess.run([os.path.join(ROOT, "build", "bench", "kh_benchmark"), f"--benchmark_filter={filt}",
                        "--benchmark_repetitions=5", "--benchmark_min_time=0.2", f"--benchmark_out={out.name}",
                        "--benchmark_out_format=json"], check=True, stdout=subprocess.DEVNULL)
        with open(out.name, encoding="utf-8") as f:
            results = json.load(f)["benchmarks"]
    return {int(b["run_name"].split("/")[1]): b["cpu_time"] for b in results
            if b.get("aggregate_name") == "median"}


def python_ns_per_update(rho, updates=1_000_000, runs=5):
    rng = np.random.default_rng(rho)
    Z = rng.normal(size=(updates, rho))
    Y = Z @ np.linspace(-1, 1, rho) + 0.1 * rng.standard_cauchy(updates)
    best = float("inf")
    for _ in range(runs):
        est = ident.RLS(rho, forgetting=0.99)
        start = time.process_time()
        est.update_many(Y, Z)
        best = min(best, time.process_time() - start)
    return 1e9 * best / updates


def fit_against_statsmodels(rows):
    import pandas as pd
    from statsmodels.regression.recursive_ls import RecursiveLS
    rng = np.random.default_rng(11)
    X = rng.normal(size=(rows, 3))
    y = 1.0 + X @ [2.0, -1.0, 0.5] + rng.normal(size=rows)
    frame = pd.DataFrame({"x1": X[:, 0], "x2": X[:, 1], "x3": X[:, 2], "y": y})
    ident_seconds = float("inf")
    for _ in range(5):  # the best of 5, as timeit reports
        start = time.perf_counter()
        result = ident.fit(frame, output="y", regressors=["x1", "x2", "x3"], intercept=True, split=1,
                           residual_lags=0)
        ident_seconds = min(ident_seconds, time.perf_counter() - start)
    with_residuals = float("inf")
    for _ in range(5):  # the default fit, with the residual analysis of `ident fit` (20 lags)
        start = time.perf_counter()
        ident.fit(frame, output="y", regressors=["x1", "x2", "x3"], intercept=True, split=1)
        with_residuals = min(with_residuals, time.perf_counter() - start)
    start = time.perf_counter()
    sm = RecursiveLS(y, np.column_stack([np.ones(rows), X])).fit()
    statsmodels_seconds = time.perf_counter() - start
    theta_sm = np.asarray(sm.params)
    agreement = float(np.max(np.abs(result.theta - theta_sm) / np.abs(theta_sm)))
    return {"rows": rows, "ident_fit_seconds": round(ident_seconds, 4),
            "statsmodels_recursive_ls_seconds": round(statsmodels_seconds, 3),
            "speed_ratio": round(statsmodels_seconds / ident_seconds, 1),
            "ident_fit_with_residual_analysis_seconds": round(with_residuals, 4),
            "speed_ratio_with_residual_analysis": round(statsmodels_seconds / with_residuals, 1),
            "max_relative_theta_difference": agreement}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rows", type=int, default=1_000_000, help="rows of the DataFrame for the fit comparison")
    p.add_argument("--json", help="write the figures to this file")
    args = p.parse_args()
    rhos = [4, 16]
    cpp = cpp_ns_per_update(rhos)
    overhead = {}
    for rho in rhos:
        py = python_ns_per_update(rho)
        overhead[str(rho)] = {"python_update_many_ns": round(py, 1), "cpp_ns": round(cpp[rho], 1),
                              "ratio": round(py / cpp[rho], 3)}
        print(f"rho = {rho:2d}: update_many {py:7.1f} ns/update, C++ {cpp[rho]:7.1f} ns/update, "
              f"ratio {py / cpp[rho]:.3f}")
    fit = fit_against_statsmodels(args.rows)
    print(f"fit of {fit['rows']} rows: ident.fit {fit['ident_fit_seconds']} s "
          f"({fit['ident_fit_with_residual_analysis_seconds']} s with the residual analysis), statsmodels RecursiveLS "
          f"{fit['statsmodels_recursive_ls_seconds']} s, ratio {fit['speed_ratio']}, theta agree to "
          f"{fit['max_relative_theta_difference']:.1e}")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump({"update_many_vs_cpp": overhead, "fit_vs_statsmodels": fit}, f, indent=1)


if __name__ == "__main__":
    main()
