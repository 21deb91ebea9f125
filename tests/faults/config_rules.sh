#!/usr/bin/env bash
# A flight configuration that parses but breaks a rule of the flight software (fsw/config_check.hpp)
# is refused at load by every command, naming the file, the key, the value and the rule (cfg::validate),
# never as a bare `bad_config` or as "the flight software never initialised on this log". The case of
# issue 25: a data set at 50 Hz navigation with a 5 Hz EKF keeps the shipped latency of 10 frames,
# which is not below the 10 frames of an EKF step.
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib.sh"
make_log "$out/in.lcmlog"
log_sum=$(sum "$out/in.lcmlog")
cat > "$out/my.toml" <<'TOML'
name = "my-autopilot"
[executive]
imu_samples_per_frame = 1
nav_rate_hz = 50.0
ekf_rate_hz = 5.0
TOML
cfg_sum=$(sum "$out/my.toml")
want="my.toml: executive.ekf_latency_frames = 10 (set in "
rule="must be below the 10 frames per EKF step (nav_rate_hz 50 / ekf_rate_hz 5)"
for cmd in replay diagnose sil fsw; do
  case $cmd in
    replay) run nonzero "$cmd" -- "$sdins" replay "$out/in.lcmlog" --flight-config "$out/my.toml" --json "$out/$cmd.json" ;;
    diagnose) run nonzero "$cmd" -- "$sdins" diagnose --log "$out/in.lcmlog" --flight-config "$out/my.toml" --json "$out/$cmd.json" ;;
    sil) run nonzero "$cmd" -- "$sdins" sil --duration 5 --lcm-url none --flight-config "$out/my.toml" --json "$out/$cmd.json" ;;
    fsw) run nonzero "$cmd" -- "$sdins" fsw --can loop:x --lcm-url none --flight-config "$out/my.toml" --json "$out/$cmd.json" ;;
  esac
  says "$cmd" "$want"; says "$cmd" "$rule"
  grep -q "bad_config\|never initialised" "$out/$cmd.log" && fail "$cmd: the refusal is still a bare status: $(cat "$out/$cmd.log")"
  absent "$out/$cmd.json"
done
# The old option name is an alias of --flight-config.
run nonzero replay_alias -- "$sdins" replay "$out/in.lcmlog" --filter-config "$out/my.toml"
says replay_alias "$rule"
# A file that passes on its own is refused under the Monte Carlo's scenario overlay when the
# overlaid result breaks a rule, and the message names the overlay: a 2 Hz GPS scenario makes the
# EKF step 100 frames, below the file's latency of 150.
printf '[executive]\nekf_latency_frames = 150\n' > "$out/latency.toml"
printf '[gps]\nrate_hz = 2.0\n' > "$out/gps2hz.toml"
run nonzero montecarlo -- "$sdins" montecarlo --runs 1 --duration 10 --scenario "$out/gps2hz.toml" \
  --flight-config "$out/latency.toml" --out "$out/mc"
says montecarlo "the Monte Carlo's scenario overlay (scenario "
says montecarlo "on $out/latency.toml: executive.ekf_latency_frames = 150 must be below the 100 frames per EKF step (nav_rate_hz 200 / ekf_rate_hz 2)"
absent "$out/mc/summary.json"
unchanged "$out/in.lcmlog" "$log_sum"
unchanged "$out/my.toml" "$cfg_sum"
done_ok
