#!/usr/bin/env bash
# Option values (docs/faults.md, "Numeric options", "Text options", "Option combinations"): one
# validator per kind in the option parser (tools/sdins/numeric_options.cpp) refuses, naming the option
# and the value, what CLI11 would otherwise clamp, wrap or re-read; options that would do nothing are
# refused by the parser (CLI11 needs/excludes, --outages' own rule); nothing is created.
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib.sh"
# Integers: beyond 64 bits (CLI11 clamped it to 2^63-1 without a word), octal-looking, hex, signs.
for v in 99999999999999999999 9223372036854775808 -99999999999999999999; do
  run nonzero "seed_$v" -- "$sdins" sim --seed "$v" --duration 1 --log "$out/s.lcmlog"
  says "seed_$v" "--seed"
  case $v in 99999999999999999999) says "seed_$v" "does not fit in 64 bits" ;; esac
done
run nonzero seed_octal -- "$sdins" sim --seed 010 --duration 1 --log "$out/s.lcmlog"
says seed_octal "leading zero"
run nonzero seed_hex -- "$sdins" sim --seed 0x10 --duration 1 --log "$out/s.lcmlog"
says seed_hex "not a decimal integer"
run nonzero runs_big -- "$sdins" montecarlo --runs 99999999999999999999 --duration 1 --out "$out/mc"
says runs_big "--runs"
run nonzero show_rej_neg -- "$sdins" log info /dev/null --show-rejections -1
says show_rej_neg "is negative"
absent "$out/s.lcmlog"; absent "$out/mc"
run 0 seed_max -- "$sdins" sim --seed 9223372036854775807 --duration 1 --log "$out/s.lcmlog"
grep -q '"seed": 9223372036854775807' "$out/s.lcmlog.json" || fail "seed_max: the sidecar does not keep the seed"
# --outages: a period of 0 or a negative length withheld nothing and exited 0.
make_log "$out/in.lcmlog"
for o in "1 0 0" "-5 10 0" "0 10 0" "20 10 0" "1 10 -3"; do
  name="outages_${o// /_}"
  # shellcheck disable=SC2086
  run nonzero "$name" -- "$sdins" replay "$out/in.lcmlog" --outages $o
  says "$name" "--outages"
done
says "outages_1_0_0" "PERIOD must be > 0"
says "outages_-5_10_0" "LENGTH must be > 0"
run 0 outages_ok -- "$sdins" replay "$out/in.lcmlog" --outages 2 5 1
says outages_ok "inputs withheld"
# Timeouts: not positive is refused (a negative one waited forever).
for t in 0 -1 -0.5; do
  run nonzero "record_timeout_$t" -- "$sdins" can record --can loop:x --out "$out/r.log" --timeout "$t"
  says "record_timeout_$t" "--timeout"
  run nonzero "dump_timeout_$t" -- "$sdins" can dump --can loop:x --timeout "$t"
done
run nonzero record_count_neg -- "$sdins" can record --can loop:x --out "$out/r.log" --count -5
absent "$out/r.log"
# Options that would do nothing.
run nonzero play_speed -- "$sdins" can play /dev/null --can loop:x --speed 2
says play_speed "--realtime"
run nonzero play_gap_rt -- "$sdins" can play /dev/null --can loop:x --realtime --gap 0.1
says play_gap_rt "--realtime"
run nonzero bus_sim_window -- "$sdins" bus-sim --can loop:x --realtime --window 5
says bus_sim_window "--lockstep"
run nonzero bus_sim_speed -- "$sdins" bus-sim --can loop:x --lockstep --speed 2
says bus_sim_speed "--realtime"
run nonzero fsw_prio -- "$sdins" fsw --can loop:x --fifo-priority 10
says fsw_prio "--realtime"
# Duplicates and unreadable-back values (found by the hostile pass, docs/faults.md).
run nonzero models_twice -- "$sdins" montecarlo --runs 2 --duration 5 --models 15,15 --out "$out/mm"
says models_twice "given twice"
absent "$out/mm"
run nonzero iface_blank -- "$sdins" can encode --duration 1 --out "$out/e.log" --iface "a b"
says iface_blank "interface name 'a b'"
run nonzero iface_empty -- "$sdins" can encode --duration 1 --out "$out/e.log" --iface ""
absent "$out/e.log"
run nonzero import_fit_neg -- "$sdins" import psins "$out" --log "$out/../imp.lcmlog" --max-fit-error -1
says import_fit_neg "--max-fit-error"
# Text: a file name that is not UTF-8 ended in a JSON library's exception after the log was
# written, leaving it without its sidecar. Refused at parse time naming the option; nothing written.
bad=$(printf 'caf\xe9.lcmlog')
run nonzero name_latin1 -- "$sdins" sim --seed 1 --duration 1 --log "$out/$bad"
says name_latin1 "--log"
says name_latin1 "not valid UTF-8"
absent "$out/$bad"; absent "$out/$bad.json"
run nonzero name_latin1_replay -- "$sdins" replay "$out/in.lcmlog" --json "$out/$bad"
absent "$out/$bad"
good=$(printf 'caf\xc3\xa9.lcmlog')
run 0 name_utf8 -- "$sdins" sim --seed 1 --duration 1 --log "$out/$good"
[ -f "$out/$good" ] && [ -f "$out/$good.json" ] || fail "name_utf8: the log and its sidecar are not both there"
# The log and its sidecar, both or neither: a sidecar that cannot be written leaves no log.
mkdir -p "$out/side.lcmlog.json"
run 1 sidecar_dir -- "$sdins" sim --seed 1 --duration 2 --log "$out/side.lcmlog"
says sidecar_dir "side.lcmlog.json: is a directory"
absent "$out/side.lcmlog"
no_temporaries "$out"
done_ok
