#!/usr/bin/python3
"""MAP smoother vs cvxopt (Debian python3-cvxopt) on the same problems, T = 10^2, 10^3, 10^4.

Usage: bench/compare_cvxopt.py [path/to/ident] [repeats]   (default build/bin/ident, 3; run from the repository root)

Model (as bench/map_smoother_benchmark.cc): x_{t+1} = [[0.99, 0.1], [0, 0.95]] x_t + w, z_t = x_{t,1} + v_t,
f_0 = 1/2|x_0|^2, f_t = 1/2 w'(0.01 I)^-1 w, g = l1 or Huber(kappa = 1). cvxopt solves the same MAP problem
as a sparse QP:
  l1:    min 1/2 x'Px + 1's           s.t.  -s <= z - Hx <= s
  Huber: min 1/2 x'Px + 1/2|a|^2 + 1's  s.t.  -s <= z - Hx - a <= s     (huber(r) = min_a a^2/2 + |r - a|)
with P = A' Qbar^-1 A. Prints both objective values, their relative difference, the solve times (ident: the
"solve_seconds" of `ident smooth --json`, without file I/O; cvxopt: the solvers.qp call) and the ratio,
both as wall time and as CPU time (process_time / std::clock; steadier on a loaded machine). Each solver runs
`repeats` times, alternating, and the smallest time of each is kept (the shared machine's load varies by 2x
between runs of the same solve).
"""
import json, os, random, subprocess, sys, tempfile, time

from cvxopt import matrix, spmatrix, solvers

IDENT = sys.argv[1] if len(sys.argv) > 1 else "build/bin/ident"
REPEATS = int(sys.argv[2]) if len(sys.argv) > 2 else 3
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


def run_ident(z, penalty, tmp):
    model = {"F": F, "H": [[1, 0]], "initial": {"penalty": "quadratic", "covariance": 1},
             "process": {"penalty": "quadratic", "covariance": 0.01}, "measurement": penalty}
    mpath, dpath = os.path.join(tmp, "model.json"), os.path.join(tmp, "data.csv")
    with open(mpath, "w") as f:
        json.dump(model, f)
    with open(dpath, "w") as f:
        f.write("z\n" + "\n".join("%.17g" % v for v in z) + "\n")
    out = subprocess.run([IDENT, "smooth", "--model", mpath, dpath, "--json"], check=True, capture_output=True, text=True)
    j = json.loads(out.stdout)
    return j["primal"], j["solve_seconds"], j["solve_cpu_seconds"], j["iterations"]


def run_cvxopt(z, huber):
    N = len(z)
    nx = 2 * N
    # P = sum_t J_t' W_t J_t: t = 0: W = I on x_0; t >= 1: W = 100 I on x_t - F x_{t-1}.
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
                add(a + i, a + j, 100.0 * sum(F[k][i] * F[k][j] for k in range(2)))
                add(a + i, b + j, -100.0 * F[j][i])
                add(b + i, a + j, -100.0 * F[i][j])
            add(b + i, b + i, 100.0)
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
    start, cpu_start = time.perf_counter(), time.process_time()
    sol = solvers.qp(P, q, G, matrix(h))
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu_start
    return sol["primal objective"], seconds, cpu, sol["status"]


def main():
    print("%-6s %7s %20s %20s %10s %10s %10s %8s %10s %10s %8s" % (
        "noise", "T", "ident primal", "cvxopt primal", "rel diff", "ident [s]", "cvxopt [s]", "ratio",
        "ident cpu", "cvxopt cpu", "ratio"))
    with tempfile.TemporaryDirectory() as tmp:
        for T in (100, 1000, 10000):
            z = make_data(T)
            for name, penalty in (("l1", {"penalty": "l1"}), ("huber", {"penalty": "huber", "kappa": 1})):
                t_ours = c_ours = t_theirs = c_theirs = float("inf")
                for _ in range(REPEATS):
                    ours, t, c, iters = run_ident(z, penalty, tmp)
                    t_ours, c_ours = min(t_ours, t), min(c_ours, c)
                    theirs, t, c, status = run_cvxopt(z, name == "huber")
                    t_theirs, c_theirs = min(t_theirs, t), min(c_theirs, c)
                print("%-6s %7d %20.12f %20.12f %10.2e %10.5f %10.5f %7.1fx %10.5f %10.5f %7.1fx  (cvxopt %s, ident %d it)" % (
                    name, T, ours, theirs, abs(ours - theirs) / abs(theirs), t_ours, t_theirs, t_theirs / t_ours,
                    c_ours, c_theirs, c_theirs / max(c_ours, 1e-6), status, iters))
                sys.stdout.flush()


if __name__ == "__main__":
    main()
