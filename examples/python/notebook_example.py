"""ident in a notebook, cell by cell: fit a real record, see what the robust estimator
discounts, compare estimators on injected outliers, and run an estimator on a live stream.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/notebook_example.py [OUTPUT_DIR]
"""

import os
import sys

import matplotlib

matplotlib.use("Agg")  # in a notebook, leave the backend alone
import numpy as np

import ident

out = sys.argv[1] if len(sys.argv) > 1 else "."

# %% The hair-dryer record, with 5 % of its estimation outputs moved by 20 noise standard deviations.
data = ident.datasets.load("dryer")
rng = np.random.default_rng(7)
rows = rng.choice(500, size=25, replace=False)
data.loc[rows, "y"] += 20 * 0.04 * rng.choice([-1, 1], size=25)

# %% Least squares and the Kárný–Hangos Cauchy estimator on the same corrupted record.
for estimator in ("rls", "cauchy"):
    result = ident.fit(data, output="y", inputs=["u"], na=2, nb=2, nk=3, estimator=estimator, history=True)
    print(f"{estimator:7s} one-step fit {result.fit_one_step:6.2f} %  theta {np.round(result.theta, 4)}")
    result.plot().savefig(os.path.join(out, f"dryer_{estimator}.png"), dpi=80)

# %% Which samples did the robust estimator discount? (weight νβ well below 1)
weight = result.history["nu"] * result.history["weight"]
discounted = result.history["row"][weight < 0.2].astype(int)
print(f"cauchy discounted {len(discounted)} samples; {len(set(discounted) & set(rows + 1))} of them are "
      "injected outliers")

# %% Estimators side by side over 10 outlier draws, scored on the clean validation half.
table = ident.compare("dryer", estimators=["rls", "cauchy", "student:3", "huber", "cauchy-ml"], trials=10)
print(table[["estimator", "kind", "fit_one_step", "fit_one_step_min", "theta_distance"]].to_string(index=False))
table.plot().savefig(os.path.join(out, "dryer_compare.png"), dpi=80)

# %% A streaming estimator keeps its state between calls, as in a control loop.
est = ident.Cauchy(2)
for t in range(200):
    z = rng.normal(size=2)
    est.update(z @ [0.5, -2.0] + 0.01 * rng.standard_cauchy(), z)
print(f"streamed estimate {np.round(est.parameters, 3)} ± {np.round(np.sqrt(np.diag(est.covariance)), 3)}")
