"""ident.fit(experiment_column=): least squares on each experiment's own regressor rows (numpy), the
command line's --experiment-column JSON, and the straddling regressors of one record differing."""

import numpy as np
import pandas as pd

import ident


def _experiment(n, seed, level):
    rng = np.random.default_rng(seed)
    u = np.sign(rng.standard_normal(n))
    e = 0.1 * rng.standard_normal(n)
    y = np.zeros(n)
    for t in range(n):
        y[t] = (1.5 * y[t - 1] - 0.7 * y[t - 2] + u[t - 1] + 0.5 * u[t - 2] if t >= 2 else 0.0) + e[t]
    return u, y + level


def _frame():
    parts = [_experiment(200, 1, 0.0), _experiment(150, 2, 3.0)]
    return parts, pd.DataFrame({"run": np.repeat([7, 8], [200, 150]),
                                "u": np.concatenate([p[0] for p in parts]),
                                "y": np.concatenate([p[1] for p in parts])})


KWARGS = dict(output="y", inputs=["u"], na=2, nb=2, nk=1, split=1, detrend="none")


def test_experiment_column_is_least_squares_without_straddling_rows(cli, tmp_path):
    parts, frame = _frame()
    rows, target = [], []
    for u, y in parts:
        for t in range(2, len(y)):
            rows.append([-y[t - 1], -y[t - 2], u[t - 1], u[t - 2]])
            target.append(y[t])
    ls = np.linalg.lstsq(np.array(rows), np.array(target), rcond=None)[0]
    result = ident.fit(frame, experiment_column="run", **KWARGS)
    np.testing.assert_allclose(result.theta, ls, rtol=0, atol=1e-12)
    assert result.experiments == [{"name": "7", "rows": [1, 200]}, {"name": "8", "rows": [201, 350]}]
    assert result.updates == 198 + 148

    one = ident.fit(frame, **KWARGS)
    assert one.updates == 348
    assert np.max(np.abs(one.theta - ls)) > 1e-4

    path = tmp_path / "runs.csv"
    frame.to_csv(path, index=False, float_format="%.17g")
    expected = cli("fit", str(path), "--output", "y", "--input", "u", "--na", "2", "--nb", "2", "--nk", "1",
                   "--split", "1", "--detrend", "none", "--experiment-column", "run", "--json")
    got = result.to_dict()
    assert list(got) == list(expected)
    assert got["experiments"] == expected["experiments"]
    np.testing.assert_allclose(got["theta"], expected["theta"], rtol=1e-12)
    for kind in ("one_step", "simulation"):
        np.testing.assert_allclose(got["fit_percent"][kind], expected["fit_percent"][kind], rtol=1e-12)
    predictions = result.predictions
    assert np.isnan(predictions["one_step"][200]) and np.isnan(predictions["one_step"][201])
    assert np.isfinite(predictions["one_step"][202])
