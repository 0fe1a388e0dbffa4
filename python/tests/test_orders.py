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
