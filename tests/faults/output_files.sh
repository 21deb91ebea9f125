#!/usr/bin/env bash
# Output-file discipline: an output that is an input is refused before anything is written; write
# failures (full disk) exit non-zero naming the file and errno; the previous file survives a failure.
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib.sh"
log="$out/in.lcmlog"
make_log "$log"
h=$(sum "$log")
events=$("$sdins" log info --json "$log" | python3 -c 'import json,sys; print(json.load(sys.stdin)["events"])')

# 1. the output is the input: every command, plain path, symlink, hard link, ./ spelling
ln -s in.lcmlog "$out/alias.lcmlog"
ln "$log" "$out/hard.lcmlog"
run nonzero replay_same -- "$sdins" replay "$log" --log "$log"
says replay_same "is the input"; says replay_same "$log"
run nonzero replay_link -- "$sdins" replay "$log" --log "$out/alias.lcmlog"
says replay_link "is the input"
run nonzero replay_json_same -- "$sdins" replay "$log" --json "$out/hard.lcmlog"
says replay_json_same "is the input"
run nonzero export_same -- "$sdins" log export "$log" --channel IMU --csv "$log"
says export_same "is the input"
run nonzero export_dot -- "$sdins" log export "$log" --channel IMU --csv "$out/./in.lcmlog"
run nonzero diagnose_same -- "$sdins" diagnose --log "$log" --json "$log"
says diagnose_same "is the input"
run nonzero outputs_same -- "$sdins" replay "$log" --log "$out/r.lcmlog" --json "$out/r.lcmlog"
says outputs_same "are the same file"
mkdir -p "$out/psins"
echo "tow,gx,gy,gz,ax,ay,az" > "$out/psins/imu_200hz.csv"
hp=$(sum "$out/psins/imu_200hz.csv")
run nonzero import_into_dataset -- "$sdins" import psins "$out/psins" --log "$out/psins/imu_200hz.csv"
says import_into_dataset "$out/psins"
run nonzero import_new_in_dataset -- "$sdins" import psins "$out/psins" --log "$out/psins/new.lcmlog"
says import_new_in_dataset "inside the input directory"
unchanged "$out/psins/imu_200hz.csv" "$hp"
absent "$out/psins/new.lcmlog"
unchanged "$log" "$h"
[ "$("$sdins" log info --json "$log" | python3 -c 'import json,sys; print(json.load(sys.stdin)["events"])')" = "$events" ] ||
  fail "events of the input changed"

# 2. full disk: /dev/full as the output of every writer that takes a path
run nonzero full_sim -- "$sdins" sim --seed 1 --duration 2 --log /dev/full
says full_sim "/dev/full"; says full_sim "No space left on device"
run nonzero full_encode -- "$sdins" can encode --duration 2 --out /dev/full
says full_encode "/dev/full"; says full_encode "No space left on device"
run nonzero full_fly -- "$sdins" fly --duration 5 --csv /dev/full
says full_fly "No space left on device"
run nonzero full_export -- "$sdins" log export "$log" --channel IMU --csv /dev/full
says full_export "No space left on device"
run nonzero full_replay_json -- "$sdins" replay "$log" --json /dev/full
says full_replay_json "/dev/full"; says full_replay_json "No space left on device"
run nonzero full_replay_log -- "$sdins" replay "$log" --log /dev/full
says full_replay_log "No space left on device"
run nonzero full_sil_json -- "$sdins" sil --duration 5 --lcm-url none --json /dev/full
says full_sil_json "No space left on device"
unchanged "$log" "$h"

# 3. a small disk (tmpfs of 64 KiB in a private mount namespace): a regular file that does not fit.
#    The previous file must survive, no temporary file may be left.
if unshare -m true 2> /dev/null; then
  cat > "$out/small_disk.sh" << 'INNER'
set -u
sdins=$1; d=$2; log=$3
mount -t tmpfs -o size=64k tmpfs "$d" || exit 77
echo "previous run" > "$d/x.lcmlog"
echo "previous csv" > "$d/x.csv"
"$sdins" sim --seed 1 --duration 5 --log "$d/x.lcmlog" > "$d/../sim_small.log" 2>&1; echo "sim=$?"
"$sdins" log export "$log" --channel IMU --csv "$d/x.csv" > "$d/../export_small.log" 2>&1; echo "export=$?"
cat "$d/x.lcmlog" "$d/x.csv"
ls -a "$d"
INNER
  mkdir -p "$out/small"
  unshare -m bash "$out/small_disk.sh" "$sdins" "$out/small" "$log" > "$out/small_disk.out" 2>&1
  if ! grep -q "^sim=77" "$out/small_disk.out"; then
    grep -q "^sim=1$" "$out/small_disk.out" || { cat "$out/small_disk.out"; fail "small disk: sim did not fail"; }
    grep -q "^export=1$" "$out/small_disk.out" || { cat "$out/small_disk.out"; fail "small disk: export did not fail"; }
    grep -q "^previous run$" "$out/small_disk.out" || fail "small disk: the previous log was lost"
    grep -q "^previous csv$" "$out/small_disk.out" || fail "small disk: the previous CSV was lost"
    grep -q "sdins-tmp" "$out/small_disk.out" && fail "small disk: a temporary file was left"
    grep -q "No space left on device" "$out/sim_small.log" || fail "small disk: sim message lacks errno"
    grep -q "x.lcmlog" "$out/sim_small.log" || fail "small disk: sim message lacks the file"
    cases=$((cases + 2))
  fi
fi

# 3b. figures (tools/plot/plot_io.py, used by every plot script): written whole or not at all, a
#     failure names the file and the OS error; on the small disk the previous figure survives.
plot_dir=$(cd "$(dirname "$sdins")/../share/sdins/plot" && pwd) || fail "no staged plot scripts beside $sdins"
cat > "$out/figures.py" << 'PY'
import os, sys
sys.path.insert(0, sys.argv[1])
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
from plot_io import OutputError, save_figure
d, big = sys.argv[2], len(sys.argv) > 3
fig = plt.figure(figsize=(20, 20) if big else (2, 2))
plt.plot(range(1000))
target = os.path.join(d, "fig.png")
try:
    save_figure(fig, target, dpi=150 if big else 50)
    print("saved", os.path.getsize(target))
except OutputError as e:
    print("error:", e)
    sys.exit(1)
PY
mkdir -p "$out/fig"
/usr/bin/python3 "$out/figures.py" "$plot_dir" "$out/fig" > "$out/fig_new.log" 2>&1 || { cat "$out/fig_new.log"; fail "figure: not written"; }
fs1=$(sum "$out/fig/fig.png")
/usr/bin/python3 "$out/figures.py" "$plot_dir" "$out/fig" big > "$out/fig_big.log" 2>&1 || fail "figure: not replaced"
[ "$(sum "$out/fig/fig.png")" != "$fs1" ] || fail "figure: the replacement did not land"
[ "$(ls -A "$out/fig")" = fig.png ] || fail "figure: files left beside it: $(ls -A "$out/fig")"
mkdir -p "$out/figdir/fig.png"
run nonzero figure_is_dir -- /usr/bin/python3 "$out/figures.py" "$plot_dir" "$out/figdir"
says figure_is_dir "$out/figdir/fig.png"; says figure_is_dir "Is a directory"
if unshare -m true 2> /dev/null; then
  mkdir -p "$out/figsmall"
  unshare -m bash -c 'mount -t tmpfs -o size=64k tmpfs "$3" || exit 77
    echo previous > "$3/fig.png"
    /usr/bin/python3 "$1" "$2" "$3" big; echo "rc=$?"; cat "$3/fig.png"; ls -A "$3"' _ \
    "$out/figures.py" "$plot_dir" "$out/figsmall" > "$out/fig_small.out" 2>&1
  if ! grep -q "^rc=77" "$out/fig_small.out" && [ -s "$out/fig_small.out" ]; then
    grep -q "^rc=1$" "$out/fig_small.out" || { cat "$out/fig_small.out"; fail "figure on a full disk: not an error"; }
    grep -q "fig.png: No space left on device" "$out/fig_small.out" || { cat "$out/fig_small.out"; fail "figure: message"; }
    [ "$(grep -c . "$out/fig_small.out")" = 4 ] && grep -q "^previous$" "$out/fig_small.out" ||
      { cat "$out/fig_small.out"; fail "figure on a full disk: the previous file was lost or a temporary left"; }
    cases=$((cases + 1))
  fi
fi

# 4. a failing command leaves the previous output as it was (exception path)
echo "previous" > "$out/prev.csv"
run nonzero export_unknown -- "$sdins" log export "$log" --channel NOPE --csv "$out/prev.csv"
[ "$(cat "$out/prev.csv")" = previous ] || fail "previous CSV overwritten by a failed export"
run 0 export_ok -- "$sdins" log export "$log" --channel IMU --csv "$out/prev.csv"
rows=$(($(wc -l < "$out/prev.csv") - 1))
imu=$("$sdins" log info --json "$log" | python3 -c 'import json,sys; print([c["messages"] for c in json.load(sys.stdin)["channels"] if c["channel"]=="IMU"][0])')
[ "$rows" = "$imu" ] || fail "export: $rows rows of $imu IMU messages"
no_temporaries "$out"
done_ok
