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
echo "mpi equivalence ok ($("$mpiexec" --version 2>&1 | head -1))"
