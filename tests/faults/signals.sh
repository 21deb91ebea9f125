#!/usr/bin/env bash
# SIGINT / SIGTERM: a long run stops cleanly with exit 128 + signal (130 / 143): a live run (fsw,
# bus-sim) prints its summary and keeps its log / --json complete; a batch run (montecarlo, replay,
# diagnose) prints what it has and leaves no partial result (a run directory keeps no summary.json);
# a command that does not poll (sim) leaves the previous file and no temporary.
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib.sh"
# signal_after SECONDS SIGNAL NAME -- CMD...: starts CMD, signals it, returns its exit code in $rc.
signal_after() {
  local delay=$1 sig=$2 name=$3
  shift 4
  "$@" > "$out/$name.log" 2>&1 &
  local pid=$!
  sleep "$delay"
  kill "-$sig" "$pid" 2> /dev/null || fail "$name: finished before the signal (make the run longer)"
  local t=0
  while kill -0 "$pid" 2> /dev/null; do
    sleep 0.1
    t=$((t + 1))
    [ $t -lt 200 ] || { kill -KILL "$pid"; fail "$name: did not stop within 20 s of $sig"; }
  done
  wait "$pid"
  rc=$?
  cases=$((cases + 1))
}

# writing_in DIR PID: PID holds an output file open in DIR that has no name yet (hal::OutputFile's
# O_TMPFILE file, which /proc shows as "DIR/#INODE (deleted)") or a named temporary.
writing_in() {
  local l
  for f in /proc/"$2"/fd/*; do
    l=$(readlink "$f" 2> /dev/null) || continue
    case "$l" in "$1/#"*" (deleted)" | "$1/."*".sdins-tmp."*) return 0 ;; esac
  done
  return 1
}

# signal_when DIR SIGNAL NAME -- CMD...: as signal_after, but signals 50 ms after CMD opens its
# output in DIR (the run is past its setup and polling), so a fast machine cannot finish first.
signal_when() {
  local dir=$1 sig=$2 name=$3
  shift 4
  "$@" > "$out/$name.log" 2>&1 &
  local pid=$!
  local n=0
  until writing_in "$dir" "$pid"; do
    kill -0 "$pid" 2> /dev/null || fail "$name: finished before its temporary output appeared"
    n=$((n + 1))
    [ $n -lt 20000 ] || { kill -KILL "$pid"; fail "$name: no temporary output appeared"; }
  done
  sleep 0.05
  kill "-$sig" "$pid" 2> /dev/null || fail "$name: finished before the signal"
  wait "$pid"
  rc=$?
  cases=$((cases + 1))
}

# montecarlo: a previous complete run in the directory, then an interrupted one.
mc="$out/mc"
"$sdins" montecarlo --duration 30 --runs 2 --models 15 --out "$mc" > /dev/null 2>&1 || fail "montecarlo setup"
[ -f "$mc/summary.json" ] || fail "montecarlo: no summary.json after a complete run"
hs=$(sum "$mc/stats_15.csv")
signal_after 2 INT mc_int -- "$sdins" montecarlo --duration 600 --runs 400 --models 15 --threads 1 --out "$mc"
[ "$rc" = 130 ] || { cat "$out/mc_int.log"; fail "montecarlo SIGINT: exit $rc, expected 130"; }
says mc_int "SIGINT"; says mc_int "runs"
absent "$mc/summary.json"  # the completion marker: this directory holds no complete run
unchanged "$mc/stats_15.csv" "$hs"  # not half-written: the previous run's file (or a complete new one)
no_temporaries "$mc"

# fsw: SIGTERM while waiting for a run: summary printed, --json and log complete, exit 143.
port=$((20000 + RANDOM % 20000))
signal_after 1 TERM fsw_term -- "$sdins" fsw --can "udp:$port" --idle-timeout 60 --lcm-url none \
  --log "$out/fsw.lcmlog" --json "$out/fsw.json"
[ "$rc" = 143 ] || { cat "$out/fsw_term.log"; fail "fsw SIGTERM: exit $rc, expected 143"; }
says fsw_term "stopped by SIGTERM"; says fsw_term "nav frames:"
python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); assert j["exit"]=="stopped", j["exit"]' "$out/fsw.json" ||
  fail "fsw --json not complete"
[ -f "$out/fsw.lcmlog" ] || fail "fsw: the log is missing"
no_temporaries "$out"

# bus-sim: SIGINT while waiting for a flight software that never answers.
signal_after 1 INT bus_sim_int -- "$sdins" bus-sim --lockstep --can "udp:$((port + 1))" --ack-timeout 60 --duration 10 \
  --json "$out/bus.json"
[ "$rc" = 130 ] || { cat "$out/bus_sim_int.log"; fail "bus-sim SIGINT: exit $rc, expected 130"; }
says bus_sim_int "stopped"
python3 -c 'import json,sys; json.load(open(sys.argv[1]))' "$out/bus.json" || fail "bus-sim --json not complete"

# replay: SIGINT in the middle of a 600 s log: the summary so far, no log, no JSON.
"$sdins" sim --seed 1 --duration 600 --log "$out/long.lcmlog" > /dev/null 2>&1 || fail "sim setup"
echo "previous" > "$out/replay_out.lcmlog"
signal_when "$out" INT replay_int -- "$sdins" replay "$out/long.lcmlog" --log "$out/replay_out.lcmlog" --json "$out/replay.json"
[ "$rc" = 130 ] || { cat "$out/replay_int.log"; fail "replay SIGINT: exit $rc, expected 130"; }
says replay_int "replay stopped after"; says replay_int "navigation frames"
[ "$(cat "$out/replay_out.lcmlog")" = previous ] || fail "replay: the previous --log was replaced by a partial one"
absent "$out/replay.json"
no_temporaries "$out"

# diagnose: SIGTERM during the candidate runs: no --json, no report directory marker.
signal_after 0.3 TERM diagnose_term -- "$sdins" diagnose --log "$out/long.lcmlog" --json "$out/diag.json" --report "$out/diag"
[ "$rc" = 143 ] || { cat "$out/diagnose_term.log"; fail "diagnose SIGTERM: exit $rc, expected 143"; }
absent "$out/diag.json"; absent "$out/diag/summary.json"

# SIGKILL in the middle of writing: nothing can clean up, and nothing needs to: the output has no
# name until it is complete, so the previous log stays and no file is left beside it.
echo "previous" > "$out/kill_out.lcmlog"
"$sdins" replay "$out/long.lcmlog" --log "$out/kill_out.lcmlog" > "$out/replay_kill.log" 2>&1 &
pid=$!
n=0
until writing_in "$out" "$pid"; do
  kill -0 "$pid" 2> /dev/null || fail "replay_kill: finished before its output was open"
  n=$((n + 1)); [ $n -lt 20000 ] || { kill -KILL "$pid"; fail "replay_kill: no output opened"; }
done
sleep 0.2
kill -KILL "$pid"; wait "$pid" 2> /dev/null
cases=$((cases + 1))
[ "$(cat "$out/kill_out.lcmlog")" = previous ] || fail "replay SIGKILL: the previous --log was replaced"
no_temporaries "$out"
[ "$(ls -A "$out" | grep -c kill_out)" = 1 ] || fail "replay SIGKILL: files left beside the log"

# sim (not polled): SIGINT ends it at once; the previous log stays, no temporary is left.
echo "previous" > "$out/sim.lcmlog"
signal_after 1 INT sim_int -- "$sdins" sim --seed 1 --duration 20000 --log "$out/sim.lcmlog"
[ "$rc" = 130 ] || { cat "$out/sim_int.log"; fail "sim SIGINT: exit $rc, expected 130"; }
[ "$(cat "$out/sim.lcmlog")" = previous ] || fail "sim: the previous log was lost"
no_temporaries "$out"
done_ok
