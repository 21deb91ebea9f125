# Sourced by the end-to-end shell tests: expect_error WANT COMMAND... runs the command, which must
# fail, and its output (stdout and stderr, kept in $work/err.txt) must contain WANT (a fixed string).
expect_error() {
  local want=$1
  shift
  if "$@" > "$work/err.txt" 2>&1; then
    echo "expected a refusal: $*"
    exit 1
  fi
  grep -qF -- "$want" "$work/err.txt" || { echo "the refusal does not name '$want':"; cat "$work/err.txt"; exit 1; }
}
