#!/usr/bin/env bash
# Stack budget gate (docs/audits.md): `sdins audit stack` builds fsw/ in the stack-audit
# configuration and computes each task's worst-case stack. This test checks the JSON report's
# structure and consistency, then FAILS when any task is unbounded or over its budget, listing
# those tasks with their numbers, the reasons and the deepest call path.
set -uo pipefail
sdins=${1:?usage: audit_stack.sh SDINS OUTDIR [BUILD_DIR]}
out=${2:?usage: audit_stack.sh SDINS OUTDIR [BUILD_DIR]}
build=${3:-}
rm -rf "$out" && mkdir -p "$out"
args=(audit stack --json "$out/stack.json")
[ -n "$build" ] && args+=(--build-dir "$build")
"$sdins" "${args[@]}" > "$out/stack.txt" 2> "$out/stack.err"
rc=$?
cat "$out/stack.err"
if [ $rc -ne 0 ] && [ $rc -ne 3 ]; then
  cat "$out/stack.txt"
  echo "sdins audit stack failed (exit $rc)"
  exit 1
fi
source_dir=$(cd "$(dirname "$0")/../.." && pwd)
/usr/bin/python3 - "$out/stack.json" "$rc" "$source_dir" <<'PY'
import json, os, re, sys
j = json.load(open(sys.argv[1]))
rc = int(sys.argv[2])
source_dir = sys.argv[3]
layouts = ["Layout15", "Layout24", "Layout15Full", "Layout24Full"]
names = [t["name"] for t in j["tasks"]]
want = [f"{k}/{l}" for l in layouts for k in ("mech_200hz", "ekf_1hz")] + [f"{k}/{l}" for l in layouts[2:] for k in ("imu_input", "gnss_input", "pvt_input", "event_input")]
assert names == want, names
assert isinstance(j["static_ram_bytes"], int) and j["static_ram_bytes"] >= 0
assert j["static_ram_bytes"] == j["static_ram"]["data"] + j["static_ram"]["bss"]
assert j["static_ram"]["text"] > 0
assert all(c["pass"] for c in j["self_check"]), j["self_check"]
assert len(j["self_check"]) >= 6
assert j["cross_check"]["differences"] == [] and j["cross_check"]["ci_records"] == j["cross_check"]["su_records"] > 0
budget = j["budget_bytes"]
failing = []
for t in j["tasks"]:
    assert isinstance(t["stack_bytes"], int) and t["stack_bytes"] > 0, t["name"]
    assert isinstance(t["bounded"], bool) and t["budget_bytes"] == budget
    assert t["bounded"] == (len(t["unbounded_reasons"]) == 0), t["name"]
    assert t["deepest_path"] and sum(s["frame_bytes"] for s in t["deepest_path"]) == t["stack_bytes"], t["name"]
    assert t["within_budget"] == (t["bounded"] and t["stack_bytes"] <= budget), t["name"]
    if not t["within_budget"]:
        failing.append(t)
by = {t["name"]: t for t in j["tasks"]}
for l in layouts:  # two groups, two entries: the 200 Hz tick no longer contains the 1 Hz group
    assert not any("run_ekf_group" in s["short"] for s in by[f"mech_200hz/{l}"]["deepest_path"]), l
    assert "run_ekf_group" in by[f"ekf_1hz/{l}"]["deepest_path"][0]["short"], by[f"ekf_1hz/{l}"]["deepest_path"][0]
for l in layouts[2:]:  # an IMU sample's input contains the 200 Hz tick
    assert by[f"imu_input/{l}"]["stack_bytes"] >= by[f"mech_200hz/{l}"]["stack_bytes"], l
    # the one dispatch contains every input's path
    assert by[f"event_input/{l}"]["stack_bytes"] >= max(by[f"{k}/{l}"]["stack_bytes"] for k in ("imu_input", "gnss_input", "pvt_input")), l
assert (rc == 3) == bool(failing) and j["all_within_budget"] == (not failing), (rc, len(failing))
print(f"stack audit report consistent: {len(j['tasks'])} tasks, budget {budget} B, static RAM {j['static_ram_bytes']} B")
if failing:
    print(f"\nSTACK BUDGET GATE FAILS: {len(failing)} of {len(j['tasks'])} tasks over {budget} B or unbounded")
    for t in failing:
        state = "unbounded" if not t["bounded"] else "over budget"
        print(f"  {t['name']:<24} {t['stack_bytes']:>8} B  {state}")
        for f in t["unbounded_via"]:
            print(f"      {f['reason'][:160]}")
            print(f"        via {' -> '.join(v[:70] for v in f['via'])}")
        print("      deepest path: " + " -> ".join(f"{s['short'][:60]} {s['frame_bytes']}" for s in t["deepest_path"]))
    sys.exit(1)
print("all tasks bounded and within budget")
# The docs restate the worst task's stack (the one dispatch, event_input): each place must say
# what the audit measures, so that they cannot drift apart (issue 28: 5472 B in one, 4816 B in
# another). When the code changes it, update these places (and the table in docs/audits.md).
worst = max(t["stack_bytes"] for t in j["tasks"])
claims = [
    ("README.md", r"at most (\d+) B of stack"),
    ("docs/README.md", r"at most (\d+) B of stack"),
    ("docs/audits.md", r"\| `event_input/Layout15Full`, `/Layout24Full` \| (\d+) \|"),
    ("docs/architecture-data-path.md", r"event_input (\d+) B for both"),
    ("docs/architecture-data-path.md", r"entries, (\d+) B for Layout15Full and Layout24Full"),
    ("docs/baremetal-qemu.md", r"the host stack audit's worst task is (\d+) B"),
]
stale = []
for doc, pattern in claims:
    text = " ".join(open(os.path.join(source_dir, doc), encoding="utf-8").read().split())
    found = [int(v) for v in re.findall(pattern, text)]
    if not found:
        stale.append(f"{doc}: no longer states the worst-case stack as /{pattern}/ (update this test with it)")
    stale += [f"{doc}: says {v} B, the audit measures {worst} B" for v in found if v != worst]
if stale:
    print("DOCS RESTATE THE WORST-CASE STACK WRONGLY:\n  " + "\n  ".join(stale))
    sys.exit(1)
print(f"the docs' worst-case stack agrees with the audit: {worst} B")
PY
