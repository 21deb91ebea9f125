#!/usr/bin/env bash
# The two other measured data sets through the flight software with their filter configurations
# (config/datasets/psins-tc.toml: raw GPS, stationary alignment; gnss-imu-walk.toml: RTK
# solutions, velocity-matching alignment of an IMU at an unknown mounting yaw): import, replay,
# and (release builds) the diagnosis. Skipped (77) without the data sets or RTKLIB's convbin.
# Usage: datasets_psins_walk.sh SDINS DATA_DIR CONFIG_DIR OUT_DIR SANITIZED(-1: no sanitizer)
set -euo pipefail
sdins=$1 data=${SDINS_RECORDINGS_DIR:-$2} config=$3 out=$4 sanitized=$5
[ -f "$data/psins-tc/imu_200hz.csv" ] && [ -f "$data/gnss-imu-walk/gnss_1730_sf.pos" ] ||
  { echo "SKIP: psins-tc or gnss-imu-walk not present under $data (set SDINS_RECORDINGS_DIR, docs/data.md)"; exit 77; }
command -v convbin > /dev/null || { echo "SKIP: RTKLIB's convbin (Debian package rtklib) is not installed"; exit 77; }
rm -rf "$out" && mkdir -p "$out"
"$sdins" import psins "$data/psins-tc" --clip-gnss-to-imu --log "$out/psins.lcmlog" > "$out/psins_import.txt"
"$sdins" import rtklib "$data/gnss-imu-walk" --log "$out/walk.lcmlog" > "$out/walk_import.txt"
"$sdins" replay "$out/psins.lcmlog" --filter-config "$config/psins-tc.toml" --json "$out/psins.json" | tee "$out/psins.txt"
"$sdins" replay "$out/walk.lcmlog" --filter-config "$config/gnss-imu-walk.toml" --json "$out/walk.json" | tee "$out/walk.txt"
py=/usr/bin/python3
$py - "$out" <<'PY'
import json, sys
out = sys.argv[1]
p = json.load(open(out + "/psins.json"))
w = json.load(open(out + "/walk.json"))
# psins-tc: at rest for ~55 s, the gyros sense the Earth rate: static alignment, then the raw GPS.
assert p["initialised"] and p["gnss_source"] == "raw", p["app"]
assert p["app"]["init_mode"] == "static" and p["app"]["init_align_s"] >= 30.0, p["app"]
assert 40.0 < p["init_t_s"] - 185492.5 < 56.0, p["init_t_s"]  # before the vehicle moves
e = p["executive"]
assert e["pr_used"] > 500 and e["pr_rejected"] <= 0.02 * e["pr_used"] and e["filter_resets"] == 0, e
# The walk: an IMU at an unknown yaw; velocity matching gives the attitude within seconds of walking.
assert w["initialised"] and w["gnss_source"] == "pvt", w["app"]
assert w["app"]["init_mode"] == "velocity_matching" and w["app"]["init_att_sigma_deg"][2] < 5.0, w["app"]
assert w["init_t_s"] - 408651.7 < 15.0, w["init_t_s"]
e = w["executive"]
assert e["pos_used"] > 1300 and e["pos_rejected"] == 0 and e["filter_resets"] == 0, e
assert e["vel_used"] > 0.98 * (e["vel_used"] + e["vel_rejected"]), e
print("replays ok: psins heading %.1f deg after %.1f s at rest; walk heading %.1f +- %.1f deg" % (
    p["app"]["init_heading_deg"], p["app"]["init_align_s"], w["app"]["init_heading_deg"], w["app"]["init_att_sigma_deg"][2]))
PY
if [ "$sanitized" != "-1" ]; then echo "sanitizer build: the diagnoses run in release builds only"; exit 0; fi
"$sdins" diagnose --log "$out/psins.lcmlog" --filter-config "$config/psins-tc.toml" --json "$out/psins_diag.json" | tail -4
"$sdins" diagnose --log "$out/walk.lcmlog" --filter-config "$config/gnss-imu-walk.toml" --json "$out/walk_diag.json" | tail -4
$py - "$out" <<'PY'
import json, sys
out = sys.argv[1]
p = json.load(open(out + "/psins_diag.json"))
w = json.load(open(out + "/walk_diag.json"))
names = lambda d: {f["effect"] + ("." + f["component"] if f["component"] else "") for f in d["findings"]}
# psins-tc (no reference): the unmodelled tropospheric delay of real pseudoranges, at about the
# standard model's size, and the IMU-GNSS time offset.
assert {"tropospheric_delay", "imu_gnss_time_offset"} <= names(p), names(p)
tropo = [f for f in p["findings"] if f["effect"] == "tropospheric_delay"][0]
assert abs(tropo["estimate"] - 1.0) < 3 * tropo["sigma"], tropo
assert p["gain"]["innovations"]["log_likelihood_gain"] > 0 and p["gain"]["navigation"] is None
assert p["gain"]["outages"]["before"]["reacquisitions"] >= 2, p["gain"]["outages"]
# The walk: the antenna a few centimetres from the IMU (data set README), and a coasting gain.
assert {"antenna_lever_arm.x", "antenna_lever_arm.y"} <= names(w), names(w)
for f in w["findings"]:
    if f["effect"] == "antenna_lever_arm":
        assert abs(f["estimate"]) < 0.15, f
assert w["gain"]["innovations"]["log_likelihood_gain"] > 0
o = w["gain"]["outages"]
assert o["before"]["windows"] >= 2 and o["after"]["horizontal_rms_m"] < o["before"]["horizontal_rms_m"], o
# A profile-likelihood interval holds its own maximum (the walk's drift profile once had it outside:
# the grid around a sharp maximum is refined now, docs/diagnosis-intervals.md).
for d in (p, w):
    for f in d["findings"]:
        iv = f["interval_95"]
        if iv["method"] == "profile_likelihood" and iv["bounded"]:
            assert iv["lo"] <= iv["estimate"] <= iv["hi"], (f["effect"], f["component"], iv)
        if iv["method"] == "profile_likelihood":  # the filter/profile agreement flag is the deviance test
            assert iv["model_agrees"] == (iv["deviance_at_filter_estimate"] <= 10.827566170662733), iv
# The walk's clock drift: the filter (811 +- 117 ppm) and the profile ([-129 (not bounded), -28]
# ppm) disagree far beyond chance and neither covers the tick records' 142 ppm
# (docs/diagnosis-intervals.md): the interval must be reported as not calibrated, not as a 95%
# statement. The lever arms agree, and so does the time offset since the profile's burn-in (it was
# [-115, -89] ms against the filter's -48 ms, an initialisation artefact).
drift = [f for f in w["findings"] if f["effect"] == "imu_clock_drift"]
if drift and drift[0]["interval_95"]["method"] == "profile_likelihood":
    assert not drift[0]["interval_95"]["model_agrees"], drift[0]["interval_95"]
# The time offset: with the chain (docs/diagnosis.md) it is applied to the walk and searched again
# until no residual is found; the reported interval is the last residual's profile, shifted, where
# filter and profile may disagree (measured: deviance 12.7 at the residual's filter estimate).
ch = w["chain"]
for f in w["findings"]:
    if f["effect"] == "imu_gnss_time_offset":
        assert f["interval_95"]["method"] == "profile_likelihood" and f["interval_95"]["bounded"], f
        assert "imu_gnss_time_offset" in [a["candidate"] for a in ch["applied"]], ch["applied"]
        assert "imu_gnss_time_offset" not in [g["candidate"] for g in ch["stages"][-1]["findings"]], ch["stages"][-1]
for f in w["findings"]:
    if f["effect"] == "antenna_lever_arm" and f["interval_95"]["method"] == "profile_likelihood":
        assert f["interval_95"]["model_agrees"], f
# The mounting (docs/diagnosis.md, "The mounting"), from the direction of travel: the walk's yaw
# (body heading minus the RTK track, 97-99 deg on the straight stretches of the replay) and psins-tc's
# 90 deg (body heading minus the GNSS track: 90.5 deg over its 64 epochs above 1 m/s); neither
# initialisation uses the track, so neither is applied.
for d, truth in ((w, 97.0), (p, 90.5)):
    m = d["chain"]["mounting_from_travel"]
    assert m["determined"] and m["yaw"]["named"], m
    lo, hi = m["yaw"]["interval_95_deg"]
    assert lo <= truth <= hi and hi - lo < 25.0, (truth, m["yaw"])
    assert m["applied"] is None, m
print("diagnoses ok:", sorted(names(p)), sorted(names(w)), "; mounting yaw walk",
      w["chain"]["mounting_from_travel"]["yaw"]["interval_95_deg"], "psins-tc", p["chain"]["mounting_from_travel"]["yaw"]["interval_95_deg"])
PY
