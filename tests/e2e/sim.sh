#!/usr/bin/env bash
# End to end: `sdins sim` writes measured data (IMU, GNSS_RAW, GPS_ALMANAC, TRUTH) and a sidecar of
# what was simulated. Checks: the sidecar names the effect and its value; `sdins log info` counts
# the channels (and nothing else); the effect really is in the IMU data (exactly gamma_xy times
# the y increment in dtheta_x, nothing in y and z) while the log carries no trace of it besides
# the data; TRUTH falls on IMU sample times; `sdins replay` initialises on the log; a bad effect
# or truth rate is refused with a message and no log; the same seed gives the same bytes.
set -euo pipefail
sdins=${1:?usage: sim.sh SDINS OUTDIR}
out=${2:?usage: sim.sh SDINS OUTDIR}
py=/usr/bin/python3
rm -rf "$out" && mkdir -p "$out"

"$sdins" sim --duration 60 --seed 3 --truth-errors baseline --effect gyro_misalignment.xy=30 --log "$out/a.lcmlog" \
  | tee "$out/a.txt"
"$sdins" sim --duration 60 --seed 3 --truth-errors baseline --effect gyro_misalignment.xy=30 --log "$out/b.lcmlog" > /dev/null
"$sdins" sim --duration 60 --seed 3 --truth-errors baseline --log "$out/noeffect.lcmlog" > /dev/null
"$sdins" sim --duration 60 --seed 4 --truth-errors baseline --effect gyro_misalignment.xy=30 --log "$out/seed4.lcmlog" > /dev/null

# Same seed, same bytes (log and sidecar apart from the file name inside it); another seed differs.
cmp "$out/a.lcmlog" "$out/b.lcmlog"
if cmp -s "$out/a.lcmlog" "$out/seed4.lcmlog"; then echo "seed 3 and seed 4 gave the same log"; exit 1; fi
if cmp -s "$out/a.lcmlog" "$out/noeffect.lcmlog"; then echo "the effect did not change the log"; exit 1; fi
diff <(sed /'"log"'/d "$out/a.lcmlog.json") <(sed /'"log"'/d "$out/b.lcmlog.json")

"$sdins" log info --json "$out/a.lcmlog" > "$out/info.json"
"$sdins" log export "$out/a.lcmlog" --channel IMU --csv "$out/imu.csv"
"$sdins" log export "$out/noeffect.lcmlog" --channel IMU --csv "$out/imu_noeffect.csv"
"$sdins" log export "$out/a.lcmlog" --channel TRUTH --csv "$out/truth.csv"
"$sdins" replay "$out/a.lcmlog" --json "$out/replay.json" | tee "$out/replay.txt"

# Refused requests: non-zero exit (not a crash), a message naming the valid effects, no log written.
for bad in "bogus=1" "gyro_misalignment.qq=1" "gyro_misalignment=1" "gyro_misalignment.xy=abc"; do
  rc=0
  "$sdins" sim --duration 2 --seed 1 --effect "$bad" --log "$out/bad.lcmlog" 2> "$out/bad.err" || rc=$?
  cat "$out/bad.err"
  [[ $rc -ne 0 && $rc -lt 128 ]] || { echo "--effect $bad: exit $rc"; exit 1; }
  [[ ! -e "$out/bad.lcmlog" ]] || { echo "--effect $bad left a log"; exit 1; }
done
"$sdins" sim --duration 2 --seed 1 --effect bogus=1 --log "$out/bad.lcmlog" 2>&1 | tee "$out/bogus.err" || true
grep -q "unknown effect 'bogus'" "$out/bogus.err"
grep -q "gyro_misalignment, accel_misalignment, gyro_scale_factor" "$out/bogus.err"
rc=0
"$sdins" sim --duration 2 --seed 1 --truth-rate 7 --log "$out/bad.lcmlog" 2> "$out/rate.err" || rc=$?
[[ $rc -ne 0 && $rc -lt 128 ]] && grep -q "does not divide the IMU rate" "$out/rate.err" && [[ ! -e "$out/bad.lcmlog" ]]
rc=0
"$sdins" sim --duration 2 --log "$out/bad.lcmlog" 2> "$out/seed.err" || rc=$?
[[ $rc -ne 0 && $rc -lt 128 ]] && grep -q -- "--seed" "$out/seed.err"

"$py" - "$out" <<'PY'
import csv, json, math, sys
d = sys.argv[1]
side = json.load(open(f"{d}/a.lcmlog.json"))
assert side["scenario"] == "bank-to-turn" and side["seed"] == 3 and side["duration_s"] == 60, side
assert side["truth_errors"] == "baseline" and side["truth_rate_hz"] == 10, side
assert side["effects"] == [{"name": "gyro_misalignment", "component": "xy", "value": 30.0, "unit": "arcsec",
                            "source": "command_line"}], side["effects"]
drawn, applied = side["imu_errors"]["drawn"], side["imu_errors"]["applied"]
# baseline: biases only; the effect adds 30 arcsec of gamma_xy on top of the draw.
assert drawn["gyro_misalignment"]["xy"] == 0.0 and abs(applied["gyro_misalignment"]["xy"] - 30.0) < 1e-9, applied
assert all(drawn["gyro_scale_factor"][a] == 0.0 for a in "xyz"), drawn
assert all(0 < abs(drawn["gyro_bias"][a]) < 0.1 for a in "xyz"), drawn["gyro_bias"]
assert all(0 < abs(drawn["accel_bias"][a]) < 1000 for a in "xyz"), drawn["accel_bias"]
assert side["channels"] == {"IMU": 60000, "GNSS_RAW": 60, "GPS_ALMANAC": side["channels"]["GPS_ALMANAC"], "TRUTH": 600}
assert 24 <= side["channels"]["GPS_ALMANAC"] <= 32, side["channels"]

info = json.load(open(f"{d}/info.json"))
ch = {c["channel"]: c for c in info["channels"]}
assert sorted(ch) == ["GNSS_RAW", "GPS_ALMANAC", "IMU", "TRUTH"], sorted(ch)  # no effect/meta channel
assert ch["IMU"]["messages"] == 60000 and ch["IMU"]["type"] == "sdins.imu_sample_t", ch["IMU"]
assert ch["GNSS_RAW"]["messages"] == 60 and ch["TRUTH"]["messages"] == 600, ch
assert ch["GPS_ALMANAC"]["messages"] == side["channels"]["GPS_ALMANAC"], ch
assert info["reader_rejections_total"] == 0 and all(c["wrong_type"] + c["decode_failed"] == 0 for c in ch.values())
assert ch["GPS_ALMANAC"]["t_last_s"] <= ch["IMU"]["t_first_s"] < ch["GNSS_RAW"]["t_first_s"], ch

imu = list(csv.DictReader(open(f"{d}/imu.csv")))
ref = list(csv.DictReader(open(f"{d}/imu_noeffect.csv")))
assert [int(r["counter"]) for r in imu] == list(range(60000))
# The effect in the data: dtheta_x gains gamma_xy * dtheta_y, y and z are untouched.
gamma = 30.0 * math.pi / 180 / 3600
num = den = 0.0
for r, s in zip(imu, ref):
    assert r["t_s"] == s["t_s"] and r["dtheta_rad[1]"] == s["dtheta_rad[1]"] and r["dtheta_rad[2]"] == s["dtheta_rad[2]"]
    assert r["dv_mps[0]"] == s["dv_mps[0]"]
    dx = float(r["dtheta_rad[0]"]) - float(s["dtheta_rad[0]"])
    y = float(s["dtheta_rad[1]"])
    num += dx * y
    den += y * y
est = num / den * 180 / math.pi * 3600
assert abs(est - 30.0) < 0.3, est

imu_t = {r["t_s"] for r in imu}
truth = list(csv.DictReader(open(f"{d}/truth.csv")))
assert len(truth) == 600
for k, r in enumerate(truth, 1):
    assert abs(float(r["t_s"]) - 0.1 * k) < 1e-9, (k, r["t_s"])
    assert r["t_s"] in imu_t, r["t_s"]   # on an IMU sample time (no time-offset effect here)

rep = json.load(open(f"{d}/replay.json"))
assert rep["initialised"] and rep["init_t_s"] <= 3.0, (rep["initialised"], rep.get("init_t_s"))
assert rep["inputs"]["imu_accepted"] == 60000 and rep["inputs"]["gnss_accepted"] == 60, rep["inputs"]
assert rep["inputs"]["rejected"] == 0 and rep["inputs"]["imu_counter_gaps"] == 0, rep["inputs"]
assert rep["inputs"]["other_events"] == 600, rep["inputs"]   # TRUTH is not an input
assert rep["nav_frames"] > 11000, rep["nav_frames"]
assert rep["executive"]["fsw_errors"] == 0, rep["executive"]
print(f"sim ok: IMU {ch['IMU']['messages']}, GNSS_RAW {ch['GNSS_RAW']['messages']}, TRUTH {ch['TRUTH']['messages']}, "
      f"almanac {ch['GPS_ALMANAC']['messages']}; gamma_xy in the data {est:.3f} arcsec; replay initialised at "
      f"{rep['init_t_s']} s, {rep['nav_frames']} frames")
PY
