"""ident.fit, ident.compare, ident.smooth, ident.logcondens and ident.datasets: the same numbers as the
command line's JSON (to 1e-12), least squares as numpy computes it, and the R logcondens reference."""

import json
import math
import os

import numpy as np
import pandas as pd
import pytest

import ident


def assert_same_json(a, b, path="", skip=()):
    """Equal structure and keys; numbers to 1e-12 relative (absolute near 0)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and list(a) == list(b), f"{path}: keys {list(a)} != {list(b)}"
        for key in a:
            if key not in skip:
                assert_same_json(a[key], b[key], f"{path}.{key}", skip)
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), f"{path}: lengths differ"
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same_json(x, y, f"{path}[{i}]", skip)
    elif isinstance(a, float) or isinstance(b, float):
        assert b is not None and math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-12), f"{path}: {a} != {b}"
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


ARX = ["--output", "y", "--input", "u", "--na", "2", "--nb", "2", "--nk", "3"]
CASES = [
    ("dryer", ARX, dict(output="y", inputs=["u"], na=2, nb=2, nk=3)),
    ("gas_furnace", ARX, dict(output="y", inputs="u", na=2, nb=[2], nk=3)),
    ("stackloss", ["--output", "stack_loss", "--regressors", "air_flow,water_temp,acid_conc", "--intercept",
                   "--split", "1"],
     dict(output="stack_loss", regressors=["air_flow", "water_temp", "acid_conc"], intercept=True, split=1)),
]


@pytest.mark.parametrize("estimator", ["rls", "cauchy", "student:3", "huber", "cauchy-ml"])
@pytest.mark.parametrize("record,args,kwargs", CASES, ids=[c[0] for c in CASES])
def test_fit_equals_the_command_line_json(cli, record, args, kwargs, estimator):
    result = ident.fit(record, estimator=estimator, **kwargs)
    expected = cli("fit", record, *args, "--estimator", estimator, "--json")
    got = result.to_dict()
    assert list(got) == list(expected)
    assert_same_json(expected, got)
    np.testing.assert_array_equal(result.theta, expected["theta"])


def test_fit_options_passes_and_forgetting_reach_the_estimator(cli):
    result = ident.fit("gas_furnace", output="y", inputs=["u"], na=2, nb=2, nk=3, estimator="cauchy", passes=3,
                       clean_regressors=False, lock_in_threshold=0.25)
    expected = cli("fit", "gas_furnace", *ARX, "--estimator", "cauchy", "--passes", "3", "--clean-regressors", "off",
                   "--lock-in-threshold", "0.25", "--json")
    assert_same_json(expected, result.to_dict())
    assert result.passes == 3
    result = ident.fit("dryer", output="y", inputs=["u"], na=2, nb=2, nk=3, forgetting=0.99, split=0.7)
    assert_same_json(cli("fit", "dryer", *ARX, "--forgetting", "0.99", "--split", "0.7", "--json"), result.to_dict())


def test_dataframe_dict_and_csv_path_give_the_same_fit():
    frame = ident.datasets.load("dryer")
    kwargs = dict(output="y", inputs=["u"], na=2, nb=2, nk=3, estimator="cauchy")
    a = ident.fit(frame, **kwargs).to_dict()
    b = ident.fit({c: frame[c].to_numpy() for c in frame.columns}, **kwargs).to_dict()
    c = ident.fit(ident.datasets.path("dryer"), **kwargs).to_dict()
    for d in (a, b, c):
        d.pop("data")
    assert a == b == c


def test_rls_fit_is_least_squares_on_the_detrended_arx_regression():
    frame = ident.datasets.load("dryer")
    n_est = len(frame) // 2
    y = frame["y"].to_numpy()[:n_est]
    u = frame["u"].to_numpy()[:n_est]
    y, u = y - y.mean(), u - u.mean()
    t = np.arange(4, n_est)  # t0 = max(na, nb + nk - 1) = 4
    Z = np.column_stack([-y[t - 1], -y[t - 2], u[t - 3], u[t - 4]])
    batch = np.linalg.lstsq(Z, y[t], rcond=None)[0]
    result = ident.fit(frame, output="y", inputs=["u"], na=2, nb=2, nk=3)
    np.testing.assert_allclose(result.theta, batch, rtol=1e-9)


def test_a_bundled_record_without_structure_uses_its_suggestion():
    result = ident.fit("telef", estimator="cauchy-ml")
    assert result.structure == "static(year)+intercept" and result.split == 1
    # The batch Cauchy ML reference of the record (R, datasets/README.md): -218.73 + 0.11229·year.
    np.testing.assert_allclose(result.theta, [-218.73, 0.11229], rtol=2e-4)


def test_history_and_predictions_for_the_plots():
    rls = ident.fit("dryer", output="y", inputs=["u"], na=2, nb=2, nk=3, history=True)
    np.testing.assert_allclose(rls.history["theta"][-1], rls.theta, rtol=1e-12)
    result = ident.fit("dryer", output="y", inputs=["u"], na=2, nb=2, nk=3, estimator="cauchy", history=True)
    h = result.history
    assert len(h["row"]) == result.updates and h["theta"].shape == (result.updates, 4)
    # The history is the recursion's; an end-of-data restart (dryer: yes) replaces its last estimate by a
    # nearby one of higher likelihood.
    assert any(e["end_of_data"] for e in result.lock_in["events"])
    assert np.all(np.abs(h["theta"][-1] - result.theta) <= 3 * np.asarray(result.theta_std))
    assert (h["theta_std"] >= 0).all() and np.isfinite(h["weight"]).all()
    p = result.predictions
    assert len(p["row"]) == result.samples_validation
    scored = np.isfinite(p["one_step"])
    e = p["measured"][scored] - p["one_step"][scored]
    fit = 100 * (1 - np.linalg.norm(e) / np.linalg.norm(p["measured"][scored] - p["measured"][scored].mean()))
    assert fit == pytest.approx(result.fit_one_step, abs=1e-9)


def test_compare_returns_a_frame_with_the_command_line_numbers(cli):
    frame = ident.compare("dryer", estimators=["rls", "cauchy", "huber"], trials=3)
    expected = cli("compare", "dryer", "--estimators", "rls,cauchy,huber", "--trials", "3", "--json")
    assert_same_json(expected, frame.json, skip=("ns_per_update", "data"))
    assert isinstance(frame, ident.CompareResult) and isinstance(frame, pd.DataFrame)
    assert list(frame["estimator"]) == [e["estimator"] for e in expected["estimators"]]
    for _, row in frame.iterrows():
        e = next(x for x in expected["estimators"] if x["estimator"] == row["estimator"])
        assert row["fit_one_step"] == pytest.approx(e["fit_percent"]["one_step"], rel=1e-12)
        assert row["kind"] == e["kind"]
        np.testing.assert_allclose(row[expected["parameter_names"]].to_numpy(float), e["theta"], rtol=1e-12)


def test_compare_scores_on_the_clean_rows():
    frame = ident.compare("stackloss", estimators=["rls", "cauchy"], trials=1)
    data = ident.datasets.load("stackloss")
    X = np.column_stack([np.ones(len(data)), data[["air_flow", "water_temp", "acid_conc"]].to_numpy()])
    y = data["stack_loss"].to_numpy()
    for _, row in frame.iterrows():
        theta = row[["intercept", "air_flow", "water_temp", "acid_conc"]].to_numpy(float)
        fit = 100 * (1 - np.linalg.norm(y - X @ theta) / np.linalg.norm(y - y.mean()))
        assert row["fit_one_step"] == pytest.approx(fit, abs=1e-8)


def test_smooth_and_logcondens_equal_the_command_line(cli, source_dir):
    model_path = os.path.join(source_dir, "examples", "duality", "tracking_huber.json")
    data_path = os.path.join(source_dir, "examples", "duality", "tracking.csv")
    with open(model_path, encoding="utf-8") as f:
        model = json.load(f)
    z = pd.read_csv(data_path)["z"].to_numpy()
    result = ident.smooth(model, z)
    expected = cli("smooth", "--model", model_path, data_path, "--json")
    np.testing.assert_allclose(result["x"], expected["x"], rtol=1e-12, atol=1e-12)
    assert result["primal"] == pytest.approx(expected["primal"], rel=1e-12)
    assert result["gap"] <= 1e-6 * max(1.0, abs(result["primal"]))
    assert result["status"] == expected["status"] == "converged"
    for key in ("kkt_residual", "gap_error_bound", "relative_gap_bound"):
        assert result[key] == pytest.approx(expected[key], rel=1e-9), key
    # The certificate bounds primal − optimum, and the optimum is at least the dual objective.
    assert result["primal"] - result["dual"] <= result["gap"] + result["gap_error_bound"]


def test_logcondens_matches_the_r_reference_and_its_optimality_conditions(source_dir):
    data = os.path.join(source_dir, "tests", "density", "data")
    samples = pd.read_csv(os.path.join(data, "gamma200_samples.csv"))["x"].to_numpy()
    knots = pd.read_csv(os.path.join(data, "gamma200_knots.csv"))
    mle = ident.logcondens(samples)
    # R's logcondens stops at a looser tolerance: the same knots, the log-density to 1e-3, and the
    # characterisation of the MLE (Dümbgen, Hüsler & Rufibach, Thm 2.4) to 1e-8.
    np.testing.assert_allclose(mle["knots"], knots["knot"], rtol=1e-9)
    np.testing.assert_allclose(mle["knot_phi"], knots["phi"], atol=1e-3)
    assert mle["max_directional_derivative"] <= 1e-8 and mle["mass_error"] <= 1e-8
    np.testing.assert_allclose(np.sum(mle["weights"] * mle["phi"]) * mle["n"], mle["loglik"], rtol=1e-12)


def test_datasets():
    assert {"dryer", "gas_furnace", "stackloss", "telef"} <= set(ident.datasets.names())
    frame = ident.datasets.load("gas_furnace")
    assert list(frame.columns)[-2:] == ["u", "y"] or {"u", "y"} <= set(frame.columns)
    assert ident.datasets.info("stackloss")["structure"]["intercept"] is True
    with pytest.raises(ValueError, match="no bundled dataset 'nope'"):
        ident.datasets.info("nope")


def test_bad_input_raises_value_error_with_the_library_message(tmp_path):
    frame = ident.datasets.load("dryer")
    with pytest.raises(ValueError, match="no column 'q'"):
        ident.fit(frame, output="q", inputs=["u"])
    with pytest.raises(ValueError, match="split"):
        ident.fit(frame, output="y", inputs=["u"], split=1.5)
    with pytest.raises(ValueError, match="unknown estimator"):
        ident.fit(frame, output="y", inputs=["u"], estimator="nope")
    with pytest.raises(ValueError, match="unknown option 'colour'"):
        ident.fit(frame, output="y", inputs=["u"], colour=1)
    bad = frame.copy()
    bad.loc[10, "u"] = np.nan
    with pytest.raises(ValueError, match="row 11, column 'u'"):
        ident.fit(bad, output="y", inputs=["u"])
    missing = ident.fit(bad, output="y", inputs=["u"], missing=True)
    assert missing.rejected >= 1
    path = tmp_path / "broken.csv"
    path.write_text("y,u\n1,2\n3,x\n")
    with pytest.raises(ValueError, match="broken.csv"):
        ident.fit(str(path), output="y", inputs=["u"])
    with pytest.raises(ValueError, match="no file or bundled dataset"):
        ident.fit("nope", output="y", inputs=["u"])
    with pytest.raises(ValueError, match="give output"):
        ident.fit(frame)


def test_the_readme_python_example_runs_as_written(source_dir):
    with open(os.path.join(source_dir, "README.md"), encoding="utf-8") as f:
        text = f.read()
    blocks = text.split("```python\n")
    assert len(blocks) == 2, "README.md has exactly one ```python block"
    code = blocks[1].split("```")[0]
    assert len([l for l in code.splitlines() if l.strip()]) == 3
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)
    assert namespace["result"].estimator == "cauchy"


def test_a_robust_fit_predicts_around_its_own_operating_point():
    # Gross errors in the estimation part move the plain mean of y, not the robust fit's offset (the mean
    # after a Hampel filter); the predictions use the offset the fit subtracted.
    frame = ident.datasets.load("gas_furnace")
    frame.loc[7:147:20, "y"] += 100.0
    clean_mean = ident.datasets.load("gas_furnace")["y"].iloc[:148].mean()
    result = ident.fit(frame, output="y", inputs=["u"], na=2, nb=2, nk=3, estimator="cauchy")
    assert abs(result.detrend_means["y"] - clean_mean) < 0.02
    assert abs(frame["y"].iloc[:148].mean() - clean_mean) > 5
    p = result.predictions
    scored = np.isfinite(p["one_step"])
    e = p["measured"][scored] - p["one_step"][scored]
    fit = 100 * (1 - np.linalg.norm(e) / np.linalg.norm(p["measured"][scored] - p["measured"][scored].mean()))
    assert fit == pytest.approx(result.fit_one_step, abs=1e-9)
