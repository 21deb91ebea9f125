#!/usr/bin/python3
"""Plots for `sdins paper`: reads OUT_DIR/summary.json and the per-case statistics CSVs,
writes PNGs into OUT_DIR.

usage: plot_paper.py OUT_DIR

fig16_mis05_15state.png ... fig19_mis15_24state.png
    one per case (the style of the paper's figures 16-19): residual attitude error
    (INS error minus filter estimate) over the Monte Carlo runs, E / N / U panels,
    mean (solid), mean +/- 1 sigma (dashed), filter 1-sigma (dotted, around zero),
    turns shaded.  A case whose misalignment/model is not one of 5"/15" x 15/24 states
    is written as fig_misNN_MMstate.png.
compare_U.png
    per misalignment level: Monte Carlo 1-sigma of the Up (heading) residual, one line
    per filter model, turns shaded - the heading error growth the 24-state model removes.
nees.png
    per case: run-averaged 9-dof navigation NEES against time with its 95% bounds.

When the alignment transient in the first 5% of the run dwarfs the rest, the y axis is scaled to
the rest (panel title says "initial transient clipped").  NaN values are drawn as gaps.
Exit code 1 with a one-line message when summary.json or a CSV is missing or malformed.
"""
import csv
import math
import os
import re
import sys
import warnings

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from plot_io import InputError, load_json, run_script, save_figure  # noqa: E402  (beside this script)

PROG = "plot_paper.py"
DPI = 150
AXES = "ENU"
AXIS_NAME = {"E": "East", "N": "North", "U": "Up (heading)"}
COLUMNS = [
    "t_s", "turning",
    "mean_E_deg", "mean_N_deg", "mean_U_deg",
    "std_E_deg", "std_N_deg", "std_U_deg",
    "filter_sigma_E_deg", "filter_sigma_N_deg", "filter_sigma_U_deg",
    "pos_rms_m", "pos_filter_sigma_m", "vel_rms_mps", "vel_filter_sigma_mps",
    "nees", "nees_att",
]
# The paper's figure numbers for its four cases (misalignment arcsec, model).
PAPER_FIGS = {(5.0, "15"): 16, (5.0, "24"): 17, (15.0, "15"): 18, (15.0, "24"): 19}
MODEL_COLOR = {"15": "C3", "24": "C0", "15c": "C7", "15t": "C1"}
NEES_DOF = 9


# ----------------------------------------------------------------------------- input

def load_summary(out_dir):
    path = os.path.join(out_dir, "summary.json")
    summary = load_json(path)
    if not isinstance(summary, dict) or not isinstance(summary.get("cases"), list) or not summary["cases"]:
        raise InputError(f"{path}: expected an object with a non-empty list 'cases'")
    cases, seen = [], set()
    for i, c in enumerate(summary["cases"]):
        where = f"{path}: cases[{i}]"
        if not isinstance(c, dict):
            raise InputError(f"{where} is not an object")
        for key in ("misalignment_arcsec", "model", "runs", "csv"):
            if key not in c:
                raise InputError(f"{where} has no '{key}'")
        mis = c["misalignment_arcsec"]
        if isinstance(mis, bool) or not isinstance(mis, (int, float)) or not math.isfinite(mis) or mis < 0:
            raise InputError(f"{where}: misalignment_arcsec must be a non-negative number, got {mis!r}")
        model = c["model"]
        # A state count with an optional variant letter: "15", "24", "15c" (conventional), "15t" (tuned).
        if isinstance(model, bool) or not isinstance(model, (str, int)) or \
                not re.fullmatch(r"[0-9]+[a-z]?", str(model).strip()):
            raise InputError(f"{where}: model must be a state count like \"15\", \"24\" or \"15c\", got {model!r}")
        m = re.fullmatch(r"([0-9]+)([a-z]?)", str(model).strip())
        model = str(int(m.group(1))) + m.group(2)
        runs = c["runs"]
        if isinstance(runs, bool) or not isinstance(runs, (int, float)) or runs < 1 or runs != int(runs):
            raise InputError(f"{where}: runs must be a positive integer, got {runs!r}")
        if not isinstance(c["csv"], str) or not c["csv"]:
            raise InputError(f"{where}: csv must be a path string")
        key = (float(mis), model)
        if key in seen:
            raise InputError(f"{where}: duplicate case misalignment {mis:g}\" model {model}")
        seen.add(key)
        bounds = c.get("nees_bounds")
        if bounds is not None:
            if not (isinstance(bounds, list) and len(bounds) == 2):
                raise InputError(f"{where}: nees_bounds must be [low, high], got {bounds!r}")
            if all(isinstance(b, (int, float)) and not isinstance(b, bool) and math.isfinite(b) for b in bounds):
                bounds = (float(bounds[0]), float(bounds[1]))
            else:  # null (NaN written by the C++ side): fall back to the approximation
                bounds = None
        mean_nees = c.get("mean_nees")
        if mean_nees is not None and (isinstance(mean_nees, bool) or not isinstance(mean_nees, (int, float))):
            mean_nees = None
        cases.append({
            "mis": float(mis), "model": model, "runs": int(runs),
            "csv": os.path.join(out_dir, c["csv"]),
            "nees_bounds": bounds, "mean_nees": mean_nees,
        })
    cases.sort(key=lambda c: (c["mis"], int(re.match(r"[0-9]+", c["model"]).group(0)), c["model"]))
    return cases


def parse_float(text):
    text = text.strip()
    if text == "":
        return math.nan
    return float(text)  # accepts nan / inf


def load_csv(path):
    if not os.path.isfile(path):
        raise InputError(f"{path} not found")
    try:
        with open(path, newline="") as f:
            reader = csv.reader(f)
            header = next(reader, None)
            if header is None:
                raise InputError(f"{path} is empty")
            header = [h.strip() for h in header]
            missing = [c for c in COLUMNS if c not in header]
            if missing:
                raise InputError(f"{path}: missing column(s) {', '.join(missing)}")
            rows = []
            for lineno, row in enumerate(reader, start=2):
                if not row or all(not x.strip() for x in row):
                    continue
                if len(row) != len(header):
                    raise InputError(f"{path}:{lineno}: {len(row)} fields, header has {len(header)}")
                values = []
                for name, x in zip(header, row):
                    try:
                        values.append(parse_float(x))
                    except ValueError:
                        raise InputError(f"{path}:{lineno}: non-numeric {name} value {x.strip()!r}")
                rows.append(values)
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise InputError(f"cannot read {path}: {e}")
    if not rows:
        raise InputError(f"{path}: no data rows")
    data = np.array(rows, dtype=float)
    cols = {name: data[:, i] for i, name in enumerate(header)}
    if not np.all(np.isfinite(cols["t_s"])):
        raise InputError(f"{path}: t_s has missing or non-finite values")
    return cols


# ----------------------------------------------------------------------------- helpers

def mis_tag(mis):
    return f"{int(mis):02d}" if mis == int(mis) else f"{mis:05.2f}".rstrip("0").replace(".", "p")


def case_figure_name(case):
    num = PAPER_FIGS.get((case["mis"], case["model"]))
    if num is not None:
        return f"fig{num}_mis{mis_tag(case['mis'])}_{case['model']}state.png"
    return f"fig_mis{mis_tag(case['mis'])}_{case['model']}state.png"


def turn_spans(t, turning):
    """(start, end) times of the turns, each epoch covering +/- half a sample."""
    dt = float(np.nanmedian(np.diff(t))) if len(t) > 1 else 1.0
    on = np.nan_to_num(turning, nan=0.0) > 0.5
    spans, start = [], None
    for i, flag in enumerate(on):
        if flag and start is None:
            start = i
        elif not flag and start is not None:
            spans.append((t[start] - dt / 2, t[i - 1] + dt / 2))
            start = None
    if start is not None:
        spans.append((t[start] - dt / 2, t[-1] + dt / 2))
    return spans


def shade_turns(ax, spans):
    for a, b in spans:
        ax.axvspan(a, b, color="0.88", lw=0, zorder=0)


def add_arcsec_axis(ax):
    sec = ax.secondary_yaxis("right", functions=(lambda d: d * 3600.0, lambda s: s / 3600.0))
    sec.set_ylabel("[arcsec]", fontsize=8)
    sec.tick_params(labelsize=8)


def clip_initial_transient(ax, curves, lower=None):
    """curves: list of (t, y).  If the first 5% of the run (alignment transient) dwarfs the rest,
    scale the y axis to the rest so the steady-state error stays readable.  True when clipped."""
    t_all = np.concatenate([np.asarray(t) for t, _ in curves])
    t_cut = t_all.min() + 0.05 * (t_all.max() - t_all.min())
    vals_all = np.concatenate([np.asarray(y) for _, y in curves])
    vals_late = np.concatenate([np.asarray(y)[np.asarray(t) >= t_cut] for t, y in curves])
    vals_all, vals_late = vals_all[np.isfinite(vals_all)], vals_late[np.isfinite(vals_late)]
    if vals_late.size == 0:
        return False
    lo, hi = vals_late.min(), vals_late.max()
    if lower is not None:
        lo = min(lo, lower)
    if hi == lo or max(vals_all.max(), hi) - min(vals_all.min(), lo) <= 3 * (hi - lo):
        return False
    pad = 0.1 * (hi - lo)
    ax.set_ylim(lower if lower is not None else lo - pad, hi + pad)
    return True


def finite_or_none(x):
    return x if x is not None and math.isfinite(x) else None


def approx_nees_bounds(runs, dof=NEES_DOF):
    """95% two-sided bounds of the run-averaged NEES: chi2(dof*runs)/runs (Wilson-Hilferty)."""
    k = dof * runs
    z = 1.959963984540054
    q = lambda zz: k * (1 - 2 / (9 * k) + zz * math.sqrt(2 / (9 * k))) ** 3 / runs  # noqa: E731
    return q(-z), q(z)


def case_label(case):
    return f"{case['model']}-state"


# ----------------------------------------------------------------------------- figures

def plot_case(out_dir, case, d):
    t = d["t_s"]
    spans = turn_spans(t, d["turning"])
    color = MODEL_COLOR.get(case["model"], "C2")
    fig, axes = plt.subplots(3, 1, figsize=(10, 8.5), sharex=True)
    for ax, k in zip(axes, AXES):
        shade_turns(ax, spans)
        mean, std, fsig = d[f"mean_{k}_deg"], d[f"std_{k}_deg"], d[f"filter_sigma_{k}_deg"]
        ax.axhline(0.0, color="0.5", lw=0.6, zorder=1)
        ax.fill_between(t, mean - std, mean + std, color=color, alpha=0.10, lw=0, zorder=1)
        ax.plot(t, mean, color=color, lw=1.4, label="mean", zorder=4)
        ax.plot(t, mean + std, color=color, lw=1.0, ls="--", label="mean ± 1σ (Monte Carlo)", zorder=3)
        ax.plot(t, mean - std, color=color, lw=1.0, ls="--", zorder=3)
        ax.plot(t, fsig, color="k", lw=0.7, ls=":", label="± filter 1σ", zorder=2)
        ax.plot(t, -fsig, color="k", lw=0.7, ls=":", zorder=2)
        clipped = clip_initial_transient(ax, [(t, mean + std), (t, mean - std), (t, fsig), (t, -fsig)])
        ax.set_ylabel(f"phi_{k} [deg]")
        ax.set_title(AXIS_NAME[k] + ("  (initial transient clipped)" if clipped else ""),
                     fontsize=9, loc="left", pad=3)
        ax.grid(alpha=0.3)
        ax.ticklabel_format(axis="y", style="plain", useOffset=False)
        add_arcsec_axis(ax)
    axes[0].legend(loc="upper left", fontsize=8, ncol=3, framealpha=0.9)
    axes[-1].set_xlabel("time [s]  (turns shaded)")
    if t[-1] > t[0]:
        axes[-1].set_xlim(t[0], t[-1])
    num = PAPER_FIGS.get((case["mis"], case["model"]))
    prefix = f"Fig. {num}: " if num is not None else ""
    fig.suptitle(f"{prefix}residual attitude error, gyro misalignment {case['mis']:g}\" (1σ), "
                 f"{case['model']}-state filter, {case['runs']} Monte Carlo runs", fontsize=11)
    fig.tight_layout()
    name = case_figure_name(case)
    save_figure(fig, os.path.join(out_dir, name), dpi=DPI)
    plt.close(fig)
    return name


def plot_compare_u(out_dir, cases, data):
    levels = sorted({c["mis"] for c in cases})
    fig, axes = plt.subplots(len(levels), 1, figsize=(10, 3.2 * len(levels) + 0.8), sharex=True, squeeze=False)
    axes = axes[:, 0]
    for ax, mis in zip(axes, levels):
        group = [c for c in cases if c["mis"] == mis]
        d0 = data[id(group[0])]
        shade_turns(ax, turn_spans(d0["t_s"], d0["turning"]))
        for c in group:
            d = data[id(c)]
            std = d["std_U_deg"]
            finite = std[np.isfinite(std)]
            final = f", final {finite[-1]:.4f}°" if finite.size else ", no data"
            ax.plot(d["t_s"], std, color=MODEL_COLOR.get(c["model"], None), lw=1.4,
                    label=f"{case_label(c)} ({c['runs']} runs{final})")
        ax.set_ylim(bottom=0)
        clipped = clip_initial_transient(ax, [(data[id(c)]["t_s"], data[id(c)]["std_U_deg"]) for c in group],
                                         lower=0)
        ax.set_ylabel("1σ of phi_U [deg]")
        ax.set_title(f"gyro misalignment {mis:g}\" (1σ)" + ("  (initial transient clipped)" if clipped else ""),
                     fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(loc="upper left", fontsize=8)
        add_arcsec_axis(ax)
    axes[-1].set_xlabel("time [s]  (turns shaded)")
    t_all = np.concatenate([data[id(c)]["t_s"] for c in cases])
    if t_all.max() > t_all.min():
        axes[-1].set_xlim(t_all.min(), t_all.max())
    fig.suptitle("Up (heading) residual error, Monte Carlo 1σ: 15-state filters (15, 15c, 15t) vs 24-state filter",
                 fontsize=11)
    fig.tight_layout()
    save_figure(fig, os.path.join(out_dir, "compare_U.png"), dpi=DPI)
    plt.close(fig)
    return "compare_U.png"


def plot_nees(out_dir, cases, data):
    n = len(cases)
    fig, axes = plt.subplots(n, 1, figsize=(10, 2.2 * n + 1.0), sharex=True, squeeze=False)
    axes = axes[:, 0]
    for ax, c in zip(axes, cases):
        d = data[id(c)]
        t, nees = d["t_s"], d["nees"]
        shade_turns(ax, turn_spans(t, d["turning"]))
        if c["nees_bounds"] is not None:
            lo, hi = c["nees_bounds"]
            bound_note = ""
        else:
            lo, hi = approx_nees_bounds(c["runs"])
            bound_note = " (approx.)"
        color = MODEL_COLOR.get(c["model"], "C2")
        ax.plot(t, nees, color=color, lw=1.0, label="run-averaged NEES")
        ax.axhline(NEES_DOF, color="0.3", lw=0.8, ls=":", label=f"expected {NEES_DOF}")
        ax.axhline(lo, color="k", lw=0.9, ls="--", label=f"95% bounds [{lo:.2f}, {hi:.2f}]{bound_note}")
        ax.axhline(hi, color="k", lw=0.9, ls="--")
        finite = nees[np.isfinite(nees)]
        mean_nees = finite_or_none(c["mean_nees"])
        if mean_nees is None and finite.size:
            mean_nees = float(finite.mean())
        inside = f", {100.0 * np.mean((finite >= lo) & (finite <= hi)):.0f}% of epochs inside" if finite.size else ""
        mean_txt = f"mean {mean_nees:.2f}" if mean_nees is not None else "no data"
        ax.set_title(f"{c['mis']:g}\" misalignment, {case_label(c)}, {c['runs']} runs: {mean_txt}{inside}",
                     fontsize=9)
        # Log scale when the NEES runs far outside the bounds, so the bounds stay readable.
        if finite.size and finite.min() > 0 and finite.max() > 5 * hi:
            ax.set_yscale("log")
        ax.set_ylabel("NEES")
        ax.grid(alpha=0.3, which="both")
        ax.legend(loc="upper left", fontsize=7, ncol=3, framealpha=0.9)
    axes[-1].set_xlabel("time [s]  (turns shaded)")
    t_all = np.concatenate([data[id(c)]["t_s"] for c in cases])
    if t_all.max() > t_all.min():
        axes[-1].set_xlim(t_all.min(), t_all.max())
    fig.suptitle(f"Navigation NEES ({NEES_DOF} dof: position, velocity, attitude), averaged over the runs",
                 fontsize=11)
    fig.tight_layout()
    save_figure(fig, os.path.join(out_dir, "nees.png"), dpi=DPI)
    plt.close(fig)
    return "nees.png"


# ----------------------------------------------------------------------------- main

def main(argv):
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        print(f"usage: {PROG} OUT_DIR   (OUT_DIR holds summary.json and the case CSVs)", file=sys.stderr)
        return 2 if len(argv) != 2 else 0
    out_dir = argv[1]
    if not os.path.isdir(out_dir):
        raise InputError(f"{out_dir} is not a directory")
    cases = load_summary(out_dir)
    data = {id(c): load_csv(c["csv"]) for c in cases}  # validate everything before drawing
    jobs = list(range(len(cases))) + ["compare_U", "nees"]
    _DRAW.update(out_dir=out_dir, cases=cases, data=data)
    written = draw_all(jobs)
    print(f"{PROG}: wrote {', '.join(written)} in {out_dir}")
    return 0


# What the figure workers draw from: set before they are forked, so that they inherit it.
_DRAW = {}


def draw_one(job):
    """One figure: a case's (its index) or one of the two comparisons; returns its file name."""
    out_dir, cases, data = _DRAW["out_dir"], _DRAW["cases"], _DRAW["data"]
    if job == "compare_U":
        return plot_compare_u(out_dir, cases, data)
    if job == "nees":
        return plot_nees(out_dir, cases, data)
    return plot_case(out_dir, cases[job], data[id(cases[job])])


def draw_all(jobs):
    """The figures in the order of jobs, drawn by one forked worker per core (each figure is
    independent: its own file, put in place whole by save_figure); an error in any is raised
    here. One core or one job: drawn in this process."""
    workers = min(len(jobs), os.cpu_count() or 1)
    if workers < 2:
        return [draw_one(j) for j in jobs]
    import multiprocessing  # noqa: PLC0415  (only when there is a second core)

    with multiprocessing.get_context("fork").Pool(workers) as pool:
        return pool.map(draw_one, jobs, chunksize=1)


if __name__ == "__main__":
    warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN slices etc.: plotted as gaps
    run_script(PROG, main)
