#!/usr/bin/env bash
# Run directories (docs/faults.md, "run directories"): the outputs of a run are exactly the files
# its summary.json names. A re-run with fewer models removes the previous run's files it did not
# write again (listed in the directory's manifest, .sdins-outputs.json); a file the tool did not
# write is never touched.
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib.sh"
mc="$out/mc"
outputs() { python3 -c "import json,sys; print(' '.join(json.load(open(sys.argv[1]))['outputs']))" "$1/summary.json"; }
run 0 mc_two -- "$sdins" montecarlo --runs 2 --duration 65 --models 15,24 --out "$mc"
[ "$(outputs "$mc")" = "stats_15.csv stats_24.csv" ] || fail "mc_two: summary names '$(outputs "$mc")'"
echo "my notes" > "$mc/notes.txt"
cp "$mc/stats_15.csv" "$mc/my_copy.csv"
run 0 mc_one -- "$sdins" montecarlo --runs 2 --duration 65 --models 24 --out "$mc"
[ "$(outputs "$mc")" = "stats_24.csv" ] || fail "mc_one: summary names '$(outputs "$mc")'"
absent "$mc/stats_15.csv"
[ -f "$mc/stats_24.csv" ] || fail "mc_one: stats_24.csv missing"
[ "$(cat "$mc/notes.txt")" = "my notes" ] || fail "a file the tool did not write was changed"
[ -f "$mc/my_copy.csv" ] || fail "a file the tool did not write was removed"
# Exactly the files named, plus the summary, the manifest and the user's two files.
n=$(find "$mc" -type f | wc -l)
[ "$n" = 5 ] || { ls -la "$mc" >&2; fail "mc_one: $n files in the directory, expected 5"; }
# A damaged manifest is refused naming it (nothing is removed on a guess).
echo "{not json" > "$mc/.sdins-outputs.json"
run 1 manifest_bad -- "$sdins" montecarlo --runs 2 --duration 65 --models 15 --out "$mc"
says manifest_bad ".sdins-outputs.json"
[ -f "$mc/stats_24.csv" ] || fail "manifest_bad: a file was removed"
# Two runs into one directory would remove each other's outputs: the second is refused while the
# first holds the directory's lock (held here by flock(1), as a running sdins holds it).
rm -f "$mc/.sdins-outputs.json"
flock "$mc" sleep 5 &
holder=$!
sleep 0.5
run 1 concurrent -- "$sdins" montecarlo --runs 2 --duration 65 --models 15 --out "$mc"
says concurrent "another sdins run is writing into this directory"
kill "$holder" 2> /dev/null; wait "$holder" 2> /dev/null
[ -f "$mc/stats_24.csv" ] || fail "concurrent: a file was removed"
# An output that is a loop of symbolic links is refused; the links stay (it used to replace one of
# them with a regular file).
ln -s "$out/lb" "$out/la"
ln -s "$out/la" "$out/lb"
run 1 link_loop -- "$sdins" fly --duration 1 --csv "$out/la"
says link_loop "Too many levels of symbolic links"
[ -L "$out/la" ] && [ -L "$out/lb" ] || fail "link_loop: a link was replaced"
no_temporaries "$mc"
done_ok
