#!/usr/bin/env bash
# End-to-end: `sdins montecarlo` gives byte-identical statistics (stats_*.csv, summary.json without
# its timing) for 1 and 2 worker threads: runs are reduced in run order whatever thread flew them.
set -euo pipefail
sdins=${1:?usage: montecarlo_threads.sh SDINS OUTDIR}
out=${2:?usage: montecarlo_threads.sh SDINS OUTDIR}
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$out"
args=(montecarlo --runs 4 --duration 120)
"$sdins" "${args[@]}" --threads 1 --out "$out/threads1"
"$sdins" "${args[@]}" --threads 2 --out "$out/threads2"
/usr/bin/python3 "$here/compare_montecarlo.py" "$out/threads1" "$out/threads2"
