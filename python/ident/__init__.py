"""ident — recursive, outlier-robust system identification, from Python.

Streaming estimators keep their state between calls::

    import ident
    est = ident.Cauchy(4)
    est.update_many(Y, Z)            # the loop runs in C++, the GIL released
    est.parameters, est.covariance

Workflows on recorded data (a pandas DataFrame, a dict of arrays, a CSV path or a bundled record)::

    result = ident.fit("dryer", output="y", inputs=["u"], na=2, nb=2, nk=3, estimator="cauchy")
    result.theta, result.to_dict()   # the keys of `ident fit --json`
    result.plot()
    ident.compare("dryer", estimators=["rls", "cauchy", "huber"], trials=10)   # a pandas DataFrame
"""

from ident._ident import StepReport, StepStatus, estimator_names, observer_names
from ident._ident import (Measurement, GaussianMeasurement, LaplaceMeasurement, ThresholdSensor,
                          UniformQuantizer)
from ident.estimators import Estimator, RLS, Cauchy, Student, Huber, CauchyML
from ident.observers import Observer, KalmanFilter, LcGaussianFilter, GridObserver
from ident.workflow import FitResult, CompareResult, fit, compare, smooth, logcondens
from ident import datasets, distributed

__all__ = [
    "StepReport", "StepStatus", "estimator_names", "observer_names",
    "Measurement", "GaussianMeasurement", "LaplaceMeasurement", "ThresholdSensor", "UniformQuantizer",
    "Estimator", "RLS", "Cauchy", "Student", "Huber", "CauchyML",
    "Observer", "KalmanFilter", "LcGaussianFilter", "GridObserver",
    "FitResult", "CompareResult", "fit", "compare", "smooth", "logcondens", "datasets", "distributed",
]
