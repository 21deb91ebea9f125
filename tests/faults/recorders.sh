#!/usr/bin/env bash
# Recorders and players (docs/faults.md, "recorders", "players"): an interrupt of a recorder waiting
# for its timeout keeps every frame received (the wait is cut short within 50 ms); a timeout that is
# not positive is refused (option_values.sh); `can play --realtime` passes the log's timestamps
# through the replay reader's time-tag gate: one timestamp a day ahead neither sleeps for a day nor
# loses the frame.
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib.sh"
"$sdins" can encode --duration 1 --out "$out/enc.log" > /dev/null 2>&1 || fail "can encode failed"
frames=$(grep -c '^(' "$out/enc.log")
port=$((36000 + $$ % 2000))
if ! "$sdins" can dump --can "udp:$port" --timeout 0.1 > "$out/probe.log" 2>&1; then
  echo "skipped: the udp: bus cannot be opened here ($(tail -1 "$out/probe.log"))"
  exit 77
fi
# 1. SIGINT to a recorder waiting out a 60 s timeout after it received the frames.
"$sdins" can record --can "udp:$port" --out "$out/rec.log" --timeout 60 > "$out/rec.out" 2> "$out/rec.err" &
pid=$!
for _ in $(seq 100); do grep -qs listening "$out/rec.err" && break; sleep 0.1; done
"$sdins" can play "$out/enc.log" --can "udp:$port" --gap 0.0005 > /dev/null 2>&1 || fail "can play failed"
sleep 0.5
t0=$(date +%s.%N)
kill -INT "$pid"
wait "$pid"
rc=$?
t1=$(date +%s.%N)
[ "$rc" = 130 ] || { cat "$out/rec.out" "$out/rec.err" >&2; fail "record: exit $rc after SIGINT, expected 130"; }
python3 -c "import sys; sys.exit(0 if float(sys.argv[2]) - float(sys.argv[1]) < 2 else 1)" "$t0" "$t1" ||
  fail "record: SIGINT took more than 2 s to end the wait"
got=$(grep -c '^(' "$out/rec.log")
[ "$got" = "$frames" ] || fail "record: $got of $frames frames kept after SIGINT"
grep -q "recorded $frames frames" "$out/rec.out" || fail "record: no summary"
cases=$((cases + 1))
# 2. can play --realtime with one timestamp moved a day ahead: about 1 s of play, every frame sent.
python3 - "$out/enc.log" "$out/wild.log" << 'PY'
import re, sys
lines = open(sys.argv[1]).read().splitlines()
k = len(lines) // 2
t = float(re.match(r"\((\d+\.\d+)\)", lines[k]).group(1))
lines[k] = re.sub(r"^\(\d+\.\d+\)", "(%.6f)" % (t + 86400.0), lines[k])
open(sys.argv[2], "w").write("\n".join(lines) + "\n")
PY
"$sdins" can record --can "udp:$((port + 1))" --out "$out/rec2.log" --timeout 3 > /dev/null 2> "$out/rec2.err" &
pid=$!
for _ in $(seq 100); do grep -qs listening "$out/rec2.err" && break; sleep 0.1; done
run 0 play_wild -- "$sdins" can play "$out/wild.log" --can "udp:$((port + 1))" --realtime --speed 4
says play_wild "time tags: 1 outliers"
says play_wild "played $frames frames"
wait "$pid"
got=$(grep -c '^(' "$out/rec2.log")
[ "$got" = "$frames" ] || fail "play_wild: $got of $frames frames arrived"
# 3. A sustained jump (a new time base) is paced as a step of 0, not slept through.
python3 - "$out/enc.log" "$out/jump.log" << 'PY'
import re, sys
lines = open(sys.argv[1]).read().splitlines()
k = len(lines) // 2
out = []
for i, l in enumerate(lines):
    if i >= k:
        t = float(re.match(r"\((\d+\.\d+)\)", l).group(1))
        l = re.sub(r"^\(\d+\.\d+\)", "(%.6f)" % (t + 3600.0), l)
    out.append(l)
open(sys.argv[2], "w").write("\n".join(out) + "\n")
PY
run 0 play_jump -- "$sdins" can play "$out/jump.log" --can "udp:$((port + 2))" --realtime --speed 4
says play_jump "1 new time bases"
done_ok
