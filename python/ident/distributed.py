"""Fleets of records and large studies on Dask distributed.

    import ident.distributed as idd
    table = idd.fit_many(["a.csv", "b.csv", frame], dict(output="y", inputs=["u"], estimator="cauchy"))
    table = idd.study(dict(records=["dryer", "gas_furnace"], estimators=["rls", "cauchy"],
                           outliers=["0.05:20", "0.1:100"], seeds=range(50)))

``client=None`` starts a local cluster of one single-threaded worker process per core and closes it at the
end; any ``dask.distributed.Client`` (a laptop's LocalCluster, or ``dask scheduler`` / ``dask worker``
processes on many machines) works unchanged; ``client="serial"`` runs in this process without Dask.
Workers need ``ident`` importable (installed, or on a shared ``PYTHONPATH``) and, for records given as
paths, the files at the same paths.

Records travel in batches, several per task, so that the scheduler's cost per task (about a
millisecond) stays small beside the fits and a study of 10⁶ fits is ~10⁴ tasks, not 10⁶.
"""

import math
import os

import pandas as pd

from ident import workflow as _workflow

_FIT_COLUMNS = ["record", "theta", "theta_std", "fit_one_step", "status", "error"]


def _fit_row(name, data, spec):
    """One record's row; a failure is the row's status, never an exception."""
    try:
        result = _workflow.fit(data, **spec)
        return {"record": name, "theta": result.theta, "theta_std": result.theta_std,
                "fit_one_step": result.fit_one_step, "status": "ok", "error": ""}
    except Exception as error:  # noqa: BLE001 - one bad record never fails the run
        return {"record": name, "theta": None, "theta_std": None, "fit_one_step": math.nan, "status": "error",
                "error": f"{type(error).__name__}: {error}" if not isinstance(error, ValueError) else str(error)}


def _fit_batch(batch, spec):
    return [_fit_row(name, data, spec) for name, data in batch]


def _records(records, key):
    """(name, data) pairs in input order; a Dask DataFrame becomes one record per value of `key`."""
    if not isinstance(records, (list, tuple)):
        records = [records]
    out = []
    for i, record in enumerate(records):
        if hasattr(record, "npartitions") and hasattr(record, "compute"):  # a Dask DataFrame
            if key is None:
                raise ValueError("a Dask DataFrame record needs key= (the column that names each record)")
            groups = record.compute().groupby(key, sort=True)
            for value, frame in groups:
                out.append((f"{key}={value}", frame.drop(columns=[key]).reset_index(drop=True)))
        elif isinstance(record, tuple) and len(record) == 2 and isinstance(record[0], str):
            out.append(record)
        elif isinstance(record, (str, os.PathLike)):
            out.append((os.fspath(record), os.fspath(record)))
        else:
            out.append((getattr(record, "attrs", {}).get("name", f"record {i}"), record))
    return out


def _batches(items, workers, batch_size):
    if batch_size is None:  # about four tasks per worker, at most 10⁴ tasks in all
        batch_size = max(1, math.ceil(len(items) / max(1, 4 * workers)), math.ceil(len(items) / 10_000))
    return [items[i:i + batch_size] for i in range(0, len(items), batch_size)]


def local_cluster(n_workers=None):
    """The local cluster that ``client=None`` starts: one single-threaded worker process per core (a fit
    holds its core), no dashboard, and so no statistical profiler in the workers (it samples every
    worker thread's stack each 10 ms for a dashboard nobody can open, and takes that time from the fits).
    ``Client(local_cluster())`` gives the same cluster to keep across calls."""
    import dask
    from dask.distributed import LocalCluster
    with dask.config.set({"distributed.worker.profile.enabled": False}):
        return LocalCluster(n_workers=n_workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                            dashboard_address=None)


class _Cluster:
    """The given client, or a local cluster for the duration of a call."""

    def __init__(self, client):
        self.client, self.own = client, None

    def __enter__(self):
        if self.client is None:
            from dask.distributed import Client
            self.own = local_cluster()
            self.client = Client(self.own)
        return self.client

    def __exit__(self, *exc):
        if self.own is not None:
            self.client.close()
            self.own.close()


def _run(function, batches, extra, client, retries):
    if isinstance(client, str) and client == "serial":
        return [function(batch, extra) for batch in batches]
    with _Cluster(client) as c:
        # The batches travel inside the tasks (not scattered onto one worker): a task lost with its worker
        # is rerun elsewhere from what the scheduler holds, so nothing is lost.
        # One submission per batch: the first tasks start while later batches are still on their way.
        futures = [c.submit(function, batch, extra, retries=retries, pure=False) for batch in batches]
        return c.gather(futures)


def fit_many(records, spec, client=None, *, key=None, batch_size=None, retries=3):
    """Fits every record with ``ident.fit(record, **spec)``.

    ``records``: a list of CSV paths, pandas DataFrames (named by ``df.attrs["name"]`` or their index in
    the list), ``(name, data)`` pairs and Dask DataFrames (one record per value of the column ``key``),
    mixed as needed. Returns a pandas DataFrame with one row per record, in input order: ``record``,
    ``theta`` and ``theta_std`` (numpy arrays), ``fit_one_step``, ``status`` ("ok" or "error") and
    ``error`` (the message; empty when ok). ``retries``: how often a task lost with its worker is rerun.
    """
    spec = dict(spec)
    spec.setdefault("residual_lags", 0)  # the table has no residual analysis: do not compute one
    items = _records(records, key)
    if not items:
        return pd.DataFrame(columns=_FIT_COLUMNS)
    workers = _worker_count(client)
    rows = [row for batch in _run(_fit_batch, _batches(items, workers, batch_size), spec, client, retries)
            for row in batch]
    return pd.DataFrame(rows, columns=_FIT_COLUMNS)


def _worker_count(client):
    if client is None:
        return os.cpu_count() or 1
    if isinstance(client, str):
        return 1
    return max(1, len(client.scheduler_info().get("workers", {})))


def _study_batch(batch, options):
    rows = []
    for record_name, data, outliers, seed in batch:
        spec = f"{outliers}:{seed}"
        try:
            table = _workflow.compare(data, options["estimators"], outliers=spec, trials=1, **options["kwargs"])
            failures = {e["estimator"]: e["failure"] or "" for e in table.json["estimators"]}
            by_name = {r["estimator"]: r for _, r in table.iterrows()}
            for estimator in options["estimators"]:  # the grid's order, not the table's ranking
                r = by_name[estimator]
                ok = r["failed_trials"] == 0
                rows.append({"record": record_name, "outliers": outliers, "seed": seed, "estimator": estimator,
                             "kind": r["kind"], "fit_one_step": r["fit_one_step"],
                             "fit_simulation": r["fit_simulation"], "theta_distance": r["theta_distance"],
                             "status": "ok" if ok else "error", "error": "" if ok else failures[estimator]})
        except Exception as error:  # noqa: BLE001 - one bad cell never fails the study
            for estimator in options["estimators"]:
                rows.append({"record": record_name, "outliers": outliers, "seed": seed, "estimator": estimator,
                             "kind": "", "fit_one_step": math.nan, "fit_simulation": math.nan,
                             "theta_distance": math.nan, "status": "error", "error": str(error)})
    return rows


def study(grid, client=None, *, batch_size=None, retries=3):
    """A compare-style study: every record × outlier spec × seed, every estimator on the same corrupted data.

    ``grid``: ``records`` (bundled names, paths, DataFrames or (name, data) pairs), ``estimators``,
    ``outliers`` ("RATE:SIZE" strings), ``seeds`` (an int n for 1…n, or the seeds), and any further keyword
    arguments of ``ident.compare`` (structure, split, passes, …) applied to every cell. Returns one row
    per (record, outliers, seed, estimator), in grid order: ``fit_one_step``, ``fit_simulation``,
    ``theta_distance`` (to the record's clean least-squares θ), ``kind``, ``status``, ``error``. Each cell
    is seeded by its seed alone, so the table is the same serially and on any cluster.
    """
    grid = dict(grid)
    records = _records(grid.pop("records"), grid.pop("key", None))
    estimators = list(grid.pop("estimators", ("rls", "cauchy", "student:3")))
    outliers = grid.pop("outliers", ["0.05:20"])
    outliers = [outliers] if isinstance(outliers, str) else list(outliers)
    seeds = grid.pop("seeds", 10)
    seeds = list(range(1, seeds + 1)) if isinstance(seeds, int) else list(seeds)
    for spec in outliers:
        if spec.count(":") != 1:
            raise ValueError(f"outliers '{spec}': need RATE:SIZE (the seed comes from seeds)")
    cells = [(name, data, spec, seed) for name, data in records for spec in outliers for seed in seeds]
    options = {"estimators": estimators, "kwargs": grid}
    batches = _batches(cells, _worker_count(client), batch_size)
    rows = [row for batch in _run(_study_batch, batches, options, client, retries) for row in batch]
    return pd.DataFrame(rows)


def summarise(table, by=("record", "outliers", "estimator"), column="theta_distance"):
    """Median, 90th percentile and worst of a study's column over the seeds (the distributions robust
    estimation is judged by)."""
    ok = table[table["status"] == "ok"]
    grouped = ok.groupby(list(by), sort=False)[column]
    return pd.DataFrame({"median": grouped.median(), "p90": grouped.quantile(0.9), "worst": grouped.max(),
                         "seeds": grouped.size()}).reset_index()


__all__ = ["fit_many", "study", "summarise"]
