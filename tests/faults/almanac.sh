#!/usr/bin/env bash
# One almanac validation for the simulator and the flight software: an impossible orbit or clock is
# refused by `sim` as it is by `replay`; a Monte Carlo run that used no pseudorange says so and
# fails (exit 2, gnss_used false).
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib.sh"
alm=${data:+$data/almanac/yuma-week431.alm}
[ -f "$alm" ] || { echo "SKIP: no almanac in $data"; exit 77; }
sed '0,/^SQRT(A)/s/^\(SQRT(A)[^:]*:\s*\).*/\11.0E+030/' "$alm" > "$out/sqrta.alm"
sed '0,/^Af0/s/^\(Af0[^:]*:\s*\).*/\11.0E+006/' "$alm" > "$out/af0.alm"
for bad in sqrta af0; do
  printf '[gps]\nalmanac = "%s"\n' "$out/$bad.alm" > "$out/$bad.toml"
  run 1 "sim_$bad" -- "$sdins" sim --seed 1 --scenario "$out/$bad.toml" --duration 2 --log "$out/$bad.lcmlog"
  says "sim_$bad" "$bad.alm"; says "sim_$bad" "fsw::almanac_valid"
  absent "$out/$bad.lcmlog"
  run 1 "mc_$bad" -- "$sdins" montecarlo --scenario "$out/$bad.toml" --duration 2 --runs 1 --out "$out/mc_$bad"
done
# every satellite unhealthy: no pseudorange used, the Monte Carlo says so and exits 2
sed 's/^\(Health:\s*\)000/\1063/' "$alm" > "$out/unhealthy.alm"
printf '[gps]\nalmanac = "%s"\n' "$out/unhealthy.alm" > "$out/unhealthy.toml"
run 2 mc_unhealthy -- "$sdins" montecarlo --scenario "$out/unhealthy.toml" --duration 30 --runs 2 --models 15 --out "$out/mc"
says mc_unhealthy "no pseudorange was used"
python3 -c 'import json,sys; assert json.load(open(sys.argv[1]))["gnss_used"] is False' "$out/mc/summary.json" ||
  fail "summary.json does not say gnss_used false"
done_ok
