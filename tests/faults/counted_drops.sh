#!/usr/bin/env bash
# Nothing dropped without a word (docs/faults.md): NaN pseudoranges the flight software's input
# conversion removes are counted in `log info` (text and JSON), `replay` (text and --json); a Monte
# Carlo shorter than its NEES window says "not measured" (text) and null (JSON), never 0.00.
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib.sh"
pydir=${SDINS_LCM_PYTHON_DIR:-}
if [ -z "$pydir" ] || [ ! -d "$pydir/sdins" ]; then
  echo "skipped: no lcm-gen Python types (SDINS_LCM_PYTHON_DIR)"
  exit 77
fi
make_log "$out/in.lcmlog"
n=$(python3 "$here/lcm_nan_pseudoranges.py" "$pydir" "$out/in.lcmlog" "$out/nan.lcmlog") || fail "poisoning failed"
[ "$n" -gt 0 ] || fail "no epoch poisoned"
run 0 info_text -- "$sdins" log info "$out/nan.lcmlog"
says info_text "$n measurements with non-finite values dropped"
run 0 info_json -- "$sdins" log info --json "$out/nan.lcmlog"
python3 -c "
import json, sys
j = json.load(open(sys.argv[1]))
c = [c for c in j['channels'] if c['channel'] == 'GNSS_RAW'][0]
sys.exit(0 if c['measurements_dropped'] == int(sys.argv[2]) else 1)" "$out/info_json.log" "$n" ||
  fail "log info --json: measurements_dropped is not $n"
run 0 replay_text -- "$sdins" replay "$out/nan.lcmlog" --json "$out/replay.json"
says replay_text "GNSS: $n measurements with non-finite values"
python3 -c "
import json, sys
sys.exit(0 if json.load(open(sys.argv[1]))['inputs']['gnss_measurements_dropped'] == int(sys.argv[2]) else 1)" \
  "$out/replay.json" "$n" || fail "replay --json: gnss_measurements_dropped is not $n"
# The intact log: 0, printed nowhere in the text.
run 0 info_clean -- "$sdins" log info "$out/in.lcmlog"
grep -q "non-finite" "$out/info_clean.log" && fail "info_clean: a drop reported on an intact log"
# Monte Carlo shorter than the 60 s NEES window.
run 0 mc_short -- "$sdins" montecarlo --runs 2 --duration 30 --models 15 --out "$out/mc"
says mc_short "NEES not measured"
grep -q " 0.00 \[" "$out/mc_short.log" && fail "mc_short: a NEES of 0.00 printed"
python3 -c "
import json, sys
m = json.load(open(sys.argv[1]))['models'][0]
sys.exit(0 if m['mean_nees'] is None and m['nees_measured'] is False else 1)" "$out/mc/summary.json" ||
  fail "mc_short: summary.json mean_nees is not null / nees_measured not false"
done_ok
