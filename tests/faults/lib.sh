# Shared helpers of the fault-case suite (tests/faults/*.sh, CTest label "faults", docs/faults.md).
# Every case asserts: the exit code, that the message names the file, that no input changed
# (checksum before/after), that no partial output is left (nor a temporary file), and where records
# are involved that none of the good ones is lost.
set -uo pipefail
sdins=${1:?usage: SCRIPT SDINS OUTDIR [DATA_DIR]}
out=${2:?usage: SCRIPT SDINS OUTDIR [DATA_DIR]}
data=${SDINS_RECORDINGS_DIR:-${3:-}}  # the recordings (docs/data.md): $SDINS_RECORDINGS_DIR, else the default given
rm -rf "$out"
mkdir -p "$out"
cases=0
fail() { echo "FAIL: $*" >&2; exit 1; }
sum() { sha256sum "$1" | cut -d' ' -f1; }
# run EXPECTED_RC NAME -- CMD...: runs CMD (stdout+stderr to $out/NAME.log) with a 20 s limit.
run() {
  local want=$1 name=$2
  shift 3
  timeout 20 "$@" > "$out/$name.log" 2>&1
  local rc=$?
  [ "$rc" = 124 ] && fail "$name: hung (killed after 20 s): $*"
  if [ "$want" = nonzero ]; then
    [ "$rc" != 0 ] || fail "$name: exit 0, expected failure: $*"
  elif [ "$rc" != "$want" ]; then
    cat "$out/$name.log" >&2
    fail "$name: exit $rc, expected $want: $*"
  fi
  cases=$((cases + 1))
}
# says NAME TEXT: the log of case NAME contains TEXT.
says() { grep -qF -- "$2" "$out/$1.log" || { cat "$out/$1.log" >&2; fail "$1: message lacks '$2'"; }; }
# no_temporaries DIR: no .sdins-tmp. file left in DIR.
no_temporaries() {
  local left
  left=$(find "$1" -maxdepth 2 -name '*.sdins-tmp.*' | head -1)
  [ -z "$left" ] || fail "temporary file left: $left"
}
unchanged() { [ "$(sum "$1")" = "$2" ] || fail "input $1 changed"; }
absent() { [ ! -e "$1" ] || fail "partial output left: $1"; }
done_ok() { echo "$(basename "$0"): $cases cases passed"; }
# A small simulated log (10 s) for the cases that need one.
make_log() {
  "$sdins" sim --seed 1 --duration 10 --log "$1" > /dev/null 2>&1 || fail "sdins sim failed"
}
