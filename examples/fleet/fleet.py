"""A fleet of simulated plants refitted on Dask: one ARX(2,2,1) model per plant, least squares against
the robust Cauchy estimator, and the distribution of their parameter errors.

Every plant drifts slowly around its own parameters and 2 % of its output samples are glitches of 20
noise standard deviations. Each record goes to ident.distributed.fit_many as a DataFrame; the errors are
measured against the plant's mean parameters over the record.

    PYTHONPATH=build/python /usr/bin/python3 examples/fleet/fleet.py [--plants 1000] [--rows 2000]
        [--scheduler-file FILE] [--output DIR]

Without --scheduler-file a local cluster with one worker per core runs the fits; with it, the cluster that
`dask scheduler --scheduler-file FILE` and `dask worker --scheduler-file FILE` started.
"""

import argparse
import os

import numpy as np
import pandas as pd

import ident
import ident.distributed as idd


def simulate_plant(seed, rows):
    """One plant's record and its mean parameters (a1, a2, b1, b2)."""
    rng = np.random.default_rng(seed)
    poles = rng.uniform(0.5, 0.9, size=2) * np.exp(1j * rng.uniform(0, 0.5) * np.array([1, -1]))
    a = np.real(np.poly(poles))[1:]                     # a1, a2 of a stable plant
    b = rng.uniform(0.5, 1.5, size=2)
    drift = np.cumsum(rng.normal(scale=2e-4, size=(rows, 4)), axis=0)   # a slow random walk
    theta = np.concatenate([a, b]) + drift - drift.mean(axis=0)
    u = np.sign(rng.normal(size=rows))                   # a binary excitation
    y = np.zeros(rows)
    sigma = 0.05
    for t in range(2, rows):
        y[t] = -theta[t, 0] * y[t - 1] - theta[t, 1] * y[t - 2] + theta[t, 2] * u[t - 1] + theta[t, 3] * u[t - 2]
        y[t] += sigma * rng.normal()
    measured = y.copy()
    glitches = rng.choice(rows, size=rows // 50, replace=False)          # 2 % of the samples
    measured[glitches] += 20 * sigma * rng.choice([-1.0, 1.0], size=glitches.size)
    frame = pd.DataFrame({"u": u, "y": measured})
    frame.attrs["name"] = f"plant {seed}"
    return frame, theta.mean(axis=0)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--plants", type=int, default=1000)
    p.add_argument("--rows", type=int, default=2000)
    p.add_argument("--scheduler-file", help="connect to this cluster instead of starting a local one")
    p.add_argument("--output", default=".", help="folder for fleet_errors.png")
    args = p.parse_args()

    plants = [simulate_plant(seed, args.rows) for seed in range(args.plants)]
    records = [frame for frame, _ in plants]
    truth = np.array([theta for _, theta in plants])
    client = None
    if args.scheduler_file:
        from dask.distributed import Client
        client = Client(scheduler_file=args.scheduler_file)
    structure = dict(output="y", inputs=["u"], na=2, nb=2, nk=1, split=1, detrend="none")
    errors = {}
    for estimator in ("rls", "cauchy"):
        table = idd.fit_many(records, dict(structure, estimator=estimator), client=client)
        ok = table["status"] == "ok"
        theta = np.stack(table.loc[ok, "theta"].to_numpy())
        errors[estimator] = np.linalg.norm(theta - truth[ok.to_numpy()], axis=1) / np.linalg.norm(
            truth[ok.to_numpy()], axis=1)
        e = errors[estimator]
        print(f"{estimator:7s} {ok.sum()} of {len(table)} plants fitted; relative parameter error median "
              f"{np.median(e):.4f}, 90 % {np.quantile(e, 0.9):.4f}, worst {e.max():.4f}")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 3.5), constrained_layout=True)
    bins = np.logspace(np.log10(min(e.min() for e in errors.values())),
                       np.log10(max(e.max() for e in errors.values())), 40)
    for name, e in errors.items():
        ax.hist(e, bins=bins, alpha=0.6, label=f"{name} (median {np.median(e):.3f})")
    ax.set(xscale="log", xlabel="‖θ̂ − θ‖ / ‖θ‖ per plant", ylabel="plants",
           title=f"{args.plants} plants, 2 % glitches of 20σ, drifting parameters")
    ax.legend()
    path = os.path.join(args.output, "fleet_errors.png")
    fig.savefig(path, dpi=90)
    print(f"wrote {path}")
    if client is not None:
        client.close()


if __name__ == "__main__":
    main()
