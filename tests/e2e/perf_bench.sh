#!/usr/bin/env bash
# tools/perf/bench end to end (a smoke run, not a speed figure: CI does not time anything): one
# binary against itself on short flights, then its JSON: every figure asked for, with medians
# that are positive, the Monte Carlo's cost per frame, the A/B ratios, and the machine; and its
# refusals of bad arguments, each naming the argument.
# Usage: perf_bench.sh SDINS_BINARY WORK_DIR
set -euo pipefail
sdins=$1
work=$2
root="$(cd "$(dirname "$0")/../.." && pwd)"
rm -rf "$work" && mkdir -p "$work"
"$root/tools/perf/bench" --sdins "$sdins" --vs "$sdins" --quick --repeat 1 --only fly,mc1 --json "$work/bench.json" \
  > "$work/table.txt"
cat "$work/table.txt"
grep -q '^machine: ' "$work/table.txt"
python3 - "$work/bench.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
assert r["machine"]["cores"] >= 1, r["machine"]
assert set(r["figures"]) == {"fly", "mc1"}, r["figures"].keys()
for name, e in r["figures"].items():
    for k in ("A", "B"):
        assert e[k]["wall_s"]["median"] > 0 and e[k]["cpu_s"]["median"] > 0, (name, k, e[k])
    assert e["ratio_A_over_B"]["wall_s"]["median"] > 0, e
us = r["figures"]["mc1"]["A"]["us_per_frame"]["median"]
assert 0 < us < 1000, us
print("bench JSON ok: mc1 %.3f us/frame" % us)
PY
# Refusals: each names what it refuses and leaves no JSON behind.
. "$root/tests/e2e/expect.sh"  # expect_error
expect_error "unknown figure 'nope'" "$root/tools/perf/bench" --sdins "$sdins" --only nope --json "$work/bad.json"
expect_error "is not an executable file" "$root/tools/perf/bench" --sdins "$work/missing" --json "$work/bad.json"
expect_error "--repeat 0" "$root/tools/perf/bench" --sdins "$sdins" --repeat 0 --json "$work/bad.json"
[ ! -e "$work/bad.json" ] || { echo "a refused run left $work/bad.json"; exit 1; }
echo "perf bench: ok"
