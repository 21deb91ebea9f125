#!/usr/bin/env bash
# End-to-end: `sdins log info` and `sdins log export` on a log with known messages written by an
# independent encoder (lcm-gen's Python code, hand-written framing), including damage: a
# wrong-type and a cut IMU message, garbage between events, a truncated last event.
set -euo pipefail
sdins=${1:?usage: lcm_log.sh SDINS OUTDIR LCM_PYTHON_DIR}
out=${2:?usage: lcm_log.sh SDINS OUTDIR LCM_PYTHON_DIR}
gen=${3:?usage: lcm_log.sh SDINS OUTDIR LCM_PYTHON_DIR}
here=$(cd "$(dirname "$0")" && pwd)
py=/usr/bin/python3
rm -rf "$out"
mkdir -p "$out"
log="$out/known.lcmlog"
"$py" "$here/lcm_write_known_log.py" "$gen" "$log" > "$out/expected.json"

"$sdins" log info "$log" | tee "$out/info.txt"
"$sdins" log info --json "$log" > "$out/info.json"
"$sdins" log export "$log" --channel IMU --csv "$out/imu.csv"
"$sdins" log export "$log" --channel GNSS_RAW --csv "$out/gnss.csv"
"$sdins" log export "$log" --channel EKF_STATE --csv "$out/ekf.csv"
"$sdins" log export "$log" --channel NAV_SOLUTION --csv "$out/nav.csv"
"$sdins" log export "$log" --channel FILTER_HEALTH --csv "$out/health.csv"
if "$sdins" log export "$log" --channel FOREIGN --csv "$out/foreign.csv" 2> "$out/foreign.err"; then
  echo "export of a channel without a known type should fail"; exit 1
fi
grep -q "no message of a known type" "$out/foreign.err"
if "$sdins" log export "$log" --channel EKF_MIXED --csv "$out/mixed.csv" 2> "$out/mixed.err"; then
  echo "export of a channel whose EKF model changes should fail"; exit 1
fi
grep -q "different field layout" "$out/mixed.err"
[ ! -e "$out/mixed.csv" ] && [ ! -e "$out/foreign.csv" ] || { echo "a failed export left its CSV behind"; exit 1; }
echo keep > "$out/existing.csv"
if "$sdins" log export "$out/does-not-exist.lcmlog" --channel IMU --csv "$out/existing.csv" 2> /dev/null; then
  echo "export of a missing log should fail"; exit 1
fi
grep -q keep "$out/existing.csv" || { echo "a failed export destroyed an existing file it never wrote"; exit 1; }
if "$sdins" log info "$out/does-not-exist.lcmlog" 2> "$out/missing.err"; then
  echo "info on a missing log should fail"; exit 1
fi
grep -q "No such file" "$out/missing.err"

"$py" - "$out" <<'PY'
import csv, json, sys
out = sys.argv[1]
exp = json.load(open(f"{out}/expected.json"))
info = json.load(open(f"{out}/info.json"))
ch = {c["channel"]: c for c in info["channels"]}

# Channels, counts, types, rejections.
want = {"IMU": (102, "sdins.imu_sample_t"), "GNSS_RAW": (3, "sdins.gnss_raw_epoch_t"),
        "GPS_ALMANAC": (2, "sdins.gps_almanac_t"), "NAV_SOLUTION": (20, "sdins.nav_solution_t"),
        "TRUTH": (20, "sdins.truth_t"), "EKF_STATE": (2, "sdins.ekf_state_t"),
        "FILTER_HEALTH": (2, "sdins.filter_health_t")}
for name, (n, typ) in want.items():
    assert ch[name]["messages"] == n, (name, ch[name])
    if name != "IMU":
        assert ch[name]["type"] == typ, (name, ch[name]["type"])
        assert ch[name]["wrong_type"] == 0 and ch[name]["decode_failed"] == 0, ch[name]
assert ch["IMU"]["type"].startswith("mixed[") and "sdins.imu_sample_t:101" in ch["IMU"]["type"], ch["IMU"]["type"]
assert ch["IMU"]["wrong_type"] == 1 and ch["IMU"]["decode_failed"] == 1, ch["IMU"]
assert ch["FOREIGN"]["messages"] == 3 and ch["FOREIGN"]["type"] == "unknown(0x4242424242424242)", ch["FOREIGN"]
assert ch["FOREIGN"]["unknown_type"] == 3 and ch["FOREIGN"]["wrong_type"] == 0, ch["FOREIGN"]
assert ch["IMU"]["t_first_s"] == 0.001 and ch["IMU"]["t_last_s"] == 0.1, ch["IMU"]
assert ch["NAV_SOLUTION"]["t_first_s"] == 0.005 and ch["NAV_SOLUTION"]["t_last_s"] == 0.1
assert info["event_timestamp_min_us"] == 0 and info["event_timestamp_max_us"] == 200000, info
assert info["events"] == 102 + 3 + 2 + 20 + 20 + 2 + 2 + 3 + 2, info["events"]
rej = info["reader_rejections"]
assert rej["no_sync"] == 1 and rej["truncated_event"] == 1 and info["reader_rejections_total"] == 2, rej
assert info["bytes_skipped"] == 50 + 28 + 3 + 20, info["bytes_skipped"]

# The text form says the same.
text = open(f"{out}/info.txt").read()
assert "IMU" in text and "102" in text and "wrong_type 1, decode_failed 1" in text, text
assert "truncated_event 1" in text and "no_sync 1" in text, text

# IMU CSV: one row per good message, exact values.
rows = list(csv.reader(open(f"{out}/imu.csv")))
header = rows[0]
assert header == ["utime", "t_s", "dt_s", "dtheta_rad[0]", "dtheta_rad[1]", "dtheta_rad[2]", "dv_mps[0]",
                  "dv_mps[1]", "dv_mps[2]", "counter", "status"], header
assert len(rows) - 1 == 100, len(rows)
for r, e in zip(rows[1:], exp["imu"]):
    d = dict(zip(header, r))
    assert float(d["t_s"]) == e["t_s"], (d, e)
    assert [float(d[f"dtheta_rad[{i}]"]) for i in range(3)] == e["dtheta_rad"], (d, e)
    assert [float(d[f"dv_mps[{i}]"]) for i in range(3)] == e["dv_mps"], (d, e)
    assert int(d["counter"]) == e["counter"] and int(d["status"]) == e["status"], (d, e)
    assert int(d["utime"]) == round(e["t_s"] * 1e6)

# GNSS CSV: all 16 slots are columns; slots beyond n_meas are empty.
rows = list(csv.DictReader(open(f"{out}/gnss.csv")))
assert [int(r["n_meas"]) for r in rows] == exp["gnss_n_meas"]
assert rows[0]["meas[4].pseudorange_m"] == "20004002" and rows[0]["meas[5].prn"] == "", rows[0]
assert rows[1]["meas[0].prn"] == "" and rows[2]["meas[15].prn"] == "16", rows[2]
assert float(rows[2]["meas[15].cn0_dbhz"]) == 42.5

# EKF CSV: sigma columns named after their state with units.
rows = list(csv.DictReader(open(f"{out}/ekf.csv")))
assert len(rows) == 2
assert float(rows[0]["sigma_pos_E_m"]) == 0.1 and float(rows[0]["sigma_att_U_rad"]) == 0.1 * 9
assert float(rows[0]["sigma_clock_drift_mps"]) == 0.1 * 17 and float(rows[1]["clock_bias_m"]) == 12.5
assert not any(k.startswith("sigma[") for k in rows[0]), list(rows[0])

rows = list(csv.DictReader(open(f"{out}/nav.csv")))
assert len(rows) == 20 and rows[19]["ekf_updated"] == "1" and rows[0]["ekf_updated"] == "0"
assert float(rows[3]["vel_enu_mps[1]"]) == -4.5 and float(rows[0]["heading_rad"]) == 1.5

rows = list(csv.DictReader(open(f"{out}/health.csv")))
assert rows[1]["ekf_runs"] == "2" and rows[0]["pr_outcome[1]"] == "2" and rows[0]["pr_outcome[2]"] == ""
assert float(rows[0]["pr_innovation_m[1]"]) == -40.0
print("sdins log info/export: all checks passed")
PY
