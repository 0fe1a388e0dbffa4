"""Fitting and comparing estimators on a recorded table: the `ident fit` and `ident compare` workflows.

``fit`` returns a FitResult whose ``to_dict()`` has exactly the keys of ``ident fit --json``; ``compare``
returns a CompareResult, a pandas DataFrame with one row per estimator (its ``json`` attribute holds the
object of ``ident compare --json``). Both take the data as a pandas DataFrame, a dict of equal-length
arrays, a CSV path, or the name of a bundled record.
"""

import json
import os

import numpy as np
import pandas as pd

from ident import _ident
from ident import datasets as _datasets

_STRUCTURE_KEYS = ("output", "inputs", "na", "nb", "nk", "regressors", "intercept", "nc", "nd", "nf")
_POLYNOMIAL_KEYS = ("nc", "nd", "nf")  # ARMAX/OE/Box-Jenkins orders: added to a suggested structure too


def _table(data, missing=False):
    """(column names, float matrix rows x columns, name for messages, bundled-record name or None)."""
    if isinstance(data, (str, os.PathLike)):
        text = os.fspath(data)
        if not os.path.exists(text) and os.sep not in text and "." not in text:
            if text not in _datasets.names():
                raise ValueError(f"no file or bundled dataset '{text}' (ident.datasets.names() lists the bundled ones)")
            columns, values = _ident.read_csv(_datasets.path(text), missing)
            return list(columns), values, _datasets.path(text), text
        columns, values = _ident.read_csv(text, missing)
        return list(columns), values, text, None
    if hasattr(data, "columns") and hasattr(data, "to_numpy"):  # pandas DataFrame
        columns = [str(c) for c in data.columns]
        values = data.to_numpy(dtype=float)
        name = "DataFrame"
    elif isinstance(data, dict):
        columns = [str(c) for c in data]
        arrays = [np.asarray(data[c], dtype=float).ravel() for c in data]
        if arrays and any(a.size != arrays[0].size for a in arrays):
            raise ValueError("the arrays of the dict have different lengths: "
                             + ", ".join(f"{c} {a.size}" for c, a in zip(columns, arrays)))
        values = np.column_stack(arrays) if arrays else np.zeros((0, 0))
        name = "dict"
    else:
        raise TypeError("data must be a pandas DataFrame, a dict of arrays, a CSV path or a bundled record's name")
    if not missing and not np.isfinite(values).all():
        bad = ~np.isfinite(values)
        if bad.any():
            row, col = np.argwhere(bad)[0]
            raise ValueError(f"{name}: row {row + 1}, column '{columns[col]}': {values[row, col]} is not a finite "
                             "number (pass missing=True to treat it as a missing sample)")
    # Column-major, the layout of the C++ table: a DataFrame's float block usually is already, and the
    # conversion is then one copy.
    return columns, np.asfortranarray(values), name, None


def _structure(kwargs, bundled):
    """The model options; a bundled record's suggested structure when none is given."""
    polynomial = {k: kwargs.pop(k) for k in _POLYNOMIAL_KEYS if kwargs.get(k) is not None}
    given = {k: kwargs.pop(k) for k in _STRUCTURE_KEYS if kwargs.get(k) is not None}
    na_given = "na" in given
    if not given and bundled is not None:
        s = _datasets.info(bundled)["structure"]
        given = {"output": s["output"]}
        if "regressors" in s:
            given.update(regressors=s["regressors"], intercept=s.get("intercept", False))
        else:
            given.update(inputs=s["input"], na=s["na"], nb=s["nb"], nk=s["nk"])
    for key in ("inputs", "regressors"):
        if isinstance(given.get(key), str):
            given[key] = [given[key]]
    for key in ("nb", "nk"):
        if key in given and np.isscalar(given[key]):
            given[key] = [int(given[key])]
    given.update(polynomial)
    if given.get("nf") and not na_given:
        given["na"] = 0  # OE/Box-Jenkins: no A polynomial
    if "output" not in given:
        raise ValueError("give output= (the output column) and inputs= (ARX) or regressors= (static regression)")
    return given


def _default_split(split, bundled, kwargs_given):
    if split is not None:
        return float(split)
    if bundled is not None and not kwargs_given:
        return float(_datasets.info(bundled)["split"])
    return 0.5


class FitResult:
    """The result of ``ident.fit``: the fields of ``ident fit --json`` as attributes (numpy arrays for
    vectors), ``to_dict()``, the validation predictions, and the update history when asked for."""

    def __init__(self, raw, predict):
        self._dict = json.loads(raw["json"])
        self._predict = predict
        self._predictions = None
        self.history = raw.get("history")
        for key, value in self._dict.items():
            if key in ("theta", "theta_std"):
                value = np.array([np.nan if v is None else v for v in value], dtype=float)
            setattr(self, key, value)

    @property
    def predictions(self):
        """The validation part: row (1-based), measured, one_step and (dynamic models) simulation outputs."""
        if self._predictions is None:
            self._predictions = {k: np.asarray(v) for k, v in self._predict(self.theta).items()}
        return self._predictions

    def to_dict(self):
        """The JSON object of ``ident fit --json`` (a fresh copy)."""
        return json.loads(json.dumps(self._dict))

    @property
    def fit_one_step(self):
        return self._dict["fit_percent"]["one_step"]

    @property
    def fit_simulation(self):
        return self._dict["fit_percent"]["simulation"]

    def plot(self, fig=None):
        """Measured vs one-step and simulated output, residual correlations with the 99 % band, the
        parameter trajectories with ±2σ bands and the robust weight under them. Returns the figure."""
        from ident import plotting
        return plotting.plot_fit(self, fig)

    def __repr__(self):
        theta = ", ".join(f"{n}={v:.6g}" for n, v in zip(self.parameter_names, self.theta))
        return (f"FitResult({self.estimator} on {self.structure}: {theta}; one-step fit "
                f"{self.fit_one_step if self.fit_one_step is None else round(self.fit_one_step, 2)} %)")


def fit(data, output=None, inputs=None, na=None, nb=None, nk=None, estimator="rls", *, regressors=None,
        intercept=None, nc=None, nd=None, nf=None, split=None, passes=1, detrend=None, missing=False,
        history=False, residual_lags=20, experiment_column=None, **options):
    """Fits a model to a record with one estimator, as ``ident fit`` does.

    Structure: ``output`` with ``inputs``, ``na``, ``nb``, ``nk`` (ARX/FIR; with ``nc``: ARMAX, with
    ``nf``: output-error, with ``nc``, ``nd``, ``nf``: Box-Jenkins) or with ``regressors`` and
    ``intercept`` (static regression); a bundled record without them uses its suggested structure and
    split. ``estimator``: "rls", "cauchy", "student:3", "huber", "cauchy-ml". ``split``: fraction of rows
    that estimate (the rest validate; 1 = all rows do both). Further options as the command line's, in
    snake case: dof, delta, forgetting, stabilised, nu0, vy0, vz0, prior (a JSON file), exact,
    lock_in_window, lock_in_threshold, lock_in_restart, history_limit, clean_regressors (bool), clean_clip, clean_gross,
    clean_below. ``history=True`` keeps every update's weight, ν, θ̂ and its standard errors (for plot()).
    ``residual_lags``: lags of the residual analysis of the validation part (0: none, residual_analysis None).
    ``experiment_column``: a column labelling the experiment; each run of one label is an experiment, and
    the regressors restart at each (``ident fit --experiment-column``).
    """
    columns, values, name, bundled = _table(data, missing)
    kwargs = dict(output=output, inputs=inputs, na=na, nb=nb, nk=nk, regressors=regressors, intercept=intercept)
    given = any(v is not None for v in kwargs.values())
    kwargs.update(nc=nc, nd=nd, nf=nf)
    model = _structure(kwargs, bundled)
    split = _default_split(split, bundled, given)
    model.update(options)
    model["estimator"] = estimator
    experiments = experiment_column or ""
    raw = _ident.fit(columns, values, name, split, int(passes), detrend or "", bool(history), int(residual_lags),
                     model, experiments)
    structure = {k: v for k, v in model.items() if k in _STRUCTURE_KEYS + ("estimator",)}
    return FitResult(raw, lambda theta: _ident.predict(columns, values, name, split, detrend or "", theta, structure,
                                                       experiments))


class CompareResult(pd.DataFrame):
    """The table of ``ident.compare``: one row per estimator; ``json`` holds ``ident compare --json``'s object."""

    _metadata = ["json"]

    @property
    def _constructor(self):
        return CompareResult

    def plot(self, *args, **kwargs):
        """One-step validation fit per estimator (median, 90 % of trials and worst) beside the clean
        least-squares level. Returns the figure. (The DataFrame's own plot stays as ``DataFrame.plot(frame)``.)"""
        from ident import plotting
        return plotting.plot_compare(self, *args, **kwargs)


def compare(data, estimators=("rls", "cauchy", "student:3"), *, outliers="0.05:20:1", trials=1, jobs=1, passes=1,
            split=None, detrend=None, output=None, inputs=None, na=None, nb=None, nk=None, regressors=None,
            intercept=None, nc=None, nd=None, nf=None, **options):
    """Compares estimators on a record with injected outliers, scored on its clean rows (``ident compare``).

    ``outliers``: "RATE:SIZE[:SEED]" or "none"; ``jobs``: threads for the trials (the same table for any
    number; 0: every core). Returns a DataFrame, one row per estimator (best one-step
    fit first): estimator, kind, passes, fit_one_step, fit_simulation, theta_distance (means over the
    trials), their spreads, ns_per_update, failed_trials and one column per parameter; ``.json`` is the
    object of ``ident compare --json``."""
    columns, values, name, bundled = _table(data)
    kwargs = dict(output=output, inputs=inputs, na=na, nb=nb, nk=nk, regressors=regressors, intercept=intercept)
    given = any(v is not None for v in kwargs.values())
    kwargs.update(nc=nc, nd=nd, nf=nf)
    model = _structure(kwargs, bundled)
    split = _default_split(split, bundled, given)
    model.update(options)
    if isinstance(estimators, str):
        estimators = [estimators]
    jobs = (os.cpu_count() or 1) if jobs == 0 else int(jobs)
    text = _ident.compare(columns, values, name, list(estimators), str(outliers), int(trials), jobs, int(passes),
                          split, detrend or "", model)
    report = json.loads(text)
    rows = []
    for e in report["estimators"]:
        row = {"estimator": e["estimator"], "kind": e["kind"], "passes": e["passes"],
               "fit_one_step": e["fit_percent"]["one_step"], "fit_simulation": e["fit_percent"]["simulation"],
               "theta_distance": e["theta_distance"], "ns_per_update": e["ns_per_update"],
               "failed_trials": e["failed_trials"]}
        for key, spread in (("fit_one_step", e["spread"]["fit_one_step"]),
                            ("theta_distance", e["spread"]["theta_distance"])):
            for stat in ("std", "min", "median", "p90", "max"):
                row[f"{key}_{stat}"] = spread[stat]
        for pname, value in zip(report["parameter_names"], e["theta"]):
            row[pname] = value
        rows.append(row)
    frame = CompareResult(rows)
    frame = frame.astype({c: float for c in frame.columns
                          if c not in ("estimator", "kind", "passes", "failed_trials")})
    frame.json = report
    return frame


def smooth(model, z):
    """MAP state smoothing with convex penalties and its dual (``ident smooth``).

    ``model``: a dict (or JSON text) with F, H, initial, process, measurement as ``ident smooth --model``
    reads it; ``z``: the measurements, one row per time (T+1 rows; a 1-D array for one measurement).
    Returns a dict: x (states, one row per time), u, y (dual), primal, dual, gap, iterations, ..."""
    text = model if isinstance(model, str) else json.dumps(model)
    z = np.asarray(z, dtype=float)
    z = z.reshape(1, -1) if z.ndim == 1 else z.T
    return _ident.smooth(text, np.ascontiguousarray(z))


def logcondens(x):
    """The log-concave maximum-likelihood density of a sample (``ident logcondens``): a dict with the
    sorted distinct values x, their weights, the log-density phi at them, the knots, loglik, ..."""
    samples = np.asarray(x, dtype=float).ravel()
    return _ident.logcondens(samples.tolist())
