#!/usr/bin/python3
"""Plots for `sdins diagnose --report DIR`: reads baseline.csv, extended.csv and diagnosis.json in
DIR, writes PNGs there.

innovations.png  pseudorange and pseudorange-rate innovation RMS per epoch, baseline vs extended
heading.png      heading (vertical-axis attitude) error against truth/reference, baseline vs extended
estimates.png    each added parameter converging, with its 1-sigma band
"""
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from plot_io import OutputError, save_figure  # noqa: E402  (beside this script)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    out = {}
    for k in (rows[0].keys() if rows else []):
        out[k] = [float(r[k]) if r[k] not in ("", None) else math.nan for r in rows]
    return out


def main(d):
    base = read_csv(os.path.join(d, "baseline.csv"))
    ext = read_csv(os.path.join(d, "extended.csv"))
    with open(os.path.join(d, "diagnosis.json")) as f:
        j = json.load(f)
    name = j["extended_model"]["name"]

    fig, axes = plt.subplots(2, 1, figsize=(11, 7), sharex=True)
    # Loosely coupled runs (GNSS solutions) have position/velocity innovations instead.
    pvt = j.get("gnss_source") == "pvt"
    keys = (("pos_rms_m", "position", "m"), ("vel_rms_mps", "velocity", "m/s")) if pvt else \
        (("pr_rms_m", "pseudorange", "m"), ("prr_rms_mps", "pseudorange rate", "m/s"))
    for ax, (key, what, unit) in zip(axes, keys):
        ax.plot(base["t_s"], base[key], lw=0.8, label="baseline " + j["baseline"])
        ax.plot(ext["t_s"], ext[key], lw=0.8, label="extended " + name)
        ax.set_ylabel(what + " innovation RMS [" + unit + "]")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right")
    axes[1].set_xlabel("time [s]")
    fig.tight_layout()
    save_figure(fig, os.path.join(d, "innovations.png"), dpi=110)
    plt.close(fig)

    if any(not math.isnan(v) for v in base.get("heading_err_deg", [])):
        fig, ax = plt.subplots(figsize=(11, 4))
        ax.plot(base["t_s"], base["heading_err_deg"], lw=0.8, label="baseline " + j["baseline"])
        ax.plot(ext["t_s"], ext["heading_err_deg"], lw=0.8, label="extended " + name)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("heading error [deg]")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right")
        fig.tight_layout()
        save_figure(fig, os.path.join(d, "heading.png"), dpi=110)
        plt.close(fig)

    states = j["extended_model"]["added_states"]
    if states:
        units = {}
        for fnd in j["findings"]:
            key = fnd["effect"] + ("." + fnd["component"] if fnd["component"] else "")
            units[key] = fnd["unit"]
        fig, axes = plt.subplots(len(states), 1, figsize=(11, 2.6 * len(states)), sharex=True, squeeze=False)
        for ax, s in zip(axes[:, 0], states):
            t, x, sg = ext["t_s"], ext[s], ext[s + "_sigma"]
            ax.plot(t, x, lw=1.0, label="estimate")
            ax.fill_between(t, [a - b for a, b in zip(x, sg)], [a + b for a, b in zip(x, sg)], alpha=0.25,
                            label="1 sigma")
            ax.set_ylabel(s + " [" + units.get(s, "") + "]")
            ax.grid(True, alpha=0.3)
            ax.legend(loc="upper right")
        axes[-1, 0].set_xlabel("time [s]")
        fig.tight_layout()
        save_figure(fig, os.path.join(d, "estimates.png"), dpi=110)
        plt.close(fig)


if __name__ == "__main__":
    try:
        main(sys.argv[1])
    except OutputError as e:
        print(f"plot_diagnosis.py: error: {e}", file=sys.stderr)
        sys.exit(1)
