"""ARMAX through ident.fit against the batch prediction-error (maximum-likelihood) fit of statsmodels.

ARMAX A y = B u + C e is the regression y(t) = x(t)'β + C(q) e(t) with x = [−y(t−1), −y(t−2), u(t−3),
u(t−4)] and MA(nc) errors, which statsmodels' SARIMAX with exogenous regressors fits by maximum likelihood
(the prediction-error criterion for Gaussian e). On the first half of the bundled dryer record, mean
detrended as ident does: the recursive prediction-error method after 20 passes agrees with it within
0.25 of SARIMAX's standard errors, pseudo-linear regression (a different, also consistent, estimator)
within 1.5 of them."""

import numpy as np
import pandas as pd
import pytest

import ident

sm = pytest.importorskip("statsmodels.api")


def sarimax_armax(y, u, na=2, nb=2, nc=2, nk=3):
    t0 = max(na, nk + nb - 1)
    n = len(y)
    x = np.column_stack([-y[t0 - k:n - k] for k in range(1, na + 1)] + [u[t0 - nk - j:n - nk - j] for j in range(nb)])
    fit = sm.tsa.SARIMAX(y[t0:], exog=x, order=(0, 0, nc), trend="n").fit(disp=False)
    return np.asarray(fit.params[:na + nb + nc]), np.asarray(fit.bse[:na + nb + nc])


def test_recursive_armax_agrees_with_the_batch_maximum_likelihood_fit():
    data = pd.read_csv(ident.datasets.path("dryer"))
    half = len(data) // 2
    y = data["y"].to_numpy()[:half]
    u = data["u"].to_numpy()[:half]
    theta, se = sarimax_armax(y - y.mean(), u - u.mean())
    for recursion, passes, tolerance in (("rpem", 20, 0.25), ("rplr", 20, 1.5)):
        r = ident.fit("dryer", nc=2, passes=passes, recursion=recursion)
        assert r.structure == "ARMAX(2,2,2,3)"
        assert list(r.parameter_names) == ["a1", "a2", "b1", "b2", "c1", "c2"]
        gap = np.abs(np.asarray(r.theta) - theta) / se
        assert gap.max() <= tolerance, (recursion, r.theta, theta, gap)


def test_output_error_keywords_and_prediction():
    r = ident.fit("dryer", nf=2, passes=5, recursion="rpem")
    assert r.structure == "OE(2,2,3)"
    assert list(r.parameter_names) == ["b1", "b2", "f1", "f2"]
    # OE: the one-step prediction is the simulation (the measured output never enters the predictor).
    p = r.predictions
    valid = ~np.isnan(p["one_step"])
    assert valid.sum() > 400
    np.testing.assert_allclose(p["one_step"][valid], p["simulation"][valid], rtol=0, atol=1e-12)
