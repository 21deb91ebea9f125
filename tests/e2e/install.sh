#!/usr/bin/env bash
# The installed tool stands alone (issue 13): `cmake --install` of the build tree into a prefix,
# the prefix then moved elsewhere (so neither the build tree's nor the first prefix's paths can be
# what it relies on), and the installed sdins run from outside every tree: its help names the
# moved data directory, `sdins paper` (short) writes its outputs and figures, the shipped scenario
# and filter configurations are where the docs say, and the binary holds no path of the source or
# build tree. The Debian package is inspected (contents, dependencies) when cpack and dpkg-deb are
# there; installing it is CI's package stage (.ci/run), which needs root.
# Usage: install.sh SOURCE_DIR BUILD_DIR OUT_DIR
set -euo pipefail
src=$(cd "$1" && pwd) build=$(cd "$2" && pwd) out=$3
rm -rf "$out" && mkdir -p "$out" && out=$(cd "$out" && pwd)
cmake --install "$build" --prefix "$out/prefix" --component sdins > "$out/install.log"
mv "$out/prefix" "$out/moved prefix"
p="$out/moved prefix"
sdins="$p/bin/sdins"
[ -x "$sdins" ] || { echo "no $sdins"; exit 1; }
for f in share/sdins/sdins-data.txt share/sdins/almanac/yuma-week431.alm share/sdins/almanac/README.md \
         share/sdins/scenarios/bank_to_turn.toml share/sdins/config/datasets/gnss-imu-drive.toml \
         share/sdins/can/sdins.dbc share/sdins/lcm/nav_solution_t.lcm share/sdins/plot/plot_paper.py; do
  [ -s "$p/$f" ] || { echo "missing from the install: $f"; exit 1; }
done
# No path of the source or build tree compiled in.
for tree in "$src" "$build"; do
  if grep -a -q -F "$tree" "$sdins"; then
    echo "the installed binary contains the path $tree:"; grep -a -o -F "$tree[^\"]*" "$sdins" | sort -u | head; exit 1
  fi
done
cd "$out"  # outside the source and build trees
unset SDINS_DATA_DIR
"$sdins" --help > help.txt
grep -q -F "Data directory: $(cd "$p/share/sdins" && pwd -P) (beside the executable)" help.txt ||
  { echo "help does not name the installed data directory:"; tail -3 help.txt; exit 1; }
"$sdins" scenario "$p/share/sdins/scenarios/bank_to_turn.toml" > scenario.txt
"$sdins" paper --runs 2 --duration 240 --threads 2 --levels 15 --out "$out/paper" > paper.txt
for f in summary.json report.md mis15/stats_15.csv mis15/stats_24.csv fig18_mis15_15state.png \
         fig19_mis15_24state.png compare_U.png nees.png; do
  [ -s "$out/paper/$f" ] || { echo "installed sdins paper: missing or empty $f"; exit 1; }
done
# A data directory that is not sdins data is refused, naming it (no fall-back to another copy).
mkdir -p not-data
if SDINS_DATA_DIR="$out/not-data" "$sdins" paper --runs 2 --duration 60 --levels 15 --no-plots --no-analysis \
     --out "$out/bad" > bad.txt 2>&1; then
  echo "a non-data SDINS_DATA_DIR was accepted"; exit 1
fi
grep -q "not-data" bad.txt || { echo "the error does not name the directory:"; cat bad.txt; exit 1; }
# --data-dir points at the moved data as well.
"$sdins" --data-dir "$p/share/sdins" --help | grep -q "(--data-dir)" || { echo "--data-dir not honoured"; exit 1; }
# The Debian package: its files and its dependencies (installing it needs root: CI's package stage).
if command -v cpack > /dev/null && command -v dpkg-deb > /dev/null; then
  (cd "$build" && cpack -G DEB -B "$out/deb" > "$out/cpack.log" 2>&1) || { cat "$out/cpack.log"; exit 1; }
  deb=$(ls "$out"/deb/sdins_*.deb)
  dpkg-deb -c "$deb" > deb_contents.txt
  for f in ./usr/bin/sdins ./usr/share/sdins/sdins-data.txt ./usr/share/sdins/almanac/yuma-week431.alm \
           ./usr/share/sdins/plot/plot_paper.py ./usr/share/sdins/can/sdins.dbc; do
    grep -q " $f\$" deb_contents.txt || { echo "the package lacks $f"; exit 1; }
  done
  if grep -q "tests\|gtest\|bench" deb_contents.txt; then echo "the package carries test files"; exit 1; fi
  deps=$(dpkg-deb -f "$deb" Depends)
  for d in python3-matplotlib liblcm libstdc++6; do
    case "$deps" in *"$d"*) ;; *) echo "package Depends lacks $d: $deps"; exit 1 ;; esac
  done
  echo "package: $(basename "$deb"), Depends: $deps"
fi
echo "install test passed: $p"
