#!/usr/bin/env bash
# The measured car drive ($SDINS_RECORDINGS_DIR/gnss-imu-drive, default ../shared/data) through the loosely coupled filter with
# its filter configuration (config/datasets/gnss-imu-drive.toml): import, replay with and without
# 15 s GNSS outages, and (release builds) the diagnosis. Skipped (77) without the data set.
# Usage: drive_dataset.sh SDINS DATA_DIR CONFIG OUT_DIR SANITIZED(-1: no sanitizer)
set -euo pipefail
sdins=$1 data=${SDINS_RECORDINGS_DIR:-$2}/gnss-imu-drive config=$3 out=$4 sanitized=$5
[ -f "$data/gnss_1934_sf.pos" ] || { echo "SKIP: recording $data not present (set SDINS_RECORDINGS_DIR, docs/data.md)"; exit 77; }
rm -rf "$out" && mkdir -p "$out"
"$sdins" import rtklib "$data" --log "$out/drive.lcmlog" > "$out/import.txt"
"$sdins" replay "$out/drive.lcmlog" --filter-config "$config" --json "$out/replay.json" > "$out/replay.txt"
"$sdins" replay "$out/drive.lcmlog" --filter-config "$config" --outages 15 60 60 --json "$out/outages.json" \
  > "$out/outages.txt"
cat "$out/replay.txt" "$out/outages.txt"
py=/usr/bin/python3
$py - "$out" <<'PY'
import json, sys
out = sys.argv[1]
r = json.load(open(out + "/replay.json"))
o = json.load(open(out + "/outages.json"))
for j in (r, o):
    assert j["initialised"], j
    assert j["gnss_source"] == "pvt"
    e = j["executive"]
    assert e["pos_used"] > 0.9 * (e["pos_used"] + e["pos_rejected"]), e
    assert e["vel_used"] > 0.9 * (e["vel_used"] + e["vel_rejected"]), e
    assert j["inputs"]["gnss_pvt_accepted"] == 2197, j["inputs"]
# Without outages the solutions are never lost for long: few re-acquisitions.
assert r["executive"]["filter_resets"] <= 10, r["executive"]
assert o["inputs"]["gnss_withheld"] > 400, o["inputs"]
print("replay ok")
PY
if [ "$sanitized" != "-1" ]; then echo "sanitizer build: the diagnosis of the drive runs in release builds only"; exit 0; fi
"$sdins" diagnose --log "$out/drive.lcmlog" --filter-config "$config" --json "$out/diag.json" --report "$out/report" \
  | tail -8
$py - "$out" "$data" <<'PY'
import json, struct, sys
out, data = sys.argv[1], sys.argv[2]
d = json.load(open(out + "/diag.json"))
assert d["gnss_source"] == "pvt"
f = d["findings"]
assert f, "no finding"
# The timing between the IMU log and the GNSS solutions is the strongest finding on this drive:
# the tag file's time scale runs the IMU clock ~240 ppm fast (docs/datasets/gnss-imu-drive.md).
assert f[0]["effect"] == "imu_clock_drift", f[0]
assert 80 < f[0]["estimate"] < 400 and f[0]["sigma"] < 40, f[0]
o = d["gain"]["outages"]
assert o["after"]["horizontal_rms_m"] < 0.85 * o["before"]["horizontal_rms_m"], o
assert o["before"]["reacquisitions"] >= 6 and o["after"]["reacquisition_nis_mean"] < 1.5, o
g = d["gain"]["innovations"]
assert g["after"]["log_likelihood"] > g["before"]["log_likelihood"], g
# The recording's own tick records (docs/diagnosis-intervals.md): the importer maps the IMU's
# millisecond tick span onto the tag file's last record (the logging PC's ticks); that stretch is
# the time scale the diagnosis must find, within its 95% interval (the profile likelihood).
tag = open(data + "/imu_1934.csv.tag", "rb").read()
last_tag_ms = struct.unpack("<I", tag[len(tag) - 8:len(tag) - 4])[0]
ticks = [int(l.split(",")[6]) for l in open(data + "/imu_1934.csv") if len(l.split(",")) == 7 and l.split(",")[6].strip().isdigit()]
implied_ppm = (last_tag_ms / (ticks[-1] - ticks[0]) - 1.0) * 1e6
assert 250 < implied_ppm < 265, implied_ppm
iv = f[0]["interval_95"]
assert iv["method"] == "profile_likelihood" and iv["bounded"], iv
assert iv["lo"] <= implied_ppm <= iv["hi"], (implied_ppm, iv)
print("diagnosis ok:", f[0]["effect"], f[0]["estimate"], "+-", f[0]["sigma"], "interval", iv["lo"], iv["hi"],
      "tick records", implied_ppm)
# The mounting (docs/diagnosis.md, "The mounting"): the direction of travel names the IMU's pitch
# against the car. The accelerometers in the first 10 s at rest say the same from other data: the
# README's axes are x backward, y right, z up, so the forward axis sits asin(-f_x / |f|) above the
# horizontal (-6.7 deg; the parking's slope and a consumer part's 30 mg bias, 1.7 deg, lie in it).
m = d["chain"]["mounting_from_travel"]
assert m["determined"] and m["pitch"]["named"], m
rest = [[float(x) for x in l.split(",")[:3]] for l in open(data + "/imu_1934.csv").readlines()[1:1001] if len(l.split(",")) == 7]
fx, fy, fz = (sum(r[i] for r in rest) / len(rest) for i in range(3))
import math
rest_pitch = math.degrees(math.asin(-fx / math.sqrt(fx * fx + fy * fy + fz * fz)))
lo, hi = m["pitch"]["interval_95_deg"]
assert lo - 1.7 <= rest_pitch <= hi + 1.7, (rest_pitch, m["pitch"])
print("mounting ok: pitch", m["pitch"]["estimate_deg"], [lo, hi], "at rest", rest_pitch, "; yaw",
      m["yaw"]["estimate_deg"], m["yaw"]["interval_95_deg"], "named" if m["yaw"]["named"] else "not named")
PY
