#!/usr/bin/env bash
# tools/perf/peer-intnavlib without the peer (CI never needs the peer's code): its refusals of bad
# arguments, each naming the argument and leaving no JSON behind, and of a checkout that does not
# build, naming the step, with nothing written into the checkout. The timed run itself (minutes: the
# peer's build and six 1800 s flights) runs here only when SDINS_PEER_INTNAVLIB names a checkout of
# the peer, as --quick --repeat 1, with its JSON checked.
# Usage: perf_peer_intnavlib.sh SDINS_BINARY WORK_DIR
set -euo pipefail
sdins=$1
work=$2
root="$(cd "$(dirname "$0")/../.." && pwd)"
script="$root/tools/perf/peer-intnavlib"
rm -rf "$work" && mkdir -p "$work"

. "$root/tests/e2e/expect.sh"  # expect_error
expect_error "checkout '$work/no-such-checkout': no such directory" \
  "$script" "$work/no-such-checkout" --sdins "$sdins" --json "$work/bad.json"
mkdir -p "$work/not-the-peer"
echo 'project(other)' > "$work/not-the-peer/CMakeLists.txt"
expect_error "checkout '$work/not-the-peer' is not an IntNavLib checkout (missing include/helpers.h" \
  "$script" "$work/not-the-peer" --sdins "$sdins" --json "$work/bad.json"
expect_error "--repeat 0: must be in [1, 50]" "$script" "$work/no-such-checkout" --sdins "$sdins" --repeat 0 --json "$work/bad.json"
expect_error "--repeat 51: must be in [1, 50]" "$script" "$work/no-such-checkout" --sdins "$sdins" --repeat 51 --json "$work/bad.json"
expect_error "argument --repeat: invalid int value: 'three'" "$script" "$work/no-such-checkout" --repeat three
expect_error "sdins '$work/missing' is not an executable file" "$script" "$work/no-such-checkout" --sdins "$work/missing"
expect_error "the following arguments are required: checkout" "$script" --sdins "$sdins"

# A checkout that has the peer's files but does not configure: refused naming the step, the checkout untouched.
fake="$work/fake-peer"
mkdir -p "$fake/include" "$fake/src"
printf 'cmake_minimum_required(VERSION 3.16)\nproject(intnavlib CXX)\nmessage(FATAL_ERROR "this fake peer does not build")\n' \
  > "$fake/CMakeLists.txt"
echo 'class MotionProfileReader {};' > "$fake/include/helpers.h"
touch "$fake/include/navigation.h" "$fake/src/navigation.cpp" "$fake/src/simulation.cpp"
before=$(cd "$fake" && find . | sort)
expect_error "configuring the peer: cmake -S" "$script" "$fake" --sdins "$sdins" --json "$work/bad.json"
grep -qF "this fake peer does not build" "$work/err.txt" || { echo "the refusal does not quote CMake:"; cat "$work/err.txt"; exit 1; }
[ "$(cd "$fake" && find . | sort)" = "$before" ] || { echo "the script wrote into the checkout $fake"; exit 1; }
[ ! -e "$work/bad.json" ] || { echo "a refused run left $work/bad.json"; exit 1; }

if [ -z "${SDINS_PEER_INTNAVLIB:-}" ]; then
  echo "perf peer-intnavlib: refusals ok; timed run skipped (SDINS_PEER_INTNAVLIB names no checkout of the peer)"
  exit 0
fi
"$script" "$SDINS_PEER_INTNAVLIB" --sdins "$sdins" --quick --repeat 1 --json "$work/peer.json" > "$work/table.txt"
cat "$work/table.txt"
python3 - "$work/peer.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
assert set(r["figures"]) == {"fly", "mc1"}, r["figures"].keys()
assert all(c["ok"] for c in r["profile"]["checks"].values()), r["profile"]["checks"]
assert r["profile"]["rows"] == 30000, r["profile"]["rows"]  # 0.01 s to 300 s at 100 Hz
for name, e in r["figures"].items():
    for k in ("ours", "peer", "peer_nowrite"):
        assert e[k]["wall_s"]["median"] > 0, (name, k, e[k])
    assert e["ratio_ours_over_peer_nowrite"]["median"] > 0, e
print("peer JSON ok")
PY
echo "perf peer-intnavlib: ok"
