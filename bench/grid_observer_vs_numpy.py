#!/usr/bin/python3
"""Grid observer and Kalman step: ident (C++, through the Python package) against numpy references of the
same posteriors, on one simulated run of the MEMS accelerometer (Henningsson & Astrom 2006, sec. V).

The run: x(k) = A x(k-1) + B u(k-1) + v, A = [[1, h], [0, 1]], B = [h^2/2, h], v ~ N(0, Q) with
Q = [[h^3/3, h^2/2], [h^2/2, h]] (sigma^2 = 1, h = 0.01); reading y = sign(x1) if |x1| >= 1 else 0; the input
ping-pongs x1 between the thresholds (velocity reference -+v_ref after each event, v_ref = 2 / t_mean).

numpy references of the grid posterior (written here, independent of ident): a fixed grid whose x1 cell
edges lie on the thresholds (the reading cuts whole cells), velocity rows over the run's range; per step
the velocity shift by h u and the shear x1 -> x1 + h v, the process noise by an FFT (rfft2, zero padded)
with the Gaussian characteristic function exp(-w'Qw/2), the reading as the indicator of the cells,
normalisation and moments; the shift and the shear by linear interpolation (np.interp per row), which
diffuses by up to a spacing^2/4 per step, so it needs fine grids (about 1100 x 400 nodes for 2 %).
numpy reference of the Kalman step: the covariance-form predict / update with 2 x 2 arrays.

Accuracy: the mean predicted velocity variance over the run after 10 % burn-in, relative to that of a
converged grid (ident at 384^2, checked against 256^2). "Equal accuracy": the cheapest grid of each code
within --accuracy (2 %) of it; when no numpy grid of the list gets there, the speed-up is bounded from
below by the time of numpy's finest grid (numpy_speedup_lower_bound). Time per step: ident's update_many over the run (the loop in C++), numpy's
loop; best of --repeat runs, process CPU time.

    PYTHONPATH=build/python bench/grid_observer_vs_numpy.py [--json FILE]
"""
import argparse
import json
import sys
import time

import numpy as np

import ident

H, SIGMA2, T = 0.01, 1.0, 1.0
A = np.array([[1.0, H], [0.0, 1.0]])
B = np.array([[0.5 * H * H], [H]])
Q = SIGMA2 * np.array([[H ** 3 / 3, H ** 2 / 2], [H ** 2 / 2, H]])
X0, P0 = np.array([0.0, 2.0]), np.diag([0.3, 1.0])


def simulate(steps, t_mean, seed):
    """Truth, readings y(k) and inputs u(k-1) (u[k] is applied before reading y[k])."""
    rng = np.random.default_rng(seed)
    L = np.linalg.cholesky(Q)
    v_ref, tau = 2 * T / t_mean, t_mean / 8
    x, u, direction = X0.copy(), 0.0, 1.0
    xs, ys, us = [], [], []
    for _ in range(steps):
        us.append(u)
        x = A @ x + B[:, 0] * u + L @ rng.standard_normal(2)
        y = float(np.sign(x[0])) if abs(x[0]) >= T else 0.0
        if y != 0:
            direction = -y
        u = -y * 2 * v_ref / tau if y != 0 else -(x[1] - direction * v_ref) / tau
        xs.append(x.copy())
        ys.append(y)
    return np.array(xs), np.array(ys), np.array(us)


class NumpyGrid:
    """The grid posterior in numpy (module docstring)."""

    def __init__(self, n1, n2, x1_half, v_lo, v_hi):
        cells = int(round(n1 * T / (2 * x1_half)))        # cells across (-T, T): edges on the thresholds
        d1 = 2 * T / cells
        extra = (n1 - cells) // 2
        self.x1 = -T + d1 * (np.arange(cells + 2 * extra) - extra + 0.5)
        self.v = np.linspace(v_lo, v_hi, n2)
        self.d1, self.d2 = d1, self.v[1] - self.v[0]
        X1, V = np.meshgrid(self.x1, self.v, indexing="ij")
        d = np.stack([X1 - X0[0], V - X0[1]])
        Pi = np.linalg.inv(P0)
        self.p = np.exp(-0.5 * np.einsum("i...,ij,j...->...", d, Pi, d))
        self.shape = (2 * len(self.x1), 2 * len(self.v))        # zero padding for the FFT
        w1 = 2 * np.pi * np.fft.fftfreq(self.shape[0], self.d1)
        w2 = 2 * np.pi * np.fft.rfftfreq(self.shape[1], self.d2)
        W1, W2 = np.meshgrid(w1, w2, indexing="ij")
        self.kernel = np.exp(-0.5 * (Q[0, 0] * W1 ** 2 + 2 * Q[0, 1] * W1 * W2 + Q[1, 1] * W2 ** 2))
        self.inside = np.abs(self.x1) < T
        self.normalise()

    def normalise(self):
        self.p /= self.p.sum() * self.d1 * self.d2
        w = self.p * self.d1 * self.d2
        self.mean = np.array([w.sum(1) @ self.x1, w.sum(0) @ self.v])
        self.var_v = w.sum(0) @ (self.v - self.mean[1]) ** 2

    def step(self, u, y):
        p = self.linear_transport(u)
        # process noise
        p = np.fft.irfft2(np.fft.rfft2(p, self.shape) * self.kernel, self.shape)[:p.shape[0], :p.shape[1]]
        np.maximum(p, 0.0, out=p)
        # reading: whole cells inside (y = 0) or beyond the threshold on the side of y
        if y == 0:
            p[~self.inside] = 0.0
        else:
            p[self.inside | (np.sign(self.x1) != y)] = 0.0
        self.p = p
        self.normalise()

    def linear_transport(self, u):
        p = self.p
        # velocity shift: f1(x1, v) = f(x1, v - h u)
        vs = self.v - H * u
        p = np.stack([np.interp(vs, self.v, row, left=0.0, right=0.0) for row in p])
        # shear: f2(x1, v) = f1(x1 - h v + h^2 u / 2, v)
        return np.stack([np.interp(self.x1 - H * vj + 0.5 * H * H * u, self.x1, col, left=0.0, right=0.0)
                         for vj, col in zip(self.v, p.T)], axis=1)


def numpy_grid_run(xs, ys, us, n1, n2):
    x1_half = max(np.abs(xs[:, 0]).max() + 0.3, T + 0.2)
    v_lo, v_hi = xs[:, 1].min() - 3.0, xs[:, 1].max() + 3.0
    g = NumpyGrid(n1, n2, x1_half, v_lo, v_hi)
    var = np.empty(len(ys))
    t0 = time.process_time()
    for k, (u, y) in enumerate(zip(us, ys)):
        g.step(u, y)
        var[k] = g.var_v
    return var, (time.process_time() - t0) / len(ys)


def ident_grid(points):
    return ident.GridObserver(A, Q, ident.ThresholdSensor([1.0, 0.0], T), X0, P0, B=B, points=points)


def ident_grid_run(ys, us, points, repeat):
    g = ident_grid(points)
    var = np.empty(len(ys))
    for k, (u, y) in enumerate(zip(us, ys)):
        g.update(y, [u])
        var[k] = g.covariance[1, 1]
    best = np.inf
    U = us.reshape(-1, 1)
    for _ in range(repeat):
        g = ident_grid(points)
        t0 = time.process_time()
        g.update_many(ys, U)
        best = min(best, (time.process_time() - t0) / len(ys))
    return var, best


def kalman_readings(ys):
    """The tuned Kalman filter's readings of x1: y T (sigma_o^2 / h for repeated readings)."""
    sigma_o = 0.5 ** (1 / 3) * (1 / np.sqrt(3)) ** (2 / 3) * SIGMA2 ** (-1 / 6)
    return ys * T, sigma_o ** 2 / H


def numpy_kalman_run(z, r, us):
    m, P, c = X0.copy(), P0.copy(), np.array([1.0, 0.0])
    t0 = time.process_time()
    for zk, u in zip(z, us):
        m = A @ m + B[:, 0] * u
        P = A @ P @ A.T + Q
        s = c @ P @ c + r
        k = P @ c / s
        m = m + k * (zk - c @ m)
        P = P - np.outer(k, c @ P)
    return m, (time.process_time() - t0) / len(z)


def ident_kalman_run(z, r, us, repeat):
    best, m = np.inf, None
    for _ in range(repeat):
        kf = ident.KalmanFilter(A, Q, [1.0, 0.0], r, X0, P0, B=B)
        t0 = time.process_time()
        kf.update_many(z, us.reshape(-1, 1))
        best = min(best, (time.process_time() - t0) / len(z))
        m = kf.mean
    return m, best


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--steps", type=int, default=1000)
    p.add_argument("--t-mean", type=float, default=1.0)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--accuracy", type=float, default=0.02)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--json", help="write the figures to this file")
    a = p.parse_args()
    xs, ys, us = simulate(a.steps, a.t_mean, a.seed)
    burn = a.steps // 10

    def mean_var(var):
        return float(np.mean(var[burn:]))

    ref_var, _ = ident_grid_run(ys, us, 384, 1)
    reference = mean_var(ref_var)
    check_var, _ = ident_grid_run(ys, us, 256, 1)
    rows = []
    for points in (32, 48, 64, 96, 128, 192):
        var, t = ident_grid_run(ys, us, points, a.repeat)
        rows.append({"code": "ident", "grid": f"{points}x{points}", "nodes": points * points,
                     "us_per_step": t * 1e6, "mean_var_v": mean_var(var),
                     "relative_error": mean_var(var) / reference - 1})
        print(rows[-1], file=sys.stderr)
    for code in ("numpy",):
        for n1, n2 in ((128, 48), (256, 96), (512, 192), (768, 288), (1024, 384), (1280, 480)):
            var, t = numpy_grid_run(xs, ys, us, n1, n2)
            rows.append({"code": code, "grid": f"{n1}x{n2}", "nodes": n1 * n2, "us_per_step": t * 1e6,
                         "mean_var_v": mean_var(var), "relative_error": mean_var(var) / reference - 1})
            print(rows[-1], file=sys.stderr)

    def cheapest(code):
        ok = [r for r in rows if r["code"] == code and abs(r["relative_error"]) <= a.accuracy]
        return min(ok, key=lambda r: r["us_per_step"]) if ok else None

    ours = cheapest("ident")
    equal = {"ident": ours and ours["grid"]}
    for code in ("numpy",):
        theirs = cheapest(code)
        equal[code] = theirs and theirs["grid"]
        equal[code + "_speedup"] = round(theirs["us_per_step"] / ours["us_per_step"], 2) if ours and theirs else None
        if ours and not theirs:
            # No numpy grid reached the accuracy: its finest (slowest) grid is still less accurate, so its time
            # per step bounds the time at equal accuracy from below.
            finest = max((r for r in rows if r["code"] == code), key=lambda r: r["nodes"])
            equal[code + "_speedup_lower_bound"] = round(finest["us_per_step"] / ours["us_per_step"], 2)
            equal[code + "_finest"] = {"grid": finest["grid"], "relative_error": round(finest["relative_error"], 5)}
    z, r = kalman_readings(ys)
    m_np, t_np = numpy_kalman_run(z, r, us)
    m_id, t_id = ident_kalman_run(z, r, us, a.repeat)
    figures = {
        "run": {"steps": a.steps, "t_mean_target": a.t_mean, "seed": a.seed, "events": int(np.sum(np.diff(
            (ys != 0).astype(int)) == 1))},
        "reference": {"grid": "384x384", "mean_var_v": reference,
                      "grid_256_relative_difference": mean_var(check_var) / reference - 1},
        "accuracy": a.accuracy,
        "rows": [{k: (round(v, 6) if isinstance(v, float) else v) for k, v in r.items()} for r in rows],
        "equal_accuracy": equal,
        "kalman": {"ident_us_per_step": round(t_id * 1e6, 3), "numpy_us_per_step": round(t_np * 1e6, 3),
                   "speedup": round(t_np / t_id, 1),
                   "final_mean_difference": float(np.max(np.abs(m_np - m_id)))},
    }
    print(json.dumps(figures, indent=1))
    if a.json:
        with open(a.json, "w", encoding="utf-8") as f:
            json.dump(figures, f, indent=1)


if __name__ == "__main__":
    main()
