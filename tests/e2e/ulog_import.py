#!/usr/bin/python3
"""End to end: `sdins import ulog` on the two PX4 logs of ../shared/data/px4-ulog.

usage: ulog_import.py SDINS DATA_DIR WORKDIR

For each log: the import's summary (what the log is from its info messages, counts per stream,
the boot-clock fit, the leap seconds, the reference's label beside the log in LOG.json), `sdins log
info` (no rejections), and the frame conventions checked on the data: the mean specific force of
the first second (body FRD) against the gravity PX4's own attitude predicts there, and (SITL) the
GNSS fixes against PX4's position estimate. A damaged copy (cut short, garbage inside) must
import with the damage counted, not crash.

Exit 77 (CTest: skipped) with the reason when the logs ($SDINS_RECORDINGS_DIR/px4-ulog, else
DATA_DIR/px4-ulog) are missing.
"""
import csv
import functools
import json
import math
import os
import random
import subprocess
import sys

from e2e_common import fresh_dir, recordings_dir, run_sdins, skip  # beside this script

sdins, data, work = sys.argv[1:4]
data = recordings_dir(data)
src = os.path.join(data, "px4-ulog")
logs = {"sample_log_small": os.path.join(src, "sample_log_small.ulg"), "sample_px4_events": os.path.join(src, "sample_px4_events.ulg")}
for p in logs.values():
    if not os.path.isfile(p):
        skip(f"{p} is missing (the shared data directory is read in place, set SDINS_RECORDINGS_DIR, docs/data.md)")
fresh_dir(work)
run = functools.partial(run_sdins, sdins)


def table(log, channel):
    path = os.path.join(work, os.path.basename(log) + "." + channel + ".csv")
    run("log", "export", log, "--channel", channel, "--csv", path)
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def imported(name, path):
    log = os.path.join(work, name + ".lcmlog")
    text = run("import", "ulog", path, "--log", log)
    print(text)
    with open(log + ".json") as f:
        side = json.load(f)
    # Every import writes the same sidecar and a starting flight configuration (docs/own-recording.md):
    # the configuration is one the flight software accepts on this log (no refusal at load).
    assert side["format"] == "sdins-import-summary" and side["importer"] == "ulog", side.get("format")
    start = os.path.join(work, name + ".filter.toml")
    assert side["filter_config"] == start and os.path.getsize(start) > 0, side.get("filter_config")
    p = subprocess.run([sdins, "replay", log, "--flight-config", start], capture_output=True, text=True)
    assert p.returncode in (0, 2) and "must be" not in p.stderr, (p.returncode, p.stderr)
    return log, side, text


def gravity_check(log, what):
    """Mean specific force of the first second against C_n_b (0, 0, g) from PX4's attitude there."""
    imu, tru = table(log, "IMU"), table(log, "TRUTH")
    t0 = imu["t_s"][0]
    idx = [k for k, t in enumerate(imu["t_s"]) if t < t0 + 1.0]
    T = sum(imu["dt_s"][k] for k in idx)
    f = [sum(imu[f"dv_mps[{i}]"][k] for k in idx) / T for i in range(3)]
    k = min(range(len(tru["t_s"])), key=lambda j: abs(tru["t_s"][j] - (t0 + 0.5)))
    r, p = tru["roll_rad"][k], tru["pitch_rad"][k]
    g = math.sqrt(sum(x * x for x in f))
    pred = [g * math.sin(p), -g * math.sin(r) * math.cos(p), -g * math.cos(r) * math.cos(p)]
    for i in range(3):
        assert abs(f[i] - pred[i]) < 0.1, f"{what}: specific force {f} vs PX4's attitude {pred} (axis {i})"
    print(f"{what}: first-second specific force {[round(x, 3) for x in f]} m/s^2, from PX4's roll/pitch "
          f"{[round(x, 3) for x in pred]}")


# The real vehicle: a CubePilot Cube Orange (PX4 v1.11.2, NuttX), a VTOL at rest, 6.5 s.
log, j, text = imported("small", logs["sample_log_small"])
u = j["ulog"]
assert u["info"]["sys_name"] == "PX4" and u["info"]["ver_hw"] == "CUBEPILOT_CUBEORANGE" and u["info"]["sys_os_name"] == "NuttX"
assert u["vehicle"]["is_vtol"] is True
assert u["damage"]["total"] == 0 and u["dropouts"]["count"] == 1
assert j["imu"]["topic"] == "sensor_combined" and j["imu"]["lines"]["accepted"] == 1298
assert j["gnss_pvt"]["topic"] == "vehicle_gps_position" and j["gnss_pvt"]["lines"]["accepted"] == 32
assert j["time_fit"]["pairs"] == 32 and j["time_fit"]["gps_minus_utc_s"] == 18 and j["time_scale"]["gps_week0"] == 2154
assert j["time_fit"]["residual_rms_ms"] < 10.0, j["time_fit"]
assert j["truth"]["with_attitude"] == 261 and j["truth"]["with_position"] == 0  # PX4 had no position estimate yet
assert j["reference"]["kind"] == "autopilot_estimate" and j["reference"]["source"] == "vehicle_attitude"
assert abs(j["imu"]["samples"]["rate_hz"] - 200.0) < 10.0 and abs(j["gnss_pvt"]["samples"]["rate_hz"] - 5.0) < 0.1
assert "CUBEPILOT_CUBEORANGE" in text and "GPS-UTC 18 s" in text
gravity_check(log, "small")

# The simulated vehicle: PX4 SITL (Linux), a multicopter taking off and landing, 31 s.
log, j, text = imported("sitl", logs["sample_px4_events"])
u = j["ulog"]
assert u["info"]["ver_hw"] == "PX4_SITL" and u["info"]["sys_os_name"] == "Linux" and u["damage"]["total"] == 0
assert j["imu"]["lines"]["accepted"] == 7783 and abs(j["imu"]["samples"]["rate_hz"] - 250.0) < 1e-6
assert j["gnss_pvt"]["lines"]["accepted"] == 423
assert j["gnss_pvt"]["lines"]["rejected_by_reason"]["no 3D fix (fix_type < 3)"] == 160
assert j["time_scale"]["gps_week0"] == 2306 and j["time_fit"]["residual_max_ms"] < 1e-3  # SITL: boot clock = UTC
assert j["reference"]["source"] == "vehicle_global_position+vehicle_attitude" and j["reference"]["has_attitude"] is True
assert j["truth"]["with_position"] == 428 and j["truth"]["with_attitude"] == 621
gravity_check(log, "sitl")
pvt, tru = table(log, "GNSS_PVT"), table(log, "TRUTH")
ok = [k for k in range(len(tru["t_s"])) if math.isfinite(tru["lat_rad"][k])]
worst = 0.0
for k, t in enumerate(pvt["t_s"]):
    i = min(ok, key=lambda m: abs(tru["t_s"][m] - t))
    if abs(tru["t_s"][i] - t) > 0.1:
        continue
    dn = (pvt["lat_rad"][k] - tru["lat_rad"][i]) * 6.37e6
    de = (pvt["lon_rad"][k] - tru["lon_rad"][i]) * 6.37e6 * math.cos(tru["lat_rad"][i])
    worst = max(worst, math.hypot(dn, de))
assert worst < 1.0, f"GNSS fixes {worst:.2f} m from PX4's position estimate"
print(f"sitl: GNSS fixes within {worst:.3f} m of PX4's position estimate")
info = run("log", "info", log)
assert "reader rejections: 0" in info, info

# The SITL log replayed and scored against PX4's estimate (docs/ulog.md, "Replay of a ULog"): static
# alignment with thresholds for SITL's noisy IMU. Roll and pitch agree with PX4; the heading cannot
# (SITL's IMU has no Earth rotation to gyrocompass), and the score shows it.
probe = os.path.join(work, "sitl.toml")
open(probe, "w").write("""name = "px4-sitl-probe"
description = "PX4 SITL log: 250 Hz frames, GNSS fixes, static alignment"
[executive]
imu_samples_per_frame = 1
nav_rate_hz = 250.0
ekf_rate_hz = 5.0
gnss_wait_s = 0.1
max_gnss_age_s = 0.2
[gnss]
source = "pvt"
pvt_max_quality = 5
pvt_pos_sigma_floor_m = 0.5
pvt_vel_sigma_floor_mps = 0.1
[imu]
arw_deg_per_rthr = 0.5
vrw_mps_per_rthr = 0.1
gyro_bias_sigma_degph = 100.0
accel_bias_sigma_mg = 10.0
gyro_bias_rw_radps_per_rts = 1e-4
accel_bias_rw_mps2_per_rts = 1e-3
[init]
mode = "static"
alignment_s = 5.0
pos_sigma_m = 1.0
vel_sigma_mps = 0.2
roll_pitch_sigma_deg = 1.0
heading_sigma_deg = 30.0
static_max_rate_dev_dps = 2.0
static_max_accel_dev_mps2 = 1.0
static_max_speed_mps = 0.3
""")
score = os.path.join(work, "sitl_score.json")
out = run("replay", log, "--filter-config", probe, "--outages", "5", "8", "2", "--score-json", score)
print(out)
assert "autopilot_estimate from vehicle_global_position+vehicle_attitude" in out, "the replay did not print the reference's label"
sc = json.load(open(score))
assert sc["attitude"]["roll"]["rms_deg"] < 0.2 and sc["attitude"]["pitch"]["rms_deg"] < 0.2, sc["attitude"]
assert sc["attitude"]["heading"]["rms_deg"] > 90.0, "SITL's heading cannot come from gyrocompassing"
assert sc["position"]["horizontal"]["rms_m"] < 0.5 and sc["outages"]["complete"] == 2, sc

# A damaged copy: garbage inside, bytes flipped, cut short.
raw = bytearray(open(logs["sample_px4_events"], "rb").read())
rng = random.Random(5)
cut = raw[: int(len(raw) * 0.7)]
pos = int(len(cut) * 0.3)
cut[pos:pos] = bytes(rng.randrange(256) for _ in range(500))
for _ in range(20):
    cut[rng.randrange(2000, len(cut))] ^= 0xFF
bad = os.path.join(work, "damaged.ulg")
open(bad, "wb").write(bytes(cut))
log, j, text = imported("damaged", bad)
d = j["ulog"]["damage"]
# Most of the garbage is skipped (a chance run of plausible bytes in it may parse as messages, counted)
assert d["total"] >= 2 and d["bytes_skipped"] >= 300 and d["by_reason"].get("truncated_message") == 1, d
assert 0 < j["imu"]["lines"]["accepted"] < 7783, j["imu"]["lines"]
print(f"damaged copy: {d['total']} damage records ({d['by_reason']}), {d['bytes_skipped']} bytes skipped, "
      f"{j['imu']['lines']['accepted']} IMU samples kept")
print("ulog_import: OK")
