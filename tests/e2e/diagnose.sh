#!/usr/bin/env bash
# End to end: a measured-data log with a hidden effect (`sdins sim --effect`) is diagnosed by
# `sdins diagnose` without being told: the JSON (docs/diagnosis.md) names the effect first with
# an estimate within 3 sigma and 30 % of the truth and a positive likelihood gain, the report has
# its markdown and plots; a log without the effect gives no finding; a log that is not a log is
# refused with a message.
set -euo pipefail
sdins=${1:?usage: diagnose.sh SDINS OUTDIR}
out=${2:?usage: diagnose.sh SDINS OUTDIR}
py=/usr/bin/python3
rm -rf "$out" && mkdir -p "$out"

"$sdins" sim --duration 400 --seed 11 --truth-errors baseline --effect antenna_lever_arm.z=-1.2 \
  --log "$out/lever.lcmlog" > /dev/null
"$sdins" diagnose --log "$out/lever.lcmlog" --json "$out/lever.json" --report "$out/report" | tee "$out/lever.txt"
"$sdins" sim --duration 400 --seed 12 --truth-errors baseline --log "$out/null.lcmlog" > /dev/null
# A component the flight cannot separate: the finding is the group (JSON, text and report).
"$sdins" sim --duration 400 --seed 13 --truth-errors baseline --effect gyro_scale_factor.z=-800 \
  --log "$out/group.lcmlog" > /dev/null
"$sdins" diagnose --log "$out/group.lcmlog" --json "$out/group.json" --report "$out/group" | tee "$out/group.txt"
"$sdins" diagnose --log "$out/null.lcmlog" --json "$out/null.json" > "$out/null.txt"

$py - "$out" <<'PY'
import json, os, sys
out = sys.argv[1]
j = json.load(open(f"{out}/lever.json"))
assert j["baseline"] == "15", j["baseline"]
f = j["findings"][0]
for k in ("effect", "component", "estimate", "sigma", "unit", "statistic", "dof", "p_value", "separable", "confounded_with", "group"):
    assert k in f, k
assert (f["effect"], f["component"], f["unit"]) == ("antenna_lever_arm", "z", "m"), f
assert abs(f["estimate"] - -1.2) < 3 * f["sigma"] and abs(f["estimate"] - -1.2) < 0.36, f
assert f["statistic"] > j["method"]["threshold"] and f["separable"] and f["group"] == [] and f["dof"] == 1, f
# The chain (docs/diagnosis.md): the lever arm is applied to the antenna and the search repeated.
assert (j["extended_model"]["applied_corrections"] + j["extended_model"]["added_states"])[0] == "antenna_lever_arm.z", j["extended_model"]
assert j["chain"]["applied"][0]["candidate"] == "antenna_lever_arm.z" and j["chain"]["stages"][-1]["findings"] == [], j["chain"]
assert f["estimate_method"] == "profile_maximum" and f["estimate"] == f["interval_95"]["estimate"], f
assert f["filter_interval_95"][0] < f["filter_estimate"] < f["filter_interval_95"][1], f
g = j["gain"]
assert g["innovations"]["log_likelihood_gain"] > 0, g["innovations"]
for side in ("before", "after"):
    i = g["innovations"][side]
    assert set(i["innovation_rms"]) == {"pseudorange_m", "pseudorange_rate_mps", "position_m", "velocity_mps"} and i["nis_mean"] > 0, i
    n = g["navigation"][side]
    for k in ("position_rms_m", "velocity_rms_mps", "tilt_rms_deg", "heading_rms_deg"):
        assert n[k] > 0, (side, k, n)
o = g["outages"]
assert o["length_s"] == 15 and o["before"]["windows"] >= 3 and o["before"]["windows"] == o["after"]["windows"], o
assert o["before"]["epochs_withheld"] >= 15 * o["before"]["windows"] - 2 and o["after"]["horizontal_rms_m"] > 0, o
assert j["method"]["alpha"] == 0.05 and j["method"]["tested_components"] > 5, j["method"]
assert len(j["screening"]) == 25 and all(u in [s["candidate"] for s in j["screening"]] for u in j["unobservable"])
# estimates.png plots the states of the last search: none here (the chain applied the lever arm);
# the group's report below has them.
assert os.path.getsize(f"{out}/group/estimates.png") > 0
for p in ("report.md", "innovations.png", "heading.png", "baseline.csv", "extended.csv"):
    assert os.path.getsize(f"{out}/report/{p}") > 0, p
md = open(f"{out}/report/report.md").read()
assert "## The chain" in md and "## Evidence the recording carries" in md, md
assert "antenna_lever_arm" in md and "![heading error](heading.png)" in md
n = json.load(open(f"{out}/null.json"))
assert n["findings"] == [] and n["extended_model"]["added_states"] == [], n["findings"]
gj = json.load(open(f"{out}/group.json"))
assert len(gj["findings"]) == 1, gj["findings"]
gf = gj["findings"][0]
assert not gf["separable"] and gf["statistic"] > gf["threshold"], gf
members = {m["candidate"]: m for m in gf["group"]}
assert "gyro_scale_factor.z" in members and len(members) >= 2, members
z = members["gyro_scale_factor.z"]
assert abs(z["alone_estimate"] - -800) < 3 * z["alone_sigma"] + 0.1 * 800, z
assert abs(sum(m["plausibility"] for m in gf["group"]) - 1) < 1e-9, gf["group"]
assert sorted(gj["extended_model"]["added_states"]) == sorted(members), gj["extended_model"]
assert "A group, not one cause" in open(f"{out}/group/report.md").read()
assert "a group this data cannot separate" in open(f"{out}/group.txt").read()
# The manoeuvre that separates it (docs/diagnosis-separation.md): predicted from the sidecar's scenario.
sep = gf["separation"]
assert sep["predicted"] and sep["members"] == [m["candidate"] for m in gf["group"]], sep
assert sep["segments"].startswith("[[trajectory.segment]]") and sep["segment_list"], sep
assert 0 <= sep["predicted_correlation"] <= 1 and sep["separates"] == (sep["predicted_correlation"] < 0.9), sep
assert sep["scenario_toml"] == open(f"{out}/group/separation-1.toml").read()
assert "The manoeuvre that separates them" in open(f"{out}/group/report.md").read()
assert "separated by:" in open(f"{out}/group.txt").read()
assert "separation" not in f, f  # a separable finding has nothing to separate
print("diagnose e2e: OK", f["estimate"], "+-", f["sigma"], "z^2", f["statistic"], "; group", sorted(members))
PY

# The scenario file it wrote is accepted by `sdins sim --scenario` as it is (a short stretch flown).
"$sdins" sim --scenario "$out/group/separation-1.toml" --seed 13 --duration 2 --log "$out/separation.lcmlog" > /dev/null

head -c 5000 /dev/urandom > "$out/junk.lcmlog"
if "$sdins" diagnose --log "$out/junk.lcmlog" --json "$out/junk.json" 2> "$out/junk.err"; then
  echo "a log of random bytes was diagnosed"; exit 1
fi
grep -q "no IMU or no GNSS data" "$out/junk.err"
echo "e2e diagnose: passed"
