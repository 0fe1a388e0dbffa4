#!/usr/bin/python3
"""MAP smoother vs cvxopt (Debian python3-cvxopt) on the same problems, T = 10^3 ... 10^6.

Usage: bench/compare_cvxopt.py [path/to/ident] [repeats] [--sizes 1000,10000,...] [--cvxopt-max T] [--json FILE]
(default build/bin/ident, 3 repeats, sizes 10^3 ... 10^6, cvxopt up to T = 10^4; run from the repository root)

Part 1, ident vs cvxopt. Model (as bench/map_smoother_benchmark.cc): x_{t+1} = [[0.99, 0.1], [0, 0.95]] x_t + w,
z_t = x_{t,1} + v_t, f_0 = 1/2|x_0|^2, f_t = 1/2 w'(0.01 I)^-1 w, g = l1 or Huber(kappa = 1). cvxopt solves the
same MAP problem as a sparse QP:
  l1:    min 1/2 x'Px + 1's           s.t.  -s <= z - Hx <= s
  Huber: min 1/2 x'Px + 1/2|a|^2 + 1's  s.t.  -s <= z - Hx - a <= s     (huber(r) = min_a a^2/2 + |r - a|)
with P = A' Qbar^-1 A. Prints both objective values, their relative difference, the solve times and the ratio,
both as wall time and as CPU time (process_time: all threads of the process). Both solvers run in this Python
process: ident through its Python module (ident.smooth, from the build tree next to the ident program:
model parsing, the solve and the conversion of the result), cvxopt's solvers.qp call, each given its data
already in its own types (a numpy array, cvxopt matrices: the conversions are not timed); the "solve_seconds" of
`ident smooth --json` (a new process for every run, without file I/O) is listed as well. Each solver runs
`repeats` times, alternating, and the smallest time of each is kept (the shared machine's load varies by 2x
between runs of the same solve). cvxopt runs only up to --cvxopt-max (its time grows faster than T).

Part 2, scale: a double integrator x_{t+1} = [[1, 1], [0, 1]] x_t + w (unit process noise), z_t = x_{t,1} + v_t
with Laplace v, whose positions reach ~T^1.5 (6e8 at T = 10^6), smoothed with l1, Huber and Gaussian
measurement penalties at every size. Every repeat runs the sizes in turn, so that each size meets the same spells
of machine load, and the fastest run of each is kept. For each: iterations, solve time, the certified relative
gap (relative_gap_bound); for l1 and Huber up to --cvxopt-max cvxopt's objective and time (one run), and at
every size the certificate on a problem of the same size whose optimum is known by construction
(known_optimum_problem: an independent check that dual - bound <= optimum and primal - optimum <= gap + bound);
for the Gaussian model the closed-form optimum by a banded Cholesky solve of the normal equations
(scipy.linalg.solveh_banded), the same check. The time at 10^6 relative to 10^5 shows whether the solve is
linear in T.
"""
import argparse, json, os, random, subprocess, sys, tempfile, time

import numpy as np
from scipy.linalg import solveh_banded
from cvxopt import matrix, spmatrix, solvers

F = [[0.99, 0.1], [0.0, 0.95]]


def make_data(T, seed=42):
    rng = random.Random(seed)
    x = [rng.gauss(0, 1), rng.gauss(0, 1)]
    z = []
    for t in range(T + 1):
        if t > 0:
            x = [F[0][0] * x[0] + F[0][1] * x[1] + 0.1 * rng.gauss(0, 1), F[1][1] * x[1] + 0.1 * rng.gauss(0, 1)]
        v = rng.expovariate(2.0) * (1 if rng.random() < 0.5 else -1)
        if rng.random() < 0.05:
            v += 10 * rng.gauss(0, 1)
        z.append(x[0] + v)
    return z


def make_double_integrator(T, seed=1):
    rng = np.random.default_rng(seed)
    x = np.cumsum(np.cumsum(rng.standard_normal(T + 1)))
    return x + rng.laplace(size=T + 1)


def write_data(z, path):
    with open(path, "w") as f:
        f.write("z\n" + "\n".join("%.17g" % v for v in z) + "\n")


def run_ident_files(ident, mpath, dpath):
    out = subprocess.run([ident, "smooth", "--model", mpath, dpath, "--json"], capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(out.stderr.strip())
    j = json.loads(out.stdout)
    j.pop("x"), j.pop("u"), j.pop("y")
    return j


def run_ident(ident, model, z, tmp):
    mpath, dpath = os.path.join(tmp, "model.json"), os.path.join(tmp, "data.csv")
    with open(mpath, "w") as f:
        json.dump(model, f)
    write_data(z, dpath)
    return run_ident_files(ident, mpath, dpath)


def load_module(ident):
    """The ident Python module of the build tree that holds the ident program (build/bin/ident: build/python)."""
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(ident))), "python"))
    import ident as module
    return module


def run_ident_in_process(module, model, z):
    start, cpu_start = time.perf_counter(), time.process_time()
    j = module.smooth(model, z)
    return j, time.perf_counter() - start, time.process_time() - cpu_start


def stable_model(penalty):
    return {"F": F, "H": [[1, 0]], "initial": {"penalty": "quadratic", "covariance": 1},
            "process": {"penalty": "quadratic", "covariance": 0.01}, "measurement": penalty}


def run_cvxopt(z, huber, F=F, weight=100.0):
    N = len(z)
    nx = 2 * N
    # P = sum_t J_t' W_t J_t: t = 0: W = I on x_0; t >= 1: W = weight I on x_t - F x_{t-1}.
    entries = {}

    def add(i, j, v):
        entries[(i, j)] = entries.get((i, j), 0.0) + v

    for i in range(2):
        add(i, i, 1.0)
    for t in range(1, N):
        # J = [-F, I] on (x_{t-1}, x_t); J'WJ = 100 [F'F, -F'; -F, I]
        a, b = 2 * (t - 1), 2 * t
        for i in range(2):
            for j in range(2):
                add(a + i, a + j, weight * sum(F[k][i] * F[k][j] for k in range(2)))
                add(a + i, b + j, -weight * F[j][i])
                add(b + i, a + j, -weight * F[i][j])
            add(b + i, b + i, weight)
    nv = nx + N + (N if huber else 0)  # x, s, (a)
    if huber:
        for t in range(N):
            add(nx + N + t, nx + N + t, 1.0)
    keys = list(entries.keys())
    P = spmatrix([entries[k] for k in keys], [k[0] for k in keys], [k[1] for k in keys], (nv, nv))
    q = matrix([0.0] * nx + [1.0] * N + ([0.0] * N if huber else []))
    # z - Hx (- a) <= s  ->  -x1 (- a) - s <= -z ;  -(z - Hx (- a)) <= s  ->  x1 (+ a) - s <= z
    V, I, J, h = [], [], [], []
    for t in range(N):
        for sign, row in ((-1.0, 2 * t), (1.0, 2 * t + 1)):
            V += [sign, -1.0]
            I += [row, row]
            J += [2 * t, nx + t]
            if huber:
                V.append(sign)
                I.append(row)
                J.append(nx + N + t)
            h.append(-z[t] if sign < 0 else z[t])
    G = spmatrix(V, I, J, (2 * N, nv))
    solvers.options.update({"show_progress": False, "abstol": 1e-10, "reltol": 1e-10, "feastol": 1e-10,
                            "maxiters": 200})
    h = matrix(h)
    start, cpu_start = time.perf_counter(), time.process_time()
    sol = solvers.qp(P, q, G, h)
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu_start
    return sol["primal objective"], seconds, cpu, sol["status"]


def gaussian_optimum(z):
    """min 1/2|x_0|^2 + sum 1/2|x_t - F x_{t-1}|^2 + sum 1/2 (z_t - x_{t,1})^2, F = [[1, 1], [0, 1]], by a banded
    Cholesky solve of the normal equations in the unknowns (x_{0,1}, x_{0,2}, x_{1,1}, ...), one step of
    iterative refinement with the residual in long double, and the objective at that x in long double (an
    upper bound on the optimum whatever the solve's accuracy: dual <= it is weak duality)."""
    N = len(z)
    Fd = np.array([[1.0, 1.0], [0.0, 1.0]])
    D = np.zeros((N, 2, 2))
    D[:] = np.eye(2)
    D[:-1] += Fd.T @ Fd
    D[:, 0, 0] += 1.0
    n = 2 * N
    ab = np.zeros((4, n))  # upper banded form, bandwidth 3: ab[3 + i - j, j] = A[i, j] for i <= j
    for i in range(2):
        for j in range(i, 2):
            ab[3 + i - j, j::2] = D[:, i, j]
    for i in range(2):  # A[2(t-1) + i, 2t + j] = (-F)[j, i], t >= 1
        for j in range(2):
            ab[3 + i - 2 - j, 2 + j::2] = -Fd[j, i]
    b = np.zeros(n)
    b[0::2] = z
    L = np.longdouble

    def gradient(x):  # A x - b in long double, from the objective's terms
        xl = x.astype(L).reshape(N, 2)
        w = xl.copy()
        w[1:] -= xl[:-1] @ Fd.T.astype(L)
        g = w.copy()
        g[:-1] -= w[1:] @ Fd.astype(L)
        g[:, 0] -= np.asarray(z, dtype=L) - xl[:, 0]
        return g.reshape(-1), w, xl

    x = solveh_banded(ab, b)
    g, _, _ = gradient(x)
    x = x - solveh_banded(ab, g.astype(float))
    _, w, xl = gradient(x)
    r = np.asarray(z, dtype=L) - xl[:, 0]
    return float(L(0.5) * (np.sum(w * w) + np.sum(r * r)))


def known_optimum_problem(T, noise, seed=3):
    """A double-integrator problem with l1 or Huber (kappa = 1) measurements whose optimum is known by
    construction. With w_t = x_t - F x_{t-1} (w_0 = x_0) the process terms' gradient is w_t - F'w_{t+1}
    (w_{T+1} = 0), so x is optimal if w_t - F'w_{t+1} = H'u_t with u_t in dg(z_t - x_t1): in components,
    u_t = w_t1 - w_{t+1,1} and w_t2 = w_{t+1,1} + w_{t+1,2}. The multipliers u_t are chosen backwards in
    time, by a bounded feedback that keeps w of order one (so that the positions grow like T^1.5, as in
    make_double_integrator): half of them at |u| = 1 (a kink of l1, the linear part of Huber), half inside.
    Then x follows from w, and z_t = x_t1 + r_t with r_t in dg*(u_t) (l1: r = 0 inside, sign(u)(1 + e) at
    |u| = 1; Huber: r = u inside, sign(u)(1 + e) beyond). Returns z and the objective at that x in long
    double: an upper bound on the optimum whatever the rounding of x and z, equal to it up to that rounding."""
    rng = np.random.default_rng(seed)
    N = T + 1
    kink = rng.random(N) < 0.5
    noise_u = rng.uniform(-0.5, 0.5, N)
    u = np.zeros(N)
    w = np.zeros((N, 2))
    a_next = c_next = 0.0  # w_{t+1}
    for t in range(N - 1, -1, -1):
        c = c_next + a_next  # w_t2
        want = -(0.3 * c + 0.8 * a_next) + noise_u[t]  # drives w back towards 0
        u[t] = (1.0 if want >= 0 else -1.0) if kink[t] else min(0.99, max(-0.99, want))
        a = a_next + u[t]  # w_t1
        w[t] = (a, c)
        a_next, c_next = a, c
    L = np.longdouble
    Fd = np.array([[1.0, 1.0], [0.0, 1.0]], dtype=L)
    xl = np.zeros((N, 2), dtype=L)
    xl[0] = w[0]
    for t in range(1, N):
        xl[t] = Fd @ xl[t - 1] + w[t].astype(L)
    x = xl.astype(float)
    e = rng.exponential(1.0, N)
    r = np.where(kink, u * (1.0 + e), 0.0 if noise == "l1" else u)
    z = x[:, 0] + r
    xl = x.astype(L)  # the objective at the rounded x
    wl = xl.copy()
    wl[1:] -= xl[:-1] @ Fd.T
    rl = z.astype(L) - xl[:, 0]
    ar = np.abs(rl)
    measurement = ar if noise == "l1" else np.where(ar <= 1, L(0.5) * rl * rl, ar - L(0.5))
    return z, float(L(0.5) * np.sum(wl * wl) + np.sum(measurement))


def bound_holds(run, optimum):
    """dual - bound <= optimum (weak duality) and primal - optimum within the certified gap, up to the
    rounding of the two objectives (1e-15 relative)."""
    slack = 1e-15 * abs(optimum)
    return bool(run["primal"] - run["gap"] - run["gap_error_bound"] <= optimum + slack
                and run["primal"] - optimum <= run["gap"] + run["gap_error_bound"] + slack)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("ident", nargs="?", default="build/bin/ident")
    p.add_argument("repeats", nargs="?", type=int, default=3)
    p.add_argument("--sizes", default="1000,10000,100000,1000000")
    p.add_argument("--cvxopt-max", type=int, default=10000)
    p.add_argument("--json", help="write the figures to this file")
    a = p.parse_args()
    sizes = [int(s) for s in a.sizes.split(",")]
    module = load_module(a.ident)
    figures = {"versus_cvxopt": [], "scale": []}
    print("%-6s %7s %20s %20s %10s %10s %10s %8s %10s %10s %8s" % (
        "noise", "T", "ident primal", "cvxopt primal", "rel diff", "ident [s]", "cvxopt [s]", "ratio",
        "ident cpu", "cvxopt cpu", "ratio"))
    with tempfile.TemporaryDirectory() as tmp:
        for T in sizes:
            z = make_data(T)
            for name, penalty in (("l1", {"penalty": "l1"}), ("huber", {"penalty": "huber", "kappa": 1})):
                t_ours = c_ours = t_theirs = c_theirs = t_cli = c_cli = float("inf")
                theirs, status = None, "not run"
                for _ in range(a.repeats):
                    j, t, c = run_ident_in_process(module, stable_model(penalty), np.asarray(z, dtype=float))
                    t_ours, c_ours = min(t_ours, t), min(c_ours, c)
                    cli = run_ident(a.ident, stable_model(penalty), z, tmp)
                    t_cli, c_cli = min(t_cli, cli["solve_seconds"]), min(c_cli, cli["solve_cpu_seconds"])
                    if T <= a.cvxopt_max:
                        theirs, t, c, status = run_cvxopt(z, name == "huber")
                        t_theirs, c_theirs = min(t_theirs, t), min(c_theirs, c)
                ours = j["primal"]
                row = {"noise": name, "T": T, "ident_primal": ours, "ident_seconds": t_ours, "ident_cpu_seconds": c_ours,
                       "ident_cli_solve_seconds": t_cli, "ident_cli_solve_cpu_seconds": c_cli,
                       "ident_iterations": j["iterations"], "ident_relative_gap_bound": j["relative_gap_bound"]}
                if theirs is not None:
                    row.update({"cvxopt_primal": theirs, "relative_difference": abs(ours - theirs) / abs(theirs),
                                "cvxopt_seconds": t_theirs, "cvxopt_cpu_seconds": c_theirs, "cvxopt_status": status,
                                "speedup_wall": t_theirs / t_ours, "speedup_cpu": c_theirs / max(c_ours, 1e-6)})
                    print("%-6s %7d %20.12f %20.12f %10.2e %10.5f %10.5f %7.1fx %10.5f %10.5f %7.1fx  (cvxopt %s, ident %d it)" % (
                        name, T, ours, theirs, row["relative_difference"], t_ours, t_theirs, row["speedup_wall"],
                        c_ours, c_theirs, row["speedup_cpu"], status, j["iterations"]))
                else:
                    print("%-6s %7d %20.12f %20s %10s %10.5f %10s %8s %10.5f  (ident %d it, gap <= %.1e)" % (
                        name, T, ours, "-", "-", t_ours, "-", "-", c_ours, j["iterations"], j["relative_gap_bound"]))
                figures["versus_cvxopt"].append(row)
                sys.stdout.flush()
        print("\ndouble integrator (positions up to ~T^1.5): certified relative gap, time, Gaussian closed form")
        print("%-6s %8s %5s %10s %10s %12s %16s %10s" % ("noise", "T", "it", "solve [s]", "us/step", "gap bound",
                                                       "reference", "holds/x"))
        # Each size's data are written once; every repeat runs the sizes in turn, so that all sizes meet the
        # same spells of machine load, and the fastest run of each is kept.
        data = {}
        for T in sizes:
            data[T] = (make_double_integrator(T), os.path.join(tmp, "di%d.csv" % T))
            write_data(*data[T])
        for name, penalty in (("l1", {"penalty": "l1"}), ("huber", {"penalty": "huber", "kappa": 1}),
                              ("gauss", {"penalty": "quadratic", "covariance": 1})):
            model = {"F": [[1, 1], [0, 1]], "H": [[1, 0]], "initial": {"penalty": "quadratic", "covariance": 1},
                     "process": {"penalty": "quadratic", "covariance": 1}, "measurement": penalty}
            mpath = os.path.join(tmp, "di_%s.json" % name)
            with open(mpath, "w") as f:
                json.dump(model, f)
            runs = {T: None for T in sizes}
            for _ in range(a.repeats):
                for T in sizes:
                    j = run_ident_files(a.ident, mpath, data[T][1])
                    if runs[T] is None or j["solve_seconds"] < runs[T]["solve_seconds"]:
                        runs[T] = j
            for T in sizes:
                z, best = data[T][0], runs[T]
                row = {"noise": name, "T": T, "iterations": best["iterations"], "solve_seconds": best["solve_seconds"],
                       "solve_cpu_seconds": best["solve_cpu_seconds"], "primal": best["primal"], "gap": best["gap"],
                       "gap_error_bound": best["gap_error_bound"], "relative_gap_bound": best["relative_gap_bound"]}
                check, holds = "", ""
                if name != "gauss" and T <= a.cvxopt_max:  # the same objective by cvxopt, once
                    theirs, t, c, status = run_cvxopt(list(z), name == "huber", F=[[1.0, 1.0], [0.0, 1.0]], weight=1.0)
                    row.update({"cvxopt_primal": theirs, "cvxopt_status": status, "cvxopt_seconds": t,
                                "cvxopt_cpu_seconds": c,
                                "relative_difference": abs(best["primal"] - theirs) / abs(theirs),
                                "speedup_wall": t / best["solve_seconds"],
                                "speedup_cpu": c / max(best["solve_cpu_seconds"], 1e-6)})
                    check = "cvxopt %.1e" % row["relative_difference"]
                    holds = "%.0fx" % row["speedup_wall"]
                if name == "gauss":
                    optimum = gaussian_optimum(z)
                    row.update({"closed_form_optimum": optimum,
                                "closed_form_relative_excess": (best["primal"] - optimum) / abs(optimum),
                                "bound_holds": bound_holds(best, optimum)})
                    check, holds = "%.2e" % row["closed_form_relative_excess"], str(row["bound_holds"])
                else:  # the certificate on a problem of the same size and model with a known optimum
                    zk, optimum = known_optimum_problem(T, name)
                    kpath = os.path.join(tmp, "known.csv")
                    write_data(zk, kpath)
                    k = run_ident_files(a.ident, mpath, kpath)
                    row["known_optimum"] = {"optimum": optimum, "primal": k["primal"], "iterations": k["iterations"],
                                            "relative_excess": (k["primal"] - optimum) / abs(optimum),
                                            "relative_gap_bound": k["relative_gap_bound"],
                                            "bound_holds": bound_holds(k, optimum)}
                    holds = (holds + " " if holds else "") + "known %s" % row["known_optimum"]["bound_holds"]
                print("%-6s %8d %5d %10.4f %10.3f %12.2e %16s %s" % (
                    name, T, best["iterations"], best["solve_seconds"], 1e6 * best["solve_seconds"] / (T + 1),
                    best["relative_gap_bound"], check, holds))
                figures["scale"].append(row)
                sys.stdout.flush()
    models = ["l1", "huber", "gauss"]
    figures["scale"].sort(key=lambda r: (r["T"], models.index(r["noise"])))
    by = {(r["noise"], r["T"]): r for r in figures["scale"]}
    if 100000 in sizes and 1000000 in sizes:
        for key, field in (("time_ratio_1e6_to_1e5", "solve_seconds"), ("cpu_time_ratio_1e6_to_1e5", "solve_cpu_seconds")):
            figures[key] = {name: round(by[(name, 1000000)][field] / by[(name, 100000)][field], 2)
                            for name in ("l1", "huber", "gauss")}
            print("%s at T = 10^6 / at T = 10^5:" % field, figures[key])
    if a.json:
        with open(a.json, "w") as f:
            json.dump(figures, f, indent=1)


if __name__ == "__main__":
    main()
