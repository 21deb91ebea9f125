#!/usr/bin/python3
"""End to end: `sdins import` on the three measured data sets, checked against their READMEs.

usage: import_datasets.py SDINS DATA_DIR WORKDIR

For each data set (gnss-imu-drive, gnss-imu-walk with its u-blox log through RTKLIB's convbin,
psins-tc): import with --json, check the counts, time spans and rates the summary reports against
what the data set's README says (and the rejected lines the files really have), then `sdins log
info --json` on the log: the channels (GNSS_PVT included), their types and spans, no rejections.
A damaged copy of the walk's IMU log (NaN, a short line, garbage) must import with those lines
counted, not crash.

Exit 77 (CTest: skipped) with the reason when the recordings ($SDINS_RECORDINGS_DIR, else DATA_DIR:
../shared/data beside the source tree) or convbin are missing.
"""
import functools
import json
import os
import shutil
import sys

from e2e_common import fresh_dir, need_convbin, need_datasets, recordings_dir, run_sdins  # beside this script

sdins, data, work = sys.argv[1:4]
data = recordings_dir(data)
need_datasets(data, ("gnss-imu-drive", "gnss-imu-walk", "psins-tc"),
              "the shared data directory is read in place, set SDINS_RECORDINGS_DIR, docs/data.md")
need_convbin()
fresh_dir(work)
run = functools.partial(run_sdins, sdins)


def near(a, b, tol, what):
    assert abs(a - b) <= tol, f"{what}: {a} not within {tol} of {b}"


def imported(fmt, path, name, *extra):
    log = os.path.join(work, name + ".lcmlog")
    js = os.path.join(work, name + ".json")
    text = run("import", fmt, path, "--log", log, "--json", js, *extra)
    print(text)
    info_text = run("log", "info", log)
    print(info_text)
    info = json.loads(run("log", "info", "--json", log))
    assert info["reader_rejections_total"] == 0, info
    ch = {c["channel"]: c for c in info["channels"]}
    for c in ch.values():
        assert c["wrong_type"] == 0 and c["decode_failed"] == 0 and c["unknown_type"] == 0, c
    return json.load(open(js)), ch, info_text


# --- drive: 100 Hz IMU about 9 minutes, RTKLIB solution at 4 Hz, nearly all RTK fixed.
s, ch, info_text = imported("rtklib", os.path.join(data, "gnss-imu-drive"), "drive")
imu = s["imu"]
assert imu["lines"]["lines"] == 54860 and imu["lines"]["rejected"] == 0, imu["lines"]
assert imu["samples"]["count"] == 54859, imu["samples"]  # trapezoid: n lines -> n - 1 increments
near(imu["samples"]["mean_rate_hz"], 100.0, 0.5, "drive IMU rate")
near(imu["samples"]["span_s"], 9 * 60, 30, "drive IMU span (about 9 minutes)")
near(imu["samples"]["span_s"], imu["tag"]["last_tick_s"] - imu["samples"]["t_first_s"] + imu["tag"]["start_tow_s"], 0.02,
     "IMU span = last tag tick - first interval")
f = imu["first_second_mean_f_body_mps2"]  # parked at the start: gravity on -z body (z down)
near(f[2], -9.81, 0.2, "drive specific force z at rest")
pvt = s["gnss_pvt"]
assert pvt["samples"]["count"] == 2197 and pvt["lines"]["rejected"] == 0, pvt
near(pvt["samples"]["mean_rate_hz"], 4.0, 1e-6, "drive solution rate")
assert pvt["by_quality"]["1"] >= 0.99 * pvt["samples"]["count"], pvt["by_quality"]  # nearly all fixed
assert s["truth"]["samples"]["count"] == pvt["by_quality"]["1"], s["truth"]
assert s["gnss_raw"] is None and s["almanac"] is None  # no raw receiver log in this data set
# GPS time: 2025-07-08 19:34:18.499 GPST is week 2374, Tuesday: 243258.499 s of the week.
assert s["time_scale"]["gps_week0"] == 2374
near(pvt["samples"]["t_first_s"], 243258.499, 1e-6, "drive first solution")
near(imu["samples"]["t_first_s"] - pvt["samples"]["t_first_s"], 3.4, 0.5, "IMU starts 3.4 s after the GNSS")
assert set(ch) == {"IMU", "GNSS_PVT", "TRUTH"}, ch.keys()
assert ch["GNSS_PVT"]["type"] == "sdins.gnss_pvt_t" and ch["GNSS_PVT"]["messages"] == 2197, ch["GNSS_PVT"]
assert "GNSS_PVT" in info_text and "sdins.gnss_pvt_t" in info_text
near(ch["IMU"]["t_first_s"], imu["samples"]["t_first_s"], 1e-9, "log info IMU span")

# --- walk: raw u-blox log through convbin, IMU, RTK solution (two thirds fixed), about 2 minutes.
s, ch, _ = imported("rtklib", os.path.join(data, "gnss-imu-walk"), "walk")
imu = s["imu"]
# The first and the last line of imu_1730.csv are partial (the README says they may be).
assert imu["lines"]["lines"] == 20457 and imu["lines"]["rejected"] == 2, imu["lines"]
assert imu["lines"]["rejected_by_reason"] == {"partial last line (no newline)": 1,
                                              "wrong field count (6, expected 7)": 1}, imu["lines"]
assert imu["samples"]["count"] == 20454
near(imu["samples"]["span_s"], 134.27, 0.01, "walk IMU span (about 2 minutes)")
# The README says 100 Hz; the log (and the source's own imu_1730_sf.csv) has 6-9 ms intervals.
near(imu["samples"]["mean_rate_hz"], 152.3, 1.0, "walk IMU rate")
near(imu["first_second_mean_f_body_mps2"][2], -9.81, 0.3, "walk specific force z at rest (z up sensor)")
pvt = s["gnss_pvt"]
assert pvt["samples"]["count"] == 536 and pvt["lines"]["rejected"] == 0
near(pvt["samples"]["mean_rate_hz"], 4.0, 1e-6, "walk solution rate")
near(pvt["by_quality"]["1"] / 536, 2 / 3, 0.05, "walk fixed share (about two thirds)")
assert pvt["by_quality"]["1"] + pvt["by_quality"]["2"] == 536
raw = s["gnss_raw"]
cb = s["convbin"]
assert cb["rinex_version"] == "3.04" and cb["obs_epochs"] == 536, cb
assert raw["samples"]["count"] == 536, raw
near(raw["samples"]["mean_rate_hz"], 4.0, 1e-6, "walk raw epoch rate")
near(raw["samples"]["t_first_s"], pvt["samples"]["t_first_s"], 0.01, "raw epochs and solutions start together")
assert raw["satellites"] == [2, 8, 10, 15, 18, 23, 24, 27, 32], raw["satellites"]
alm = s["almanac"]
assert alm["written"] == cb["nav_gps_prns"] and len(alm["written"]) >= 4, alm
for fit in alm["fits"]:
    assert fit["written"] and fit["max_pos_err_m"] + fit["max_clock_err_m"] <= 0.1, fit
assert set(ch) == {"IMU", "GNSS_PVT", "TRUTH", "GNSS_RAW", "GPS_ALMANAC"}, ch.keys()
assert ch["GNSS_RAW"]["messages"] == 536 and ch["GPS_ALMANAC"]["messages"] == alm["messages"]
assert ch["TRUTH"]["messages"] == pvt["by_quality"]["1"]
assert s["rejected_lines_total"] == 2

# --- psins: 27280 IMU rows at 200 Hz over 136.4 s; 1707 epochs over 1800 s from 8 satellites.
s, ch, _ = imported("psins", os.path.join(data, "psins-tc"), "psins")
imu = s["imu"]
assert imu["lines"]["lines"] == 27280 and imu["lines"]["rejected"] == 0, imu["lines"]
assert imu["samples"]["count"] == 27280
near(imu["samples"]["mean_rate_hz"], 200.0, 0.01, "psins IMU rate")
near(imu["samples"]["span_s"] + imu["samples"]["dt_s"]["median"], 136.4, 0.01, "psins IMU span")
near(imu["first_second_mean_f_body_mps2"][2], -9.79, 0.05, "psins specific force z at rest (+9.79 up in RFU)")
raw = s["gnss_raw"]
assert raw["samples"]["count"] == 1707 and raw["lines"]["rejected"] == 0, raw
near(raw["samples"]["span_s"], 1800.0, 1e-9, "psins GNSS span")
assert len(raw["satellites"]) == 8, raw["satellites"]
assert s["ephemeris"]["lines"]["accepted"] == 10 and s["ephemeris"]["gps_week"] == 2183, s["ephemeris"]
alm = s["almanac"]
assert alm["written"] == raw["satellites"] and alm["observed_without_ephemeris"] == [], alm
assert all(f["max_pos_err_m"] + f["max_clock_err_m"] <= 0.1 for f in alm["fits"]), alm["fits"]
assert set(ch) == {"IMU", "GNSS_RAW", "GPS_ALMANAC"}, ch.keys()
assert ch["GNSS_RAW"]["t_first_s"] == 183828.0 and ch["IMU"]["t_first_s"] == 185492.5, ch

# Clipping the GNSS to the IMU window (what a replay of the flight software wants).
s2, ch2, _ = imported("psins", os.path.join(data, "psins-tc"), "psins_clip", "--clip-gnss-to-imu")
assert ch2["GNSS_RAW"]["t_first_s"] >= 185491.5, ch2["GNSS_RAW"]
assert s2["gnss_raw"]["clipped_to_imu"] + s2["gnss_raw"]["samples"]["count"] == 1707

# --- Damage: a copy of the walk directory with a NaN line, a short line and garbage in the IMU log.
dmg = os.path.join(work, "walk-damaged")
os.makedirs(dmg)
src = os.path.join(data, "gnss-imu-walk")
lines = open(os.path.join(src, "imu_1730.csv")).read().split("\n")
lines[100] = "nan,0.1,1.0,0.1,0.1,0.1," + lines[100].split(",")[-1]
lines[200] = lines[200][: len(lines[200]) // 2]
lines.insert(300, "\x00\x01garbage\xff")
open(os.path.join(dmg, "imu_1730.csv"), "w", encoding="latin-1").write("\n".join(lines))
for n in ("imu_1730.csv.tag", "gnss_1730_sf.pos"):
    shutil.copy(os.path.join(src, n), dmg)
s, ch, _ = imported("rtklib", dmg, "walk_damaged")
r = s["imu"]["lines"]
assert r["rejected"] == 5, r  # the two partial lines of the original plus three
assert r["rejected_by_reason"]["non-finite value"] == 1, r
assert s["gnss_raw"] is None  # no .ubx copied
print("import_datasets: all checks passed")
