"""PNG plots of the bench CSVs. matplotlib is optional (``pip install matplotlib``, or the ``plot``
extra); the CSVs never need it.

:func:`write_plots` reads whichever of these are in the directory and writes one PNG beside each:

* ``work_precision.csv`` (instrument, method, setting, cpu_s, nfev, error_rad) →
  ``work_precision.png``: one panel per instrument, error at the end versus CPU time, log-log, one
  series per method (fidelity tier), points labelled with their setting (a work-precision diagram
  in the manner of Hairer, Nørsett & Wanner);
* ``observation_time.csv`` (see ``studies.OBS_HEADER``) and ``systematic_floors.csv`` →
  ``observation_time.png``: rms latitude and Earth-rate errors versus observation time, log-log,
  for the sine fit, Quet's counting and the Cramér–Rao bound, with the mean reported σ, the
  noise-free error and the systematic floors (every correction applied, and each left out);
* ``effect_cost.csv`` (see :mod:`gyro_instrument.bench.effect_cost`) → ``effect_cost.png``: the
  largest angle difference caused by leaving each effect out, per scene and instrument, as
  horizontal bars on a log scale (an exact zero or a missing value is written beside its bar).

CSVs are read with :mod:`csv`; empty cells (None) become ``None``.
"""

import csv
import math
import os

#: Values below this are drawn at this value on log axes (an exact 0 cannot be placed on them).
LOG_FLOOR = 1e-16


def write_plots(out_dir) -> list:
    """Write the PNGs for the CSVs found in ``out_dir``.

    Returns
    -------
    list of str
        Paths written, in the order work-precision, observation time, effect cost (those whose CSV
        exists). ``[]`` when matplotlib is not installed (tell the user ``pip install matplotlib``).
    """
    plt = _pyplot()
    if plt is None:
        return []
    written = []
    for stem, plot in (("work_precision", _plot_work_precision), ("observation_time", _plot_observation_time),
                       ("effect_cost", _plot_effect_cost)):
        src = os.path.join(out_dir, stem + ".csv")
        if not os.path.exists(src):
            continue
        rows = read_csv(src)
        if not rows:
            continue
        dst = os.path.join(out_dir, stem + ".png")
        fig = plot(plt, rows, out_dir)
        try:
            fig.savefig(dst, dpi=110, bbox_inches="tight")
        finally:
            plt.close(fig)
        written.append(dst)
    return written


def _pyplot():
    from gyro_instrument.views.backend import matplotlib_config_dir
    matplotlib_config_dir()
    try:
        import matplotlib
    except ImportError:
        return None
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    return plt


def read_csv(path) -> list:
    """Rows of a CSV as dicts; numeric cells become float, empty cells None, other text stays text."""
    with open(path, newline="") as fh:
        return [{k: _value(v) for k, v in row.items()} for row in csv.DictReader(fh)]


def _value(text):
    if text is None or text == "" or text == "None":
        return None
    try:
        return float(text)
    except ValueError:
        return text


def _pos(x):
    """A value that can go on a log axis (None stays None)."""
    if x is None or not isinstance(x, float) or not math.isfinite(x):
        return None
    return max(abs(x), LOG_FLOOR)


# ----------------------------------------------------------------------------- work-precision
def _plot_work_precision(plt, rows, out_dir=None):
    instruments = list(dict.fromkeys(r["instrument"] for r in rows))
    ncols = min(3, max(len(instruments), 1))
    nrows = max(1, -(-len(instruments) // ncols))
    fig, axes = plt.subplots(nrows, ncols, figsize=(6.0 * ncols, 5.8 * nrows), squeeze=False)
    for ax in axes.flat[len(instruments):]:
        ax.set_visible(False)
    for ax, inst in zip(axes.flat, instruments):
        sub = [r for r in rows if r["instrument"] == inst]
        for method in dict.fromkeys(r["method"] for r in sub):
            pts = sorted((r for r in sub if r["method"] == method and _pos(r["error_rad"]) is not None),
                         key=lambda r: _pos(r["cpu_s"]) or LOG_FLOOR)
            if not pts:
                continue
            cpu = [_pos(r["cpu_s"]) or LOG_FLOOR for r in pts]
            err = [_pos(r["error_rad"]) for r in pts]
            ax.loglog(cpu, err, "o-" if len(pts) > 1 else "s", label=str(method))
            for i, (r, x, y) in enumerate(zip(pts, cpu, err)):
                if r.get("setting"):
                    ax.annotate(str(r["setting"]), (x, y), textcoords="offset points",
                                xytext=(4, 4 if i % 2 == 0 else -9), fontsize=6)
        ax.set_xlabel("CPU time (s)")
        ax.set_ylabel("error at the end (rad)")
        ax.set_title(str(inst), fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.13))
    fig.suptitle("Work-precision by fidelity tier (error against a tight reference vs CPU time)")
    fig.tight_layout()
    return fig


# ----------------------------------------------------------------------------- observation time
def _plot_observation_time(plt, rows, out_dir=None):
    floors_csv = os.path.join(out_dir, "systematic_floors.csv") if out_dir else None
    floors = read_csv(floors_csv) if floors_csv and os.path.exists(floors_csv) else []
    rows = sorted(rows, key=lambda r: r["minutes"] or 0.0)
    panels = [("deg", "latitude error (deg)", "", "latitude_bias_deg"),
              ("rad/s", "Earth-rate error, eq. (10) (rad/s)", "_earth_rate_rad_s", "earth_rate_bias_rad_s")]
    have_n = any(r.get("rms_fit_earth_rate_rad_s") is not None for r in rows)
    fig, axes = plt.subplots(1, 2 if have_n else 1, figsize=(12 if have_n else 7, 7.0), squeeze=False)
    for ax, (unit, ylabel, suffix, floor_key) in zip(axes[0], panels):
        def key(base):
            return (base + suffix) if suffix else (base + "_deg")
        series = ((key("rms_fit"), "sine fit, rms error", "o-"), (key("mean_sigma"), "sine fit, reported σ", "--"),
                  (key("crlb"), "Cramér–Rao bound", "k:"), (key("rms_counting"), "Quet's counting, rms error", "s-"),
                  ("noise_free" + (suffix.replace("_rad_s", "_error_rad_s") if suffix else "_error_deg"),
                   "noise-free error, quet_paris as shipped (the estimator's own floor)", "x-"))
        for k, label, style in series:
            pts = [(r["minutes"], _pos(r.get(k))) for r in rows if r.get("minutes") and _pos(r.get(k)) is not None]
            if pts:
                ax.loglog([a for a, _ in pts], [b for _, b in pts], style, label=label)
        for case in dict.fromkeys((f["left_out"], f["scope"]) for f in floors):
            pts = [(f["minutes"], _pos(f.get(floor_key))) for f in floors
                   if (f["left_out"], f["scope"]) == case and _pos(f.get(floor_key)) is not None]
            if pts:
                left_out, scope = case
                label = (f"floor, every correction: {scope}" if left_out == "none"
                         else f"floor without the {left_out.replace('_', ' ')} correction: {scope}")
                ax.loglog([a for a, _ in pts], [b for _, b in pts], ":" if left_out == "none" else "-.",
                          alpha=0.8, label=label)
        minutes = sorted({r["minutes"] for r in rows if r.get("minutes")})
        if minutes:
            from matplotlib.ticker import NullFormatter
            ax.set_xticks(minutes)
            ax.set_xticklabels([f"{m:g}" for m in minutes])
            ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("observation time per configuration (min)")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.12))
    fig.suptitle("Error versus observation time (quet_paris), with the systematic floors")
    fig.tight_layout()
    return fig


# ----------------------------------------------------------------------------- effect cost
def _plot_effect_cost(plt, rows, out_dir=None):
    rows = [r for r in rows if r.get("effect") and r.get("instrument") and r.get("column")
            and r.get("instrument") != "(combined)"]
    labels, values, texts = [], [], []
    for r in rows:
        labels.append(f"{r['scene']}: {r['effect']} / {r['instrument']}")
        v = r.get("max_abs_diff_rad")
        if isinstance(v, float) and math.isfinite(v) and v > 0:
            values.append(v)
            texts.append(f"{v:.2g}")
        else:
            values.append(LOG_FLOOR)
            texts.append("0" if v == 0.0 else "n/a")
    fig, ax = plt.subplots(figsize=(9, 1.2 + 0.28 * max(len(rows), 1)))
    if rows:
        y = list(range(len(rows)))[::-1]
        scenes = list(dict.fromkeys(r["scene"] for r in rows))
        cmap = plt.get_cmap("tab10")
        colors = [cmap(scenes.index(r["scene"]) % 10) for r in rows]
        ax.barh(y, values, color=colors, log=True)
        ax.set_yticks(y)
        ax.set_yticklabels(labels, fontsize=7)
        for yi, v, t in zip(y, values, texts):
            ax.text(v, yi, " " + t, va="center", fontsize=7)
        ax.set_xlim(left=max(min(values) / 10, LOG_FLOOR / 10), right=max(values) * 30)
    ax.set_xscale("log")
    ax.set_xlabel("largest change of the instrument's angle when the effect is left out (rad)")
    ax.set_title("Effect cost: error made by leaving each effect out")
    ax.grid(True, axis="x", which="both", alpha=0.3)
    fig.tight_layout()
    return fig
