"""The streaming regression estimators, checked against closed-form least squares, a brute-force
Cauchy likelihood optimum (scipy) and their own loop."""

import numpy as np
import pytest

import ident


def regression(n=2000, rho=4, seed=1, noise=None):
    rng = np.random.default_rng(seed)
    Z = rng.normal(size=(n, rho))
    theta = np.linspace(-1.5, 2.0, rho)
    e = noise(rng, n) if noise else 0.1 * rng.normal(size=n)
    return Z @ theta + e, Z, theta


def test_rls_with_a_weak_prior_is_batch_least_squares():
    Y, Z, _ = regression()
    est = ident.RLS(4, nu0=1e-9, V0=np.eye(5) * 1e-9)
    status = est.update_many(Y, Z)
    assert (status == int(ident.StepStatus.UPDATED)).all()
    batch, *_ = np.linalg.lstsq(Z, Y, rcond=None)
    np.testing.assert_allclose(est.parameters, batch, rtol=0, atol=1e-9)
    residual = Y - Z @ batch
    s2 = residual @ residual / (len(Y) - 4)
    np.testing.assert_allclose(est.covariance, s2 * np.linalg.inv(Z.T @ Z), rtol=1e-3)


def test_rls_with_forgetting_is_exponentially_weighted_least_squares():
    Y, Z, _ = regression(n=400)
    lam = 0.98
    est = ident.RLS(4, forgetting=lam, nu0=1e-12, V0=np.eye(5) * 1e-12)
    est.update_many(Y, Z)
    w = lam ** np.arange(len(Y) - 1, -1, -1)
    batch = np.linalg.solve(Z.T @ (w[:, None] * Z), Z.T @ (w * Y))
    np.testing.assert_allclose(est.parameters, batch, atol=1e-8)


def test_update_many_is_the_loop_of_update_bit_for_bit():
    Y, Z, _ = regression(n=500, noise=lambda rng, n: 0.1 * rng.standard_cauchy(n))
    for make in (lambda: ident.RLS(4), lambda: ident.Cauchy(4), lambda: ident.Student(4, dof=3)):
        a, b = make(), make()
        a.update_many(Y, Z)
        for y, z in zip(Y, Z):
            b.update(y, z)
        assert np.array_equal(a.parameters, b.parameters)
        assert np.array_equal(a.covariance, b.covariance)


def cauchy_ml(Y, Z):
    """The Cauchy maximum-likelihood estimate in (theta, scale), by scipy from the least-squares start."""
    from scipy.optimize import minimize

    def nll(p):
        theta, log_s = p[:-1], p[-1]
        r = (Y - Z @ theta) / np.exp(log_s)
        return np.sum(np.log1p(r * r)) + len(Y) * log_s

    start = np.append(np.linalg.lstsq(Z, Y, rcond=None)[0], 0.0)
    return minimize(nll, start, method="Nelder-Mead",
                    options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 40000, "maxfev": 40000}).x[:-1]


def test_batch_cauchy_ml_matches_a_brute_force_optimum():
    Y, Z, _ = regression(n=300, rho=2, noise=lambda rng, n: 0.2 * rng.standard_cauchy(n))
    est = ident.CauchyML(2)
    est.update_many(Y, Z)
    assert est.kind == "batch"
    np.testing.assert_allclose(est.parameters, cauchy_ml(Y, Z), atol=1e-4)


def test_recursive_cauchy_is_close_to_the_cauchy_ml_estimate_and_far_better_than_least_squares():
    Y, Z, theta = regression(n=3000, rho=3, noise=lambda rng, n: 0.1 * rng.standard_cauchy(n))
    est = ident.Cauchy(3)
    est.update_many(Y, Z)
    ls = np.linalg.lstsq(Z, Y, rcond=None)[0]
    assert np.linalg.norm(est.parameters - theta) < 0.02
    assert np.linalg.norm(est.parameters - theta) < 0.2 * np.linalg.norm(ls - theta)
    np.testing.assert_allclose(est.parameters, cauchy_ml(Y, Z), atol=0.02)
    assert est.lock_in is not None and est.lock_in["restarts"] == 0
    assert est.nu > 2900


def test_huber_is_batch_and_resists_gross_outliers():
    Y, Z, theta = regression(n=400, rho=2)
    Y[::20] += 50.0
    est = ident.Huber(2)
    est.update_many(Y, Z)
    assert est.kind == "batch"
    assert np.linalg.norm(est.parameters - theta) < 0.05


def test_predict_reset_enabled_and_reports():
    Y, Z, _ = regression(n=200)
    est = ident.Cauchy(4)
    est.update_many(Y, Z)
    assert est.predict(Z[0]) == pytest.approx(Z[0] @ est.parameters, abs=1e-12)
    np.testing.assert_allclose(est.predict(Z[:5]), Z[:5] @ est.parameters, atol=1e-12)
    theta = est.parameters
    est.enabled = False
    report = est.update(100.0, Z[0])
    assert report.status == ident.StepStatus.SKIPPED and not report
    assert (est.update_many(Y, Z) == int(ident.StepStatus.SKIPPED)).all()
    assert np.array_equal(est.parameters, theta)
    est.enabled = True
    report = est.update(float("nan"), Z[0])
    assert report.status == ident.StepStatus.REJECTED_INVALID
    assert np.array_equal(est.parameters, theta)
    report = est.update(Y[0], Z[0])
    assert report.updated and 0 <= report.weight and report.nu > 0
    est.reset()
    fresh = ident.Cauchy(4)
    assert np.array_equal(est.parameters, fresh.parameters)


def test_bad_input_raises_value_error_with_the_library_message():
    with pytest.raises(ValueError, match="unknown estimator 'nope'"):
        ident.Estimator("nope", 2)
    with pytest.raises(ValueError, match="z has 3 entries; this estimator has 2 parameters"):
        ident.RLS(2).update(1.0, [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="Z has 3 columns"):
        ident.RLS(2).update_many(np.zeros(4), np.zeros((4, 3)))
    with pytest.raises(ValueError, match="Y has 4 samples but Z has 5 rows"):
        ident.RLS(2).update_many(np.zeros(4), np.zeros((5, 2)))
    with pytest.raises(ValueError, match="forgetting"):
        ident.RLS(2, forgetting=1.5)
    with pytest.raises(ValueError, match="dof"):
        ident.Student(2, dof=-1)
    with pytest.raises(ValueError, match="need at least one parameter"):
        ident.RLS(0)
    with pytest.raises(ValueError, match="lock-in"):
        ident.Estimator("rls", 2, lock_in_window=50)
    with pytest.raises(ValueError, match="history_limit = 5; need 0"):
        ident.Cauchy(2, history_limit=5)


def test_numpy_arrays_of_other_layouts_are_accepted():
    Y, Z, _ = regression(n=300)
    a, b = ident.RLS(4), ident.RLS(4)
    a.update_many(Y, Z)
    b.update_many(list(Y), np.asfortranarray(Z))  # a list and a column-major array are converted
    np.testing.assert_array_equal(a.parameters, b.parameters)


def test_further_passes_move_the_recursive_estimate_to_the_batch_optimum():
    Y, Z, _ = regression(n=300, rho=2, noise=lambda rng, n: 0.2 * rng.standard_cauchy(n))
    est = ident.Cauchy(2)
    est.update_many(Y, Z)
    est.finish_startup()
    one_pass = np.linalg.norm(est.parameters - cauchy_ml(Y, Z))
    for _ in range(3):
        assert est.begin_pass()
        est.update_many(Y, Z)
    assert np.linalg.norm(est.parameters - cauchy_ml(Y, Z)) <= one_pass + 1e-12
    assert not ident.RLS(2).begin_pass()  # least squares reaches its optimum in one pass
    assert set(ident.estimator_names()) >= {"rls", "cauchy", "student", "huber", "cauchy-ml"}
