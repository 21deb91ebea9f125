#!/usr/bin/env bash
# End-to-end: `mpirun -np K sdins montecarlo` writes the same results as one process.
#   usage: mpi_equivalence.sh SDINS OUTDIR HAVE_MPI [MPIEXEC]
# HAVE_MPI: whether sdins was built with MPI (CMake's SDINS_HAVE_MPI); MPIEXEC: the launcher CMake
# found (default: mpirun on PATH). Exits 77 (CTest: skipped) when either is missing.
# Checks, all with --runs 4 --duration 120 against a plain single-process --threads 1 run:
#   - mpirun -np 2 (default threads: 1 per rank) and -np 3 (uneven blocks 1/1/2, oversubscribed)
#     and -np 1: stats_*.csv byte-identical, summary.json identical without "timing",
#     timing.mpi_ranks = K (the ranks did form one world), only rank 0 printed the table;
#   - a failure on one rank (test hook SDINS_TEST_FAIL_RANK) fails the whole job quickly with the
#     rank's message instead of hanging.
set -euo pipefail
sdins=${1:?usage: mpi_equivalence.sh SDINS OUTDIR HAVE_MPI [MPIEXEC]}
out=${2:?usage: mpi_equivalence.sh SDINS OUTDIR HAVE_MPI [MPIEXEC]}
have_mpi=${3:?usage: mpi_equivalence.sh SDINS OUTDIR HAVE_MPI [MPIEXEC]}
mpiexec=${4:-}
here=$(cd "$(dirname "$0")" && pwd)

case "$have_mpi" in
  ON|on|1|TRUE|true|YES|yes) ;;
  *) echo "SKIP: sdins was built without MPI (install libopenmpi-dev openmpi-bin and reconfigure)"; exit 77 ;;
esac
if [ -z "$mpiexec" ] || [ ! -x "$mpiexec" ]; then mpiexec=$(command -v mpirun || true); fi
if [ -z "$mpiexec" ]; then echo "SKIP: mpirun is not installed (Debian: openmpi-bin)"; exit 77; fi

# Open MPI refuses root without these and counts cores for -np; both are harmless elsewhere.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
launch=("$mpiexec")
if "$mpiexec" --version 2>&1 | grep -qi -e "open mpi" -e openrte -e open-mpi; then launch+=(--oversubscribe); fi
limit=120  # seconds per launch: a hung job fails the test instead of stalling CTest

rm -rf "$out"
mkdir -p "$out"
args=(montecarlo --runs 4 --duration 120)
"$sdins" "${args[@]}" --threads 1 --out "$out/single" > "$out/single.log"

for np in 2 3 1; do
  dir="$out/np$np"
  if ! timeout "$limit" "${launch[@]}" -np "$np" "$sdins" "${args[@]}" --out "$dir" > "$dir.log" 2> "$dir.err"; then
    echo "mpirun -np $np failed:"; cat "$dir.log" "$dir.err"; exit 1
  fi
  /usr/bin/python3 "$here/compare_montecarlo.py" "$out/single" "$dir"
  ranks=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["timing"]["mpi_ranks"])' "$dir/summary.json")
  [ "$ranks" = "$np" ] || { echo "-np $np: summary.json says mpi_ranks = $ranks (not one MPI world?)"; exit 1; }
  tables=$(grep -c "^outputs in " "$dir.log" || true)
  [ "$tables" = 1 ] || { echo "-np $np: $tables ranks printed results, expected only rank 0"; cat "$dir.log"; exit 1; }
done

# An error on one rank aborts the job (non-zero exit, the rank's message), never hangs.
for rank in 1 0; do
  rc=0
  SDINS_TEST_FAIL_RANK=$rank timeout "$limit" "${launch[@]}" -np 2 "$sdins" montecarlo --runs 2 --duration 20 \
    --out "$out/fail$rank" > "$out/fail$rank.log" 2>&1 || rc=$?
  if [ "$rc" = 0 ] || [ "$rc" = 124 ]; then
    echo "failure on rank $rank: exit code $rc (expected a failed job, 124 = hung)"; cat "$out/fail$rank.log"; exit 1
  fi
  grep -q "sdins: error on MPI rank $rank of 2: injected failure" "$out/fail$rank.log" ||
    { echo "failure on rank $rank: message missing"; cat "$out/fail$rank.log"; exit 1; }
  echo "failure on rank $rank: job failed with exit code $rc and the rank's message"
done
# SIGINT to mpirun while the ranks fly (docs/faults.md): mpirun forwards SIGTERM to every rank and
# kills them 1 s later; each rank stops within a frame, says how far it got and writes nothing: the
# previous run's CSVs stay as they were, and its completion marker summary.json is gone (the
# directory no longer holds one complete run).
prev="$out/np2"
sum_before=$(md5sum "$prev"/stats_*.csv)
"${launch[@]}" -np 2 "$sdins" montecarlo --runs 4000 --duration 120 --out "$prev" > "$out/int.log" 2>&1 &
mpid=$!
# Signal once both ranks have spent 2 s of CPU (past MPI start-up and the truth generation).
for _ in $(seq 600); do
  busy=0
  for p in $(pgrep -P "$mpid" -f "sdins montecarlo" || true); do
    read -r -a st < "/proc/$p/stat" 2> /dev/null || continue
    [ $((st[13] + st[14])) -ge 200 ] && busy=$((busy + 1))
  done
  [ "$busy" -ge 2 ] && break
  sleep 0.1
done
[ "$busy" -ge 2 ] || { echo "SIGINT case: the ranks did not start flying"; kill -KILL "$mpid"; cat "$out/int.log"; exit 1; }
kill -INT "$mpid"
rc=0; timeout 30 tail --pid="$mpid" -f /dev/null || { echo "SIGINT case: mpirun did not stop within 30 s"; exit 1; }
wait "$mpid" || rc=$?
[ "$rc" != 0 ] || { echo "SIGINT case: exit code 0"; cat "$out/int.log"; exit 1; }
for rank in 0 1; do
  grep -q "sdins: MPI rank $rank of 2: SIGTERM: Monte Carlo stopped after [0-9]* of 2000 runs; no results written" "$out/int.log" ||
    { echo "SIGINT case: rank $rank did not say how far it got"; cat "$out/int.log"; exit 1; }
done
[ "$(md5sum "$prev"/stats_*.csv)" = "$sum_before" ] || { echo "SIGINT case: the previous run's CSVs changed"; exit 1; }
[ ! -e "$prev/summary.json" ] || { echo "SIGINT case: summary.json marks an interrupted run complete"; exit 1; }
if find "$prev" -name '*.sdins-tmp.*' | grep -q .; then echo "SIGINT case: temporary files left"; exit 1; fi
echo "SIGINT to mpirun: both ranks stopped and said so, mpirun exit $rc, previous results intact"
echo "mpi equivalence ok ($("$mpiexec" --version 2>&1 | head -1))"
