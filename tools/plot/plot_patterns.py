#!/usr/bin/python3
"""Figure of `sdins paper --patterns`: reads OUT_DIR/patterns.json, writes OUT_DIR/patterns.png.

usage: plot_patterns.py OUT_DIR

patterns.png
    left: the ratio 24-state / 15-state of the final residual 1-sigma for E, N and U per turn
    pattern (below 1: the 24-state filter is better), with the acceptance's U limit 0.6;
    right: the final E and U residual 1-sigma of both filters per pattern.
Exit code 1 with a one-line message when patterns.json is missing or malformed.
"""
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from plot_io import InputError, load_json, run_script, save_figure  # noqa: E402  (beside this script)

PROG = "plot_patterns.py"


def load(out_dir):
    path = os.path.join(out_dir, "patterns.json")
    j = load_json(path)
    pats = j.get("patterns") if isinstance(j, dict) else None
    if not isinstance(pats, list) or not pats:
        raise InputError(f"{path}: expected a non-empty list 'patterns'")
    for i, p in enumerate(pats):
        try:
            for ax in "ENU":
                for v in (p["ratio_24_15"][ax], p["models"]["15"]["final_residual_sigma_deg"][ax],
                          p["models"]["24"]["final_residual_sigma_deg"][ax]):
                    if not isinstance(v, (int, float)) or not math.isfinite(v):
                        raise InputError(f"{path}: patterns[{i}]: non-finite value")
            str(p["name"])
        except (KeyError, TypeError) as e:
            raise InputError(f"{path}: patterns[{i}] lacks {e}")
    return j


def main(argv):
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        print(f"usage: {PROG} OUT_DIR   (OUT_DIR holds patterns.json)", file=sys.stderr)
        return 2 if len(argv) != 2 else 0
    j = load(argv[1])
    pats = j["patterns"]
    names = [p["name"].replace("_", " ") for p in pats]
    x = np.arange(len(pats))
    fig, (a, b) = plt.subplots(1, 2, figsize=(13, 4.8))
    w = 0.26
    for k, (ax_name, color) in enumerate(zip("ENU", ("C2", "C4", "C0"))):
        vals = [p["ratio_24_15"][ax_name] for p in pats]
        bars = a.bar(x + (k - 1) * w, vals, w, color=color, label=f"{ax_name} ratio 24/15")
        for r, v in zip(bars, vals):
            a.text(r.get_x() + r.get_width() / 2, v, f"{v:.2f}", ha="center", va="bottom", fontsize=7)
    a.axhline(1.0, color="0.4", lw=0.8)
    a.axhline(0.6, color="C0", lw=0.8, ls="--", label="U limit 0.6 (paper's case)")
    top = max(max(p["ratio_24_15"][k] for k in "ENU") for p in pats)
    a.set_ylim(0, max(1.0, top) * 1.3)  # room for the legend above the bars
    a.set_xticks(x, names, fontsize=8)
    a.set_ylabel("final residual 1σ, 24-state / 15-state")
    a.set_title(f"gyro misalignment {j.get('misalignment_arcsec', 0):g}\" (1σ), {j.get('runs', '?')} runs per pattern",
                fontsize=10)
    a.legend(fontsize=8, ncol=2, loc="upper left")
    a.grid(alpha=0.3, axis="y")
    for k, (model, ax_name, style) in enumerate([("15", "E", "C3"), ("24", "E", "C0"), ("15", "U", "C3"),
                                                 ("24", "U", "C0")]):
        vals = [p["models"][model]["final_residual_sigma_deg"][ax_name] for p in pats]
        b.bar(x + (k - 1.5) * 0.2, vals, 0.2, color=style, alpha=1.0 if ax_name == "U" else 0.45,
              label=f"{model}-state {ax_name}")
    b.set_xticks(x, names, fontsize=8)
    b.set_ylabel("final residual 1σ [deg]")
    b.set_title("final E (light) and U (dark) residual 1σ", fontsize=10)
    b.legend(fontsize=8, ncol=2)
    b.grid(alpha=0.3, axis="y")
    fig.suptitle("Which turn patterns make the 24-state filter worth it", fontsize=11)
    fig.tight_layout()
    save_figure(fig, os.path.join(argv[1], "patterns.png"), dpi=150)
    plt.close(fig)
    print(f"{PROG}: wrote patterns.png in {argv[1]}")
    return 0


if __name__ == "__main__":
    run_script(PROG, main)
