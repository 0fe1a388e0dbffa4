"""ident.distributed on loopback: a LocalCluster of 2 worker processes, a scheduler and two workers
started as separate processes with the `dask` commands, a worker killed mid-run, and malformed records."""

import json
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pandas as pd
import pytest

import ident
import ident.distributed as idd

distributed = pytest.importorskip("dask.distributed")

ARX = dict(output="y", inputs=["u"], na=2, nb=2, nk=1, split=1, detrend="none")


def plant(seed, rows=2000):
    rng = np.random.default_rng(seed)
    u = rng.normal(size=rows)
    y = np.zeros(rows)
    for t in range(2, rows):
        y[t] = 1.2 * y[t - 1] - 0.5 * y[t - 2] + 0.8 * u[t - 1] + 0.3 * u[t - 2] + 0.05 * rng.standard_cauchy()
    frame = pd.DataFrame({"u": u, "y": y})
    frame.attrs["name"] = f"plant {seed}"
    return frame


def assert_same_rows(a, b):
    assert list(a["record"]) == list(b["record"])
    assert list(a["status"]) == list(b["status"]) and list(a["error"]) == list(b["error"])
    for x, y in zip(a["theta"], b["theta"]):
        assert (x is None and y is None) or np.array_equal(x, y)


def test_local_cluster_of_two_processes_gives_the_serial_results(tmp_path):
    import dask.dataframe as dd
    frames = [plant(seed) for seed in range(6)]
    path = tmp_path / "plant_on_disk.csv"
    frames[0].to_csv(path, index=False)
    long = pd.concat([f.assign(unit=i) for i, f in enumerate(frames[:3])], ignore_index=True)
    records = [str(path), *frames[1:], ("malformed", {"y": [1.0, 2.0], "u": [0.0, 1.0]}),
               dd.from_pandas(long, npartitions=2)]
    spec = dict(ARX, estimator="cauchy")
    serial = idd.fit_many(records, spec, client="serial", key="unit")
    # The cluster client=None starts: one process per worker, and no statistical profiler in them.
    with idd.local_cluster(2) as cluster, distributed.Client(cluster) as client:
        profiling = client.run(lambda: __import__("dask").config.get("distributed.worker.profile.enabled"))
        parallel = idd.fit_many(records, spec, client=client, key="unit", batch_size=2)
    assert list(profiling.values()) == [False, False]
    assert_same_rows(serial, parallel)
    assert list(serial["record"])[-4:] == ["malformed", "unit=0", "unit=1", "unit=2"]
    bad = serial[serial["record"] == "malformed"].iloc[0]
    assert bad["status"] == "error" and "estimation part has 2 rows" in bad["error"]
    assert (serial["status"] == "ok").sum() == len(serial) - 1
    # The Dask groups are the same records as the frames they came from.
    np.testing.assert_array_equal(serial.iloc[-3]["theta"], serial.iloc[0]["theta"])
    truth = np.array([-1.2, 0.5, 0.8, 0.3])
    for theta in serial.loc[serial["status"] == "ok", "theta"]:
        assert np.linalg.norm(theta - truth) < 0.05


def test_a_study_is_the_same_serially_and_distributed():
    grid = dict(records=["dryer", "stackloss"], estimators=["rls", "cauchy"], outliers=["0.05:20", "0.1:100"],
                seeds=3)
    serial = idd.study(grid, client="serial")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        parallel = idd.study(grid, client=client, batch_size=1)
    pd.testing.assert_frame_equal(serial, parallel)
    assert len(serial) == 2 * 2 * 3 * 2
    # Each cell is `ident compare` with that seed.
    one = ident.compare("stackloss", ["rls", "cauchy"], outliers="0.1:100:2")
    row = serial[(serial.record == "stackloss") & (serial.outliers == "0.1:100") & (serial.seed == 2)
                 & (serial.estimator == "cauchy")].iloc[0]
    assert row["theta_distance"] == one.set_index("estimator").loc["cauchy", "theta_distance"]
    summary = idd.summarise(serial)
    cauchy = summary[(summary.estimator == "cauchy") & (summary.record == "dryer")]
    rls = summary[(summary.estimator == "rls") & (summary.record == "dryer")]
    assert (cauchy["worst"].to_numpy() < rls["median"].to_numpy()).all()


@pytest.fixture(scope="module")
def external_cluster(tmp_path_factory):
    """`dask scheduler` and two `dask worker` processes (no nanny: a killed worker stays dead)."""
    folder = tmp_path_factory.mktemp("cluster")
    scheduler_file = str(folder / "scheduler.json")
    common = dict(stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=dict(os.environ))
    scheduler = subprocess.Popen(["dask", "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                  "--scheduler-file", scheduler_file], **common)
    workers = []
    try:
        for _ in range(60):
            if os.path.exists(scheduler_file):
                break
            time.sleep(0.25)
        for _ in range(2):
            workers.append(subprocess.Popen(["dask", "worker", "--scheduler-file", scheduler_file, "--host",
                                             "127.0.0.1", "--nthreads", "1", "--no-nanny", "--no-dashboard"],
                                            **common))
        client = distributed.Client(scheduler_file=scheduler_file, timeout=30)
        client.wait_for_workers(2, timeout=60)
        yield client, workers
        client.close()
    finally:
        for p in [*workers, scheduler]:
            p.kill()
            p.wait()


def test_separate_scheduler_and_worker_processes(external_cluster):
    client, _ = external_cluster
    addresses = list(client.scheduler_info()["workers"])
    assert len(addresses) == 2 and all(a.startswith("tcp://127.0.0.1:") for a in addresses)
    records = [plant(seed) for seed in range(8)]
    spec = dict(ARX, estimator="rls")
    assert_same_rows(idd.fit_many(records, spec, client="serial"), idd.fit_many(records, spec, client=client))


def test_a_worker_killed_mid_run_loses_nothing(external_cluster):
    client, workers = external_cluster
    records = [plant(seed, rows=50_000) for seed in range(12)]  # several seconds of fitting per worker
    spec = dict(ARX, estimator="cauchy")
    victim = next(a for a, pid in client.run(os.getpid).items() if pid == workers[1].pid)
    result = {}
    run = threading.Thread(target=lambda: result.update(table=idd.fit_many(records, spec, client=client,
                                                                           batch_size=1)))
    run.start()
    deadline = time.time() + 60
    while not client.processing().get(victim) and time.time() < deadline:
        time.sleep(0.01)
    time.sleep(0.1)
    assert client.processing().get(victim) and run.is_alive()  # mid-run: it holds tasks
    workers[1].send_signal(signal.SIGKILL)
    run.join(timeout=300)
    assert not run.is_alive()
    table = result["table"]
    assert list(table["record"]) == [f"plant {s}" for s in range(12)]  # every record once, in order
    assert (table["status"] == "ok").all()
    assert_same_rows(idd.fit_many(records, spec, client="serial"), table)


def test_the_fleet_example_runs(tmp_path, source_dir):
    script = os.path.join(source_dir, "examples", "fleet", "fleet.py")
    done = subprocess.run([sys.executable, script, "--plants", "40", "--rows", "1000", "--output", str(tmp_path)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    medians = {line.split()[0]: float(line.split("median")[1].split(",")[0]) for line in done.stdout.splitlines()
               if "plants fitted" in line}
    assert "40 of 40 plants fitted" in done.stdout
    assert medians["cauchy"] < 0.5 * medians["rls"]  # the glitches cost least squares, not the robust fit
    assert (tmp_path / "fleet_errors.png").stat().st_size > 10_000
