#!/usr/bin/env bash
# Inputs that hold nothing valid: `log info` and `can dump` exit non-zero (after their summary);
# an export with no known message writes nothing.
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib.sh"
: > "$out/empty.lcmlog"
head -c 5000 /dev/urandom > "$out/garbage.lcmlog"
printf 'not a candump line\n(1.0)\n' > "$out/garbage.candump"
: > "$out/empty.candump"
for f in empty garbage; do
  run 1 "info_$f" -- "$sdins" log info "$out/$f.lcmlog"
  says "info_$f" "no valid LCM event"; says "info_$f" "$out/$f.lcmlog"
  run 1 "info_json_$f" -- "$sdins" log info --json "$out/$f.lcmlog"
  run 1 "dump_$f" -- "$sdins" can dump --log "$out/$f.candump"
  says "dump_$f" "no valid candump frame"; says "dump_$f" "$out/$f.candump"
  run nonzero "export_$f" -- "$sdins" log export "$out/$f.lcmlog" --channel IMU --csv "$out/$f.csv"
  absent "$out/$f.csv"
done
# A valid log / candump file still exits 0.
make_log "$out/ok.lcmlog"
run 0 info_ok -- "$sdins" log info "$out/ok.lcmlog"
"$sdins" can encode --duration 1 --out "$out/ok.candump" > /dev/null 2>&1 || fail "can encode"
run 0 dump_ok -- "$sdins" can dump --log "$out/ok.candump" --quiet
done_ok
