#!/usr/bin/python3
"""Plots for `sdins analyze`: reads the CSV files and analysis.json in DIR, writes PNGs there.

bank_turn.png  attitude error (E, N, U) for each gyro misalignment alone, turns shaded
               (the style of the paper's figures 11-13)
rotation.png   single-axis rotation: simulated error (solid) against the closed form (dashed)
               for 5 and 10 arcsec (the style of figures 2-5)
"""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from plot_io import OutputError, save_figure  # noqa: E402  (beside this script)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0].keys()} if rows else {}


def shade_turns(ax, t, roll):
    start = None
    for ti, r in zip(t, roll):
        if abs(r) > 1.0 and start is None:
            start = ti
        elif abs(r) <= 1.0 and start is not None:
            ax.axvspan(start, ti, color="0.9", lw=0)
            start = None
    if start is not None:
        ax.axvspan(start, t[-1], color="0.9", lw=0)


def plot_bank_turn(d, summary):
    comps = ["xy", "xz", "yx", "yz", "zx", "zy"]
    fig, axes = plt.subplots(3, 2, figsize=(13, 10), sharex=True)
    for ax, c in zip(axes.T.flat, comps):
        s = read_csv(os.path.join(d, f"bank_turn_{c}.csv"))
        shade_turns(ax, s["t_s"], s["roll_deg"])
        ax.plot(s["t_s"], s["phi_E_arcsec"], label="phi_E", lw=1)
        ax.plot(s["t_s"], s["phi_N_arcsec"], label="phi_N", lw=1)
        ax.plot(s["t_s"], s["phi_U_arcsec"], label="phi_U (heading)", lw=1.6, color="k")
        info = summary["bank_turn"][c]
        verdict = "accumulates" if info["accumulates"] else "does not accumulate"
        ax.set_title(f"gamma_{c} = {info['gamma_arcsec']:g}\": phi_U {info['u_error_per_turn_arcsec']:+.1f}\"/turn, {verdict}",
                     fontsize=10)
        ax.set_ylabel("attitude error [arcsec]")
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]  (turns shaded)")
    axes[0][0].legend(loc="upper left", fontsize=8)
    fig.suptitle(f"Bank-to-turn, free inertial, each gyro misalignment alone ({summary['scenario']['name']})")
    fig.tight_layout()
    save_figure(fig, os.path.join(d, "bank_turn.png"), dpi=110)
    plt.close(fig)


def plot_rotation(d, summary):
    cases = summary["single_axis_rotation"]
    pairs = []
    for c in cases:
        key = (c["axis"], c["component"])
        if key not in pairs:
            pairs.append(key)
    fig, axes = plt.subplots(len(pairs) // 2, 2, figsize=(13, 3.2 * (len(pairs) // 2)), sharex=True)
    for ax, (axis, comp) in zip(axes.flat, pairs):
        for c in cases:
            if (c["axis"], c["component"]) != (axis, comp):
                continue
            s = read_csv(os.path.join(d, f"rotation_{c['case']}.csv"))
            for k, col in zip("ENU", ["C0", "C1", "C2"]):
                sim = s[f"phi_{k}_sim_arcsec"]
                if max(abs(v) for v in sim) < 0.02 * c["gamma_arcsec"]:
                    continue
                ax.plot(s["t_s"], sim, color=col, lw=1.4,
                        label=f"phi_{k} sim, {c['gamma_arcsec']:g}\"")
                ax.plot(s["t_s"], s[f"phi_{k}_formula_arcsec"], color="k", lw=0.8, ls="--")
        ax.set_title(f"rotation about body {axis}, gamma_{comp}  (dashed: closed form)", fontsize=10)
        ax.set_ylabel("attitude error [arcsec]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.suptitle("Single-axis rotation at 10 deg/s with one gyro misalignment (5 and 10 arcsec)")
    fig.tight_layout()
    save_figure(fig, os.path.join(d, "rotation.png"), dpi=110)
    plt.close(fig)


def main():
    if len(sys.argv) != 2:
        print("usage: plot_analysis.py DIR", file=sys.stderr)
        return 2
    d = sys.argv[1]
    with open(os.path.join(d, "analysis.json")) as f:
        summary = json.load(f)
    plot_bank_turn(d, summary)
    plot_rotation(d, summary)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except OutputError as e:
        print(f"plot_analysis.py: error: {e}", file=sys.stderr)
        sys.exit(1)
