"""The regression estimators y(t) = theta' z(t) + e(t), by name.

Every class is an ident._ident.Estimator: ``update(y, z)`` returns a StepReport, ``update_many(Y, Z)``
runs the samples in C++ without the GIL and returns the StepStatus codes, ``parameters`` and
``covariance`` are numpy arrays, ``predict(z)``, ``reset()``, and ``enabled`` (False: samples are skipped).
"""

from ident._ident import Estimator


class RLS(Estimator):
    """Recursive least squares (LD-factorised), with optional exponential or stabilised forgetting."""

    def __init__(self, n, forgetting=1.0, *, stabilised=False, nu0=None, V0=None):
        super().__init__("rls", n, forgetting=forgetting, stabilised=stabilised, nu0=nu0, V0=V0)


class Cauchy(Estimator):
    """The Kárný–Hangos recursive estimator for Cauchy noise (robust start-up and lock-in safeguard).

    ``exact=True`` runs the paper's recursion without the safeguards."""

    def __init__(self, n, forgetting=1.0, *, stabilised=False, delta=None, nu0=None, V0=None, exact=False,
                 lock_in_window=None, lock_in_threshold=None, lock_in_restart=True, history_limit=None):
        super().__init__("cauchy", n, forgetting=forgetting, stabilised=stabilised, delta=delta, nu0=nu0, V0=V0,
                         exact=exact, lock_in_window=lock_in_window, lock_in_threshold=lock_in_threshold,
                         lock_in_restart=lock_in_restart, history_limit=history_limit)


class Student(Estimator):
    """The Kárný–Hangos recursive estimator for Student-t noise with ``dof`` degrees of freedom."""

    def __init__(self, n, dof, forgetting=1.0, *, stabilised=False, delta=None, nu0=None, V0=None, exact=False,
                 lock_in_window=None, lock_in_threshold=None, lock_in_restart=True, history_limit=None):
        super().__init__("student", n, dof=float(dof), forgetting=forgetting, stabilised=stabilised, delta=delta,
                         nu0=nu0, V0=V0, exact=exact, lock_in_window=lock_in_window,
                         lock_in_threshold=lock_in_threshold, lock_in_restart=lock_in_restart,
                         history_limit=history_limit)


class Huber(Estimator):
    """Batch reference: Huber M-estimation (IRLS, MAD scale), solved on every sample at read-out."""

    def __init__(self, n):
        super().__init__("huber", n)


class CauchyML(Estimator):
    """Batch reference: Cauchy maximum likelihood in theta and scale jointly, global optimum from many starts."""

    def __init__(self, n):
        super().__init__("cauchy-ml", n)
