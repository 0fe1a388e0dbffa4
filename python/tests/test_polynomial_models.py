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


def test_recursive_box_jenkins_agrees_with_the_batch_prediction_error_fit():
    """Box-Jenkins y = (B/F) u + (C/D) e simulated (10^4 samples, B = q^-1 + 0.5 q^-2, F = 1 - 1.2 q^-1 +
    0.5 q^-2, C = 1 + 0.5 q^-1, D = 1 - 0.8 q^-1): RPEM after 10 passes lands within 1 standard error of
    the batch prediction-error fit (scipy least squares on e = (D/C)(y - (B/F) u)), and its theta_std
    within 20 % of that fit's Gauss-Newton standard errors."""
    from scipy.optimize import least_squares
    from scipy.signal import lfilter

    rng = np.random.default_rng(3)
    n = 10000
    u = np.sign(rng.standard_normal(n))
    y = lfilter([0, 1.0, 0.5], [1, -1.2, 0.5], u) + lfilter([1, 0.5], [1, -0.8], 0.3 * rng.standard_normal(n))

    def errors(theta):
        b1, b2, c1, d1, f1, f2 = theta
        return lfilter([1, d1], [1, c1], y - lfilter([0, b1, b2], [1, f1, f2], u))[2:]

    pem = least_squares(errors, np.array([0.5, 0.2, 0, 0, -1, 0.3]), xtol=1e-14, ftol=1e-14, gtol=1e-14)
    jac = pem.jac
    se = np.sqrt(np.diag(np.sum(pem.fun ** 2) / (len(pem.fun) - 6) * np.linalg.inv(jac.T @ jac)))
    data = pd.DataFrame({"t": np.arange(n), "u": u, "y": y})
    r = ident.fit(data, output="y", inputs=["u"], nb=2, nc=1, nd=1, nf=2, nk=1, split=1, detrend="none",
                  passes=10, recursion="rpem")
    assert r.structure == "BJ(2,1,1,2,1)"
    assert list(r.parameter_names) == ["b1", "b2", "c1", "d1", "f1", "f2"]
    gap = np.abs(np.asarray(r.theta) - pem.x) / se
    assert gap.max() <= 1.0, (r.theta, pem.x, gap)
    ratio = np.asarray(r.theta_std) / se
    assert np.all((ratio > 0.8) & (ratio < 1.25)), ratio
