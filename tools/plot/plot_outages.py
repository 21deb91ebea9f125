#!/usr/bin/python3
"""The GNSS outages of a scored replay (`sdins replay --outages L P F --score-json S.json
--score-plot OUT.png`): horizontal and vertical error against the reference vs the time since each
outage began, one line per outage, the filter's own horizontal 1-sigma at each outage's end as a
marker, and the RMS over the outages at their end.

usage: plot_outages.py SCORE.json OUT.png
"""
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from plot_io import OutputError, save_figure  # noqa: E402  (beside this script)


def main(score_path, out):
    with open(score_path) as f:
        s = json.load(f)
    g = s.get("outages")
    if not g or not g["windows"]:
        raise SystemExit(f"{score_path}: no outages scored (replay with --outages and a reference on TRUTH)")
    fig, (ah, av) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    cmap = plt.get_cmap("viridis")
    n = len(g["windows"])
    for i, w in enumerate(g["windows"]):
        if not w["curve"]:
            continue
        t = [c[0] for c in w["curve"]]
        colour = cmap(i / max(1, n - 1))
        style = "-" if w["complete"] else ":"
        label = f"outage {w['index']} (t_s {w['start_t_s']:.0f})" + ("" if w["complete"] else ", incomplete")
        ah.plot(t, [c[1] for c in w["curve"]], style, color=colour, label=label)
        av.plot(t, [c[2] for c in w["curve"]], style, color=colour)
        if w["end_horizontal_sigma_m"] is not None and w["end_since_start_s"] is not None:
            ah.plot([w["end_since_start_s"]], [w["end_horizontal_sigma_m"]], "x", color=colour)
    eh = g.get("end_horizontal")
    ref = s["reference"]["label"]
    what = "unlabelled reference" if ref is None else f"{ref.get('kind', '?')} ({ref.get('source', '?')})"
    title = f"GNSS withheld {g['length_s']:g} s every {g['period_s']:g} s: error against the {what}"
    if eh:
        title += f"\nat the outages' end: horizontal RMS {eh['rms_m']:.2f} m, max {eh['max_m']:.2f} m over {g['complete']}"
    ah.set_title(title, fontsize=10)
    ah.set_ylabel("horizontal error [m]  (x: filter 1-sigma)")
    av.set_ylabel("vertical error [m]")
    av.set_xlabel("time since the outage began [s]")
    for a in (ah, av):
        a.grid(True, alpha=0.3)
    av.axhline(0.0, color="k", lw=0.5)
    if n <= 12:
        ah.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    save_figure(fig, out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    try:
        main(sys.argv[1], sys.argv[2])
    except OutputError as e:
        print(f"plot_outages.py: {e}", file=sys.stderr)
        sys.exit(1)
    except (OSError, ValueError, KeyError) as e:
        print(f"plot_outages.py: {sys.argv[1]}: {e}", file=sys.stderr)
        sys.exit(1)
