"""Pictures for notebooks (matplotlib): FitResult.plot() and CompareResult.plot()."""

import numpy as np


def _figure(fig, rows, cols, height):
    import matplotlib.pyplot as plt
    if fig is None:
        fig = plt.figure(figsize=(11, height), constrained_layout=True)
    return fig, fig.subplots(rows, cols, squeeze=False)


def plot_fit(result, fig=None):
    """Four panels: (1) validation output, measured vs one-step and simulated; (2) residual auto- and
    cross-correlations with the 99 % band (MATLAB's resid); (3) the parameter trajectories with ±2σ bands;
    (4) the robust weight νβ(t) of every update (1: a sample counted fully, near 0: discounted).
    Panels 3 and 4 need ``ident.fit(..., history=True)``."""
    fig, axes = _figure(fig, 2, 2, 7.5)
    p = result.predictions
    ax = axes[0, 0]
    ax.plot(p["row"], p["measured"], color="black", lw=1, label="measured")
    ax.plot(p["row"], p["one_step"], lw=1, label=f"one-step ({_percent(result.fit_one_step)})")
    if "simulation" in p:
        ax.plot(p["row"], p["simulation"], lw=1, label=f"simulation ({_percent(result.fit_simulation)})")
    ax.set(title=f"validation: {result.structure}, {result.estimator}", xlabel="row")
    ax.legend(loc="best", fontsize="small")

    ax = axes[0, 1]
    analysis = result.residual_analysis
    if analysis and not analysis.get("applies", True):
        ax.text(0.5, 0.5, "no residual correlations: a static regression's rows need not be a time series",
                ha="center", va="center", wrap=True)
        ax.set_axis_off()
    elif analysis:
        band = analysis["band"]
        lags = np.arange(1, len(analysis["autocorrelation"]) + 1)
        ax.stem(lags, analysis["autocorrelation"], basefmt=" ", label="r_ee(τ)")
        for k, (name, values) in enumerate(analysis["cross_correlation"].items()):
            ax.plot(np.arange(len(values)) + 0.15 * (k + 1), values, "o", ms=3, label=f"r_e{name}(τ)")
        ax.axhspan(-band, band, color="grey", alpha=0.2, label="99 % band")
        ax.set(title="residual correlations (validation)", xlabel="lag τ")
        ax.legend(loc="best", fontsize="small")
    else:
        ax.text(0.5, 0.5, "validation part too short for the residual analysis", ha="center", va="center")
        ax.set_axis_off()

    history = result.history
    ax, wax = axes[1, 0], axes[1, 1]
    if history is None:
        for a in (ax, wax):
            a.text(0.5, 0.5, "fit with history=True for the trajectories", ha="center", va="center")
            a.set_axis_off()
        return fig
    rows = np.asarray(history["row"])
    theta, std = np.asarray(history["theta"]), np.asarray(history["theta_std"])
    for i, name in enumerate(result.parameter_names):
        line, = ax.plot(rows, theta[:, i], lw=1, label=name)
        ax.fill_between(rows, theta[:, i] - 2 * std[:, i], theta[:, i] + 2 * std[:, i], color=line.get_color(),
                        alpha=0.15)
    ax.set(title="parameter estimates ± 2σ", xlabel="row")
    ax.legend(loc="best", fontsize="small", ncol=2)
    weight = np.asarray(history["nu"]) * np.asarray(history["weight"])
    wax.plot(rows, weight, ".", ms=2)
    wax.axhline(1.0, color="grey", lw=0.5)
    wax.set(title="robust weight νβ(t) of each sample (low: discounted)", xlabel="row", ylim=(0, None))
    ax.sharex(wax)
    return fig


def plot_compare(frame, fig=None):
    """One-step validation fit per estimator: the mean over trials as a bar, the median, 90th percentile
    and worst trial as marks. Returns the figure."""
    fig, axes = _figure(fig, 1, 1, 3.5)
    ax = axes[0, 0]
    x = np.arange(len(frame))
    ax.bar(x, frame["fit_one_step"], color="tab:blue", alpha=0.6, label="mean over trials")
    ax.plot(x, frame["fit_one_step_median"], "k_", ms=18, label="median")
    ax.plot(x, frame["fit_one_step_min"], "rv", label="worst trial")
    reference = frame.json["reference"]["fit_percent"]["one_step"]
    ax.axhline(reference, color="black", ls="--", lw=1, label="clean-data least squares")
    ax.set_xticks(x, frame["estimator"])
    ax.set(ylabel="one-step fit %", title=f"{frame.json['structure']}: outliers {frame.json['outliers']['rate']:g} "
           f"at {frame.json['outliers']['size']:g}σ, {frame.json['trials']} trial(s)")
    ax.legend(loc="lower right", fontsize="small")
    return fig


def _percent(value):
    return "undefined" if value is None else f"{value:.1f} %"
