#!/usr/bin/python3
"""Throughput of ident.distributed on a local cluster, and the threads of `ident compare --jobs`.

1. A fleet of 400 simulated records of 10^4 rows (ARX(2,2,1), Cauchy noise), fitted with cauchy, given
   as CSV paths and as DataFrames: serially in this process, then on ident.distributed.local_cluster(2),
   the cluster client=None starts, of 2 single-threaded worker processes (started and warmed before the
   clock). Speed-up = serial time / cluster time; overhead
   per record = (cluster time x workers - serial time) / records, split into the scheduler's share (wall
   time outside the span of the tasks, from Dask's task stream) and the workers' compute against the same
   fits run alone in this process.
2. `ident compare RECORD --trials 200` with --jobs 1 and --jobs 2: wall time of each, and whether the
   tables agree (every column but the ns/update timing, which differs between any two runs).

    PYTHONPATH=build/python /usr/bin/python3 bench/dask_fleet.py [--records 400] [--rows 10000] [--json OUT]
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np
import pandas as pd

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "build", "python"))
import ident.distributed as idd  # noqa: E402


def record(seed, rows):
    rng = np.random.default_rng(seed)
    u = rng.normal(size=rows)
    e = 0.05 * rng.standard_cauchy(size=rows)
    y = np.zeros(rows)
    for t in range(2, rows):
        y[t] = 1.2 * y[t - 1] - 0.5 * y[t - 2] + 0.8 * u[t - 1] + 0.3 * u[t - 2] + e[t]
    return pd.DataFrame({"u": u, "y": y})


def fleet(records, rows, workers, folder):
    """The fleet as CSV files (what a nightly refit reads), and as DataFrames sent from this process."""
    from dask.distributed import Client, get_task_stream
    frames = [record(seed, rows) for seed in range(records)]
    paths = []
    for i, frame in enumerate(frames):
        paths.append(os.path.join(folder, f"record{i}.csv"))
        frame.to_csv(paths[-1], index=False)
    spec = dict(output="y", inputs=["u"], na=2, nb=2, nk=1, split=1, detrend="none", estimator="cauchy")
    out = {"records": records, "rows": rows, "workers": workers}
    with idd.local_cluster(workers) as cluster, Client(cluster) as client:
        idd.fit_many(frames[:workers * 2], spec, client=client)  # warm the workers (imports)
        for name, fleet_records in (("paths", paths), ("dataframes", frames)):
            start = time.perf_counter()
            serial = idd.fit_many(fleet_records, spec, client="serial")
            serial_seconds = time.perf_counter() - start
            with get_task_stream(client) as stream:
                start = time.perf_counter()
                parallel = idd.fit_many(fleet_records, spec, client=client)
                cluster_seconds = time.perf_counter() - start
            phases = [phase for task in stream.data for phase in task["startstops"]]
            span = max(p["stop"] for p in phases) - min(p["start"] for p in phases)
            compute = sum(p["stop"] - p["start"] for p in phases if p["action"] == "compute")
            same = all(np.array_equal(a, b) for a, b in zip(serial["theta"], parallel["theta"]))
            per_record = serial_seconds / records
            overhead = max(0.0, cluster_seconds * workers - serial_seconds) / records
            out[name] = {"serial_seconds": round(serial_seconds, 3), "cluster_seconds": round(cluster_seconds, 3),
                         "speedup": round(serial_seconds / cluster_seconds, 3),
                         "fit_ms_per_record": round(1e3 * per_record, 3),
                         "overhead_ms_per_record": round(1e3 * overhead, 3),
                         "overhead_share_of_fit": round(overhead / per_record, 4),
                         # The scheduler's own share: wall time outside the span of the tasks on the workers.
                         "scheduling_ms_per_record": round(1e3 * (cluster_seconds - span) / records, 3),
                         "scheduling_share_of_fit": round((cluster_seconds - span) / records / per_record, 4),
                         # The fits' CPU on the workers against the same fits in this process alone.
                         "worker_compute_over_serial": round(compute / serial_seconds, 3),
                         "same_results": bool(same)}
    return out


def compare_jobs(dataset, trials):
    program = os.path.join(ROOT, "build", "bin", "ident")
    out = {}
    tables = {}
    for jobs in (1, 2):
        cmd = [program, "compare", dataset, "--trials", str(trials), "--jobs", str(jobs)]
        start = time.perf_counter()
        text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        out[f"jobs_{jobs}_seconds"] = round(time.perf_counter() - start, 3)
        tables[jobs] = re.sub(r" +\d+$", "", text, flags=re.M)  # the ns/update column
    out.update(record=dataset, trials=trials, speedup=round(out["jobs_1_seconds"] / out["jobs_2_seconds"], 3),
               identical_tables=tables[1] == tables[2])
    return out


def main():  # noqa: D103 - a LocalCluster starts processes: keep the work under __main__
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--records", type=int, default=400)
    p.add_argument("--rows", type=int, default=10_000)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--compare-record", default="silverbox_snls80mv")
    p.add_argument("--trials", type=int, default=200)
    p.add_argument("--json", help="write the figures to this file")
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        fleet_figures = fleet(args.records, args.rows, args.workers, folder)
    figures = {"fleet": fleet_figures,
               "compare_jobs": compare_jobs(args.compare_record, args.trials)}
    print(json.dumps(figures, indent=1))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(figures, f, indent=1)


if __name__ == "__main__":
    main()
