"""`ident orders` against statsmodels: the same least-squares loss, AIC and BIC for every structure (up to
the constant n(log 2π + 1) by which statsmodels' Gaussian likelihood criteria differ from N log V + 2d)."""

import math

import numpy as np
import pytest

import ident

sm = pytest.importorskip("statsmodels.api")


def test_orders_match_statsmodels_ols(cli):
    report = cli("orders", "dryer", "--output", "y", "--input", "u", "--na", "1:3", "--nb", "1:3", "--nk", "1:3",
                 "--json")
    frame = ident.datasets.load("dryer")
    n_est = len(frame) // 2
    y = frame["y"].to_numpy()[:n_est]
    u = frame["u"].to_numpy()[:n_est]
    y, u = y - y.mean(), u - u.mean()
    t0 = 3 + 3 - 1  # max(na_max, nk_max + nb_max - 1)
    t = np.arange(t0, n_est)
    n = len(t)
    assert report["samples"] == n
    shift = n * (math.log(2 * math.pi) + 1)
    for s in report["structures"]:
        Z = np.column_stack([-y[t - i] for i in range(1, s["na"] + 1)] +
                            [u[t - s["nk"] - k] for k in range(s["nb"])])
        ols = sm.OLS(y[t], Z).fit()
        assert s["loss"] == pytest.approx(ols.ssr / n, rel=1e-10)
        assert s["aic"] == pytest.approx(ols.aic - shift, abs=1e-7)
        assert s["bic"] == pytest.approx(ols.bic - shift, abs=1e-7)
        np.testing.assert_allclose(s["theta"], ols.params, rtol=1e-8)
    best = min(report["structures"], key=lambda s: s["aic"])
    assert report["best"] == best


def test_robust_orders_match_scipy_student_t(cli):
    """`--estimator student:3`: each structure's nll is scipy's Student-t NLL of the residuals of its reported θ,
    minimised over the scale; aic, bic and mdl count θ and the scale."""
    stats = pytest.importorskip("scipy.stats")
    optimize = pytest.importorskip("scipy.optimize")
    k = 3.0
    report = cli("orders", "dryer", "--output", "y", "--input", "u", "--na", "1:2", "--nb", "1:2", "--nk", "1:2",
                 "--estimator", "student:3", "--criterion", "bic", "--json")
    assert report["estimator"] == "student:3"
    frame = ident.datasets.load("dryer")
    n_est = len(frame) // 2
    y = frame["y"].to_numpy()[:n_est]
    u = frame["u"].to_numpy()[:n_est]
    y, u = y - y.mean(), u - u.mean()
    t = np.arange(3, n_est)  # max(na_max, nk_max + nb_max - 1)
    n = len(t)
    assert report["samples"] == n
    for s in report["structures"]:
        Z = np.column_stack([-y[t - i] for i in range(1, s["na"] + 1)] +
                            [u[t - s["nk"] - j] for j in range(s["nb"])])
        r = y[t] - Z @ np.asarray(s["theta"])

        def nll(log_scale):
            return -stats.t.logpdf(r, df=k, scale=math.exp(log_scale)).sum()

        c = 0.5 * math.log(np.mean(r * r))
        best = optimize.minimize_scalar(nll, bounds=(c - 10, c + 3), method="bounded",
                                        options={"xatol": 1e-12, "maxiter": 1000})
        p = s["n_parameters"] + 1
        assert s["loss"] == pytest.approx(np.mean(r * r), rel=1e-10)
        assert s["nll"] == pytest.approx(best.fun, rel=1e-8)
        assert s["scale"] == pytest.approx(math.exp(best.x), rel=1e-6)
        assert s["aic"] == pytest.approx(2 * best.fun + 2 * p, rel=1e-8)
        assert s["bic"] == pytest.approx(2 * best.fun + p * math.log(n), rel=1e-8)
        assert s["mdl"] == pytest.approx(best.fun + p / 2 * math.log(n), rel=1e-8)
        assert s["fpe"] is None
    assert report["best"] == min(report["structures"], key=lambda s: s["bic"])
