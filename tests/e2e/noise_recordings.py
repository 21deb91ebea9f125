#!/usr/bin/python3
"""End to end: `sdins noise` on the three measured recordings that have a rest segment.

usage: noise_recordings.py SDINS DATA_DIR WORKDIR

Each data set is imported (as docs/import.md does), then `sdins noise` finds its rest where the
data set's README and docs/import.md say the vehicle rests, and its outputs are checked: the
segments, the readings (finite, each with its interval or an upper bound and a note), the filter
values, and that filter.toml is a valid filter configuration (read back by `sdins noise
--filter-config`). Exit 77 (CTest: skipped) with the reason when the recordings
($SDINS_RECORDINGS_DIR, else DATA_DIR) or convbin are missing.
"""
import functools
import json
import math
import os
import sys

from e2e_common import fresh_dir, need_convbin, need_datasets, recordings_dir, run_sdins  # beside this script

sdins, data, work = sys.argv[1:4]
data = recordings_dir(data)
need_datasets(data, ("gnss-imu-drive", "gnss-imu-walk", "psins-tc"), "set SDINS_RECORDINGS_DIR, docs/data.md")
need_convbin()
fresh_dir(work)
run = functools.partial(run_sdins, sdins, echo=True)


def noise(name, fmt, extra=()):
    log = os.path.join(work, name + ".lcmlog")
    run("import", fmt, os.path.join(data, name), "--log", log, *extra)
    out = os.path.join(work, name)
    run("noise", log, "--out", out, "--no-plots")
    s = json.load(open(os.path.join(out, "summary.json")))
    for ax in s["data"]["axes"]:
        for t in ("white", "bias_instability", "rate_random_walk"):
            r = ax[t]
            assert math.isfinite(r["value"]) and r["value"] > 0 and r["note"], (name, ax["name"], t, r)
            if r["supported"]:
                assert r["lo95"] <= r["value"] <= r["hi95"], (name, ax["name"], t, r)
    # filter.toml is a filter configuration the tools accept (parsed by --filter-config).
    run("noise", log, "--out", out + "-check", "--no-plots", "--filter-config", os.path.join(out, "filter.toml"))
    c = json.load(open(os.path.join(out + "-check", "summary.json")))["configured"]
    v = s["filter_values"]
    assert abs(c["arw_deg_per_rthr"] / float(f"{v['arw_deg_per_rthr']['value']:.4g}") - 1) < 1e-9, (c, v)
    return s, log


def segments(s):
    t0 = s["rest"]["window_t_s"][0]
    return [(g["t_begin_s"] - t0, g["t_end_s"] - t0) for g in s["rest"]["segments"]]


# psins-tc: at rest for the first ~55 s (GNSS speed < 0.08 m/s), a disturbance at 17-19 s
# (docs/import.md, config/datasets/psins-tc.toml): rest found before and after it, none after 57 s.
s, _ = noise("psins-tc", "psins", ("--clip-gnss-to-imu",))
seg = segments(s)
print("psins-tc rest segments [s from the first window]:", seg)
assert s["speed_source"] == "GNSS_RAW"
assert seg and all(b <= 57 for a, b in seg), seg
assert not any(a < 18.0 < b for a, b in seg), seg  # the disturbance at 17-19 s splits the rest
assert sum(b - a for a, b in seg) >= 35, seg
assert s["data"]["axes"][0]["white"]["supported"]  # gyro x: white noise read at 1 s

# gnss-imu-drive: parked at the start (~35 s before it moves, docs/import.md) and at the end.
s, _ = noise("gnss-imu-drive", "rtklib")
seg = segments(s)
print("drive rest segments:", seg)
assert s["speed_source"] == "GNSS_PVT"
assert seg[0][0] < 5 and 15 <= seg[0][1] <= 40, seg
assert all(ax["white"]["supported"] for ax in s["data"]["axes"]), "drive: white noise on every axis"
# Two rests: each analysed alone too; they disagree on some axes (the end rest holds a disturbance).
assert len(s["per_segment"]) == 6 and all(len(r["white"]) == 2 for r in s["per_segment"]), s["per_segment"]
assert any(r["disagree"] for r in s["per_segment"]), "drive: the two rests' noise differs on some axis"

# gnss-imu-walk: the walker stands at the start (~12 s, but moves the IMU by hand: sway) and at the end.
s, _ = noise("gnss-imu-walk", "rtklib")
seg = segments(s)
print("walk rest segments:", seg)
assert seg and seg[-1][1] > 120, seg
print("noise_recordings: all checks passed")
