#!/usr/bin/env bash
# Bounded readers: an endless or non-regular input (/dev/zero, a FIFO, a directory) is refused with
# a message naming it, at once (the 20 s limit of run() catches a hang or unbounded growth).
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib.sh"
mkfifo "$out/fifo"
printf '[gps]\nalmanac = "/dev/zero"\n' > "$out/zero_almanac.toml"
for src in /dev/zero "$out/fifo" "$out"; do
  n=$(basename "$src")
  run nonzero "scenario_$n" -- "$sdins" fly --scenario "$src" --duration 1
  says "scenario_$n" "$src"
  run nonzero "candump_$n" -- "$sdins" can dump --log "$src"
  says "candump_$n" "$src"
  run nonzero "lcm_info_$n" -- "$sdins" log info "$src"
  says "lcm_info_$n" "$src"
  run nonzero "replay_$n" -- "$sdins" replay "$src"
  says "replay_$n" "$src"
  run nonzero "filter_config_$n" -- "$sdins" replay /dev/null --filter-config "$src"
  says "filter_config_$n" "$src"
done
run nonzero almanac_zero -- "$sdins" sim --seed 1 --scenario "$out/zero_almanac.toml" --duration 1 --log "$out/za.lcmlog"
says almanac_zero "/dev/zero"; says almanac_zero "not a regular file"
run nonzero candump_play_zero -- "$sdins" can play /dev/zero --can loop:x
says candump_play_zero "/dev/zero"
# The importers' inputs: a recording directory whose IMU CSV is a FIFO / a device.
mkdir -p "$out/psins"
ln -s /dev/zero "$out/psins/imu_200hz.csv"
echo "tow,prn,pr,cp,x,dop" > "$out/psins/gps_obs.csv"
echo "h" > "$out/psins/gps_eph.csv"
run nonzero import_zero -- "$sdins" import psins "$out/psins" --log "$out/psins.lcmlog"
says import_zero "imu_200hz.csv"; says import_zero "not a regular file"
absent "$out/psins.lcmlog"
# A regular candump file with an endless-looking line: bounded, counted, the good frames kept.
{ echo "(1.000000) can0 123#DEADBEEF"; head -c 200000 /dev/zero | tr '\0' 'A'; echo; echo "(1.100000) can0 123#00"; } > "$out/long.log"
run 0 candump_long_line -- "$sdins" can dump --log "$out/long.log" --quiet
says candump_long_line "3 lines, 2 frames, 1 malformed lines"
done_ok
