"""State observers for x(k) = A x(k-1) + B u(k-1) + v, v ~ N(0, Q), and a reading y(k) of x(k).

Every class is an ident._ident.Observer: ``update(y, u=None)`` (time update with u(k-1), then the
measurement update with y(k)) returns a StepReport, ``update_many(Y, U=None)`` runs in C++ without the
GIL, ``mean`` and ``covariance`` are numpy arrays, ``reset()`` returns to the prior N(x0, P0), and
``enabled`` (False: readings are skipped).
"""

import numpy as np

from ident._ident import GaussianMeasurement, Observer


def _model(A, B, Q):
    A = np.atleast_2d(np.asarray(A, dtype=float))
    B = None if B is None else np.asarray(B, dtype=float).reshape(A.shape[0], -1)
    return A, B, np.atleast_2d(np.asarray(Q, dtype=float))


class KalmanFilter(Observer):
    """The square-root Kalman filter for a linear-Gaussian reading y = c'x + e, e ~ N(0, r)."""

    def __init__(self, A, Q, c, r, x0, P0, B=None):
        A, B, Q = _model(A, B, Q)
        super().__init__("kalman", A, B, Q, GaussianMeasurement(np.asarray(c, dtype=float), float(r)),
                         np.asarray(x0, dtype=float), np.atleast_2d(np.asarray(P0, dtype=float)))


class LcGaussianFilter(Observer):
    """The log-concave Gaussian filter (assumed density, exact tilted moments) for a reading through c'x:
    GaussianMeasurement, LaplaceMeasurement, ThresholdSensor, UniformQuantizer."""

    def __init__(self, A, Q, measurement, x0, P0, B=None):
        A, B, Q = _model(A, B, Q)
        super().__init__("lc_gaussian", A, B, Q, measurement, np.asarray(x0, dtype=float),
                         np.atleast_2d(np.asarray(P0, dtype=float)))


class GridObserver(Observer):
    """The Bayesian observer on a grid (1 to 3 states), for any log-concave measurement.

    Options as the registry's: points (an int, or per axis as "64x48"), initial_sigmas, noise_sigmas,
    support_level, min_half_width, padding."""

    def __init__(self, A, Q, measurement, x0, P0, B=None, **options):
        A, B, Q = _model(A, B, Q)
        super().__init__("grid", A, B, Q, measurement, np.asarray(x0, dtype=float),
                         np.atleast_2d(np.asarray(P0, dtype=float)),
                         {key: str(value) for key, value in options.items()})
