#!/usr/bin/env bash
# Numeric options: NaN and infinities are refused at the command line by every floating-point
# option (one validator, tools/sdins/numeric_options.cpp), before anything runs or waits.
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib.sh"
# (An option with a range check of its own may refuse an infinity first, with its own message.)
for v in nan NaN -nan inf -inf infinity 1e999; do
  run nonzero "fsw_idle_$v" -- "$sdins" fsw --can loop:x --idle-timeout "$v"
  says "fsw_idle_$v" "--idle-timeout"
  case $v in *nan | *NaN) says "fsw_idle_$v" "not a finite number" ;; esac
done
run nonzero bus_sim_ack -- "$sdins" bus-sim --can loop:x --ack-timeout nan
says bus_sim_ack "not a finite number"
run nonzero fly_duration -- "$sdins" fly --duration nan
says fly_duration "--duration"
run nonzero replay_outages -- "$sdins" replay /dev/null --outages nan 10 0
says replay_outages "--outages"
run nonzero replay_outages_inf -- "$sdins" replay /dev/null --outages 1 inf 0
run nonzero diagnose_alpha -- "$sdins" diagnose --log /dev/null --json "$out/x.json" --alpha inf
run nonzero import_fit -- "$sdins" import psins "$out" --log "$out/x.lcmlog" --max-fit-error nan
says import_fit "--max-fit-error"
run nonzero can_play_gap -- "$sdins" can play /dev/null --can loop:x --gap -inf
run nonzero montecarlo_dur -- "$sdins" montecarlo --duration 1e999 --runs 1 --out "$out/mc"
absent "$out/mc"
absent "$out/x.json"; absent "$out/x.lcmlog"
# Finite values still pass the validator.
run 0 fly_ok -- "$sdins" fly --duration 1.5
done_ok
