"""The observers, checked against a Kalman filter written here in numpy and against each other."""

import numpy as np
import pytest

import ident

A = np.array([[1.0, 0.1], [0.0, 1.0]])
B = np.array([[0.005], [0.1]])
Q = np.array([[1e-4, 5e-4], [5e-4, 1e-2]])
C = np.array([1.0, 0.0])
R = 0.04
X0, P0 = np.zeros(2), np.eye(2)


def simulate(n=300, seed=3):
    rng = np.random.default_rng(seed)
    x, U, Y = np.zeros(2), rng.normal(size=(n, 1)), np.empty(n)
    L = np.linalg.cholesky(Q)
    for k in range(n):
        x = A @ x + B @ U[k] + L @ rng.normal(size=2)
        Y[k] = C @ x + np.sqrt(R) * rng.normal()
    return Y, U


def numpy_kalman(Y, U):
    x, P = X0.copy(), P0.copy()
    for y, u in zip(Y, U):
        x, P = A @ x + B @ u, A @ P @ A.T + Q
        s = C @ P @ C + R
        k = P @ C / s
        x, P = x + k * (y - C @ x), P - np.outer(k, C @ P)
    return x, P


def test_kalman_filter_matches_the_textbook_recursion():
    Y, U = simulate()
    kf = ident.KalmanFilter(A, Q, C, R, X0, P0, B=B)
    status = kf.update_many(Y, U)
    assert (status == int(ident.StepStatus.UPDATED)).all()
    x, P = numpy_kalman(Y, U)
    np.testing.assert_allclose(kf.mean, x, atol=1e-10)
    np.testing.assert_allclose(kf.covariance, P, atol=1e-10)


def test_lc_gaussian_filter_with_a_gaussian_reading_is_the_kalman_filter():
    Y, U = simulate(n=100)
    lc = ident.LcGaussianFilter(A, Q, ident.GaussianMeasurement(C, R), X0, P0, B=B)
    lc.update_many(Y, U)
    x, P = numpy_kalman(Y, U)
    np.testing.assert_allclose(lc.mean, x, atol=1e-9)
    np.testing.assert_allclose(lc.covariance, P, atol=1e-9)


def test_predict_is_the_kalman_predicted_reading():
    Y, U = simulate(n=60)
    kf = ident.KalmanFilter(A, Q, C, R, X0, P0, B=B)
    x, P = X0.copy(), P0.copy()
    for y, u in zip(Y, U):
        x, P = A @ x + B @ u, A @ P @ A.T + Q
        assert kf.predict(u) == pytest.approx(C @ x, abs=1e-10)
        k = P @ C / (C @ P @ C + R)
        x, P = x + k * (y - C @ x), P - np.outer(k, C @ P)
        kf.update(y, u)
    with pytest.raises(ValueError, match="u has 2 entries"):
        kf.predict(np.zeros(2))


def test_grid_observer_approaches_the_exact_posterior():
    Y, U = simulate(n=50)
    grid = ident.GridObserver(A, Q, ident.GaussianMeasurement(C, R), X0, P0, B=B, points=96)
    grid.update_many(Y, U)
    x, P = numpy_kalman(Y, U)
    np.testing.assert_allclose(grid.mean, x, atol=0.02 * np.sqrt(np.diag(P)).max())


def test_update_reset_enabled_and_a_robust_reading():
    Y, U = simulate(n=40)
    lap = ident.LcGaussianFilter(A, Q, ident.LaplaceMeasurement(C, 0.2), X0, P0, B=B)
    for y, u in zip(Y, U):
        assert lap.update(y, u).updated
    mean = lap.mean
    lap.enabled = False
    assert lap.update(Y[0], U[0]).status == ident.StepStatus.SKIPPED
    assert np.array_equal(lap.mean, mean)
    lap.enabled = True
    lap.reset()
    np.testing.assert_array_equal(lap.mean, X0)
    np.testing.assert_array_equal(lap.covariance, P0)


def test_bad_observer_input_raises_value_error():
    with pytest.raises(ValueError, match="kalman"):
        ident.Observer("kalman", A, B, Q, ident.LaplaceMeasurement(C, 1.0), X0, P0)
    with pytest.raises(ValueError):
        ident.KalmanFilter(A, Q, C, R, X0, -P0, B=B)  # P0 not positive definite
    kf = ident.KalmanFilter(A, Q, C, R, X0, P0, B=B)
    with pytest.raises(ValueError, match="u has 2 entries; the model has 1 inputs"):
        kf.update(1.0, [1.0, 2.0])
    with pytest.raises(ValueError, match="give U"):
        kf.update_many(np.zeros(3))
    with pytest.raises(ValueError, match="no option"):
        ident.GridObserver(A, Q, ident.GaussianMeasurement(C, R), X0, P0, B=B, colour=3)


def test_interval_readings_keep_the_state_inside_their_intervals():
    Y, U = simulate(n=60)
    step = 0.05
    quantised = step * np.round((Y - np.sqrt(R) * 0) / step)
    q = ident.LcGaussianFilter(A, Q, ident.UniformQuantizer(C, step), X0, P0, B=B)
    assert (q.update_many(quantised, U) == int(ident.StepStatus.UPDATED)).all()
    assert abs(C @ q.mean - quantised[-1]) <= step  # the reading's interval, widened by one prior step
    sensor = ident.ThresholdSensor(C, 1.0)
    assert sensor.name and sensor.num_states == 2
    readings = np.where(np.abs(Y) >= 1.0, np.sign(Y), 0.0)
    grid = ident.Observer("grid", A, B, Q, sensor, X0, P0, {"points": "48"})
    assert (grid.update_many(readings, U) == int(ident.StepStatus.UPDATED)).all()
    assert np.isfinite(grid.mean).all() and np.linalg.eigvalsh(grid.covariance).min() > 0
    assert "grid" in ident.observer_names() and grid.name == "grid"
