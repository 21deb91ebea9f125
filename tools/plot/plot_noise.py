#!/usr/bin/python3
"""Plot for `sdins noise`: the overlapping Allan deviation of every gyro and accelerometer axis
over the rest segments, with the 95% intervals, the fitted IEEE Std 952 model, the reading lines
(slope -1/2 through N at 1 s, the floor 0.664 B, slope +1/2 through K at 3 s) and the
simulator's IMU model (the scenario's grade, and set to the terms read); below, the rest
detector's window statistics with the thresholds and the rest segments.

usage: plot_noise.py NOISE_JSON OUT_PNG
"""
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from plot_io import OutputError, save_figure  # noqa: E402  (beside this script)

DEG = math.pi / 180.0


def scale(axis):
    # gyro in deg/h, accelerometers in mg
    return (3600.0 / DEG, "deg/h") if axis["name"].startswith("gyro") else (1e3 / 9.80665, "mg")


def allan_panel(ax, axis, sims):
    k, unit = scale(axis)
    c = axis["curve"]
    tau = [p["tau_s"] for p in c]
    adev = [p["adev"] * k for p in c]
    lo = [p["lo95"] * k for p in c]
    hi = [min(p["hi95"], 1e30) * k for p in c]
    ax.fill_between(tau, lo, hi, color="C0", alpha=0.2, lw=0, label="data, 95%")
    ax.loglog(tau, adev, "C0.-", lw=1, ms=3, label="data")
    ax.loglog(tau, [p["model_adev"] * k for p in c], "k--", lw=0.8, label="fitted model")
    floor = 0.2 * min(lo + adev)
    for name, (an, style) in sims.items():
        sc = [a for a in an["axes"] if a["name"] == axis["name"]][0]["curve"]
        y = [p["adev"] * k for p in sc]
        if max(y) < floor:  # e.g. a navigation-grade scenario without white noise: say so, keep the scale
            ax.text(0.02, 0.02, name + ": below the plot (max %.2g %s)" % (max(y), unit), transform=ax.transAxes,
                    fontsize=6, color=style[:2])
            continue
        ax.loglog([p["tau_s"] for p in sc], y, style, lw=0.9, label=name)
    w, b, r = axis["white"], axis["bias_instability"], axis["rate_random_walk"]
    t0, t1 = tau[0], tau[-1]
    if w["supported"]:
        ax.loglog([t0, t1], [w["value"] * k / math.sqrt(t) for t in (t0, t1)], "C2:", lw=1, label="N (slope -1/2)")
    if b["supported"]:
        ax.axhline(b["value"] * 0.6643 * k, color="C3", ls=":", lw=1, label="0.664 B")
    if r["supported"]:
        ax.loglog([t0, t1], [r["value"] * k * math.sqrt(t / 3.0) for t in (t0, t1)], "C4:", lw=1, label="K (slope +1/2)")
    ax.set_ylim(floor, 5.0 * max(adev))
    ax.set_title(axis["name"] + ("" if axis["fit"]["adequate"] else " (model fit NOT adequate)"), fontsize=9)
    ax.set_ylabel("Allan deviation [" + unit + "]", fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    ax.tick_params(labelsize=7)


def main(src, out):
    with open(src) as f:
        j = json.load(f)
    axes = j["data"]["axes"]
    sims = {"sim: scenario " + j["sim_grade"]["scenario"]: (j["sim_grade"]["analysis"], "C1-"),
            "sim: terms read": (j["sim_fitted"]["analysis"], "C5-")}
    fig = plt.figure(figsize=(13, 10))
    gs = fig.add_gridspec(3, 3, height_ratios=[1, 1, 0.8])
    for i, axis in enumerate(axes):
        ax = fig.add_subplot(gs[i // 3, i % 3])
        allan_panel(ax, axis, sims)
        if i >= 3:
            ax.set_xlabel("tau [s]", fontsize=8)
        if i == 0:
            ax.legend(fontsize=6, loc="lower left")
    rest = j["rest"]
    ax = fig.add_subplot(gs[2, :])
    t = rest["window_t_s"]
    t = [x - t[0] for x in t]
    ax.semilogy(t, rest["window_rate_std_radps"], "C0", lw=0.8, label="rate scatter [rad/s]")
    ax.semilogy(t, rest["window_sf_std_mps2"], "C1", lw=0.8, label="|f| scatter [m/s^2]")
    ax.axhline(rest["threshold"]["rate_std_radps"], color="C0", ls="--", lw=0.8)
    ax.axhline(rest["threshold"]["sf_std_mps2"], color="C1", ls="--", lw=0.8)
    t_base = rest["window_t_s"][0]
    for s in rest["segments"]:
        ax.axvspan(s["t_begin_s"] - t_base, s["t_end_s"] - t_base, color="C2", alpha=0.2)
    ax.set_xlabel("time from the log's first IMU window [s]   (green: rest segments; dashed: thresholds)", fontsize=8)
    ax.set_ylabel("window std", fontsize=8)
    ax.legend(fontsize=7, loc="upper right")
    ax.grid(True, which="both", alpha=0.3)
    fig.suptitle("sdins noise: " + j["log"] + " (%.1f s of rest, tau0 %.4g s)" % (j["data"]["rest_s"], j["data"]["tau0_s"]),
                 fontsize=10)
    fig.tight_layout()
    save_figure(fig, out, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: plot_noise.py NOISE_JSON OUT_PNG")
    try:
        main(sys.argv[1], sys.argv[2])
    except (OutputError, OSError, KeyError, ValueError) as e:
        print(f"plot_noise.py: {e}", file=sys.stderr)
        sys.exit(1)
