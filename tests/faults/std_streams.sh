#!/usr/bin/env bash
# Standard streams (docs/faults.md, "standard streams"): descriptors 0-2 closed at start are opened
# on /dev/null (tools/sdins/main.cpp) so the next file opened cannot become stdout; stdout is
# flushed and checked at exit (a full disk behind a redirect is exit 1 with a message); a closed pipe
# (`| head`) ends the command by SIGPIPE without a temporary file left.
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib.sh"
make_log "$out/in.lcmlog"
# stdout closed: the CSV must hold only CSV (before, `log info`'s table landed inside it).
"$sdins" log export "$out/in.lcmlog" --channel IMU --csv "$out/imu.csv" >&- 2> "$out/closed.err"
rc=$?
[ "$rc" = 0 ] || { cat "$out/closed.err" >&2; fail "stdout closed: exit $rc"; }
head -1 "$out/imu.csv" | grep -q '^t_s\|^utime' || fail "stdout closed: the CSV does not start with its header"
grep -q 'rows of' "$out/imu.csv" && fail "stdout closed: the command's messages landed in the CSV"
"$sdins" sim --seed 2 --duration 2 --log "$out/closed.lcmlog" >&- 2>&-
[ $? = 0 ] || fail "stdout and stderr closed: sim failed"
"$sdins" log info "$out/closed.lcmlog" > "$out/closed_info.txt" 2>&1 || fail "the log written with closed streams does not read"
grep -q 'IMU' "$out/closed_info.txt" || fail "the log written with closed streams lacks IMU"
cases=$((cases + 2))
# stdout on a full disk: exit 1, message on stderr, the outputs still complete.
run 1 full_info -- sh -c "\"$sdins\" log info \"$out/in.lcmlog\" > /dev/full"
says full_info "writing standard output failed: No space left on device"
run 1 full_help -- sh -c "\"$sdins\" --help > /dev/full"
says full_help "writing standard output failed"
run 1 full_sim -- sh -c "\"$sdins\" sim --seed 3 --duration 2 --log \"$out/full.lcmlog\" > /dev/full"
says full_sim "No space left on device"
[ -f "$out/full.lcmlog" ] && [ -f "$out/full.lcmlog.json" ] || fail "full_sim: the log or its sidecar missing"
# stdout is a pipe closed early: SIGPIPE (141) or, with SIGPIPE ignored, exit 1 naming the error.
"$sdins" can encode --duration 5 --out "$out/enc.log" > /dev/null 2>&1 || fail "can encode failed"
( "$sdins" can dump --log "$out/enc.log" | head -1 > /dev/null ); cases=$((cases + 1))
rc=$(bash -c "trap '' PIPE; \"$sdins\" can dump --log \"$out/enc.log\" 2> \"$out/pipe.err\" | head -1 > /dev/null; echo \${PIPESTATUS[0]}")
[ "$rc" = 1 ] || fail "SIGPIPE ignored: exit $rc, expected 1"
grep -q "writing standard output failed: Broken pipe" "$out/pipe.err" || { cat "$out/pipe.err" >&2; fail "SIGPIPE ignored: no message on stderr"; }
cases=$((cases + 1))
no_temporaries "$out"
done_ok
