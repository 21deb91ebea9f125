#!/usr/bin/env bash
# End to end: the commands fly the shipped flight configuration (config/README.md). A SIL log
# replays to the run's digest with and without the shipped file given explicitly; a data
# directory whose config/default.toml says something else changes what replay and montecarlo fly
# (so they read the file, not defaults in code); a broken or missing file stops them with its
# error; a renamed key is refused naming its new spelling; every command's --help lists the
# filter models with the same names.
set -euo pipefail
sdins=${1:?usage: flight_config.sh SDINS OUTDIR}
out=${2:?usage: flight_config.sh SDINS OUTDIR}
rm -rf "$out" && mkdir -p "$out"
data="$(dirname "$sdins")/../share/sdins"
shipped="$data/config/default.toml"
[ -f "$shipped" ] || { echo "no shipped flight configuration at $shipped"; exit 1; }

"$sdins" sil --duration 40 --seed 4 --log "$out/sil.lcmlog" --lcm-url none --json "$out/sil.json" > /dev/null
"$sdins" replay "$out/sil.lcmlog" --json "$out/replay.json" > /dev/null
"$sdins" replay "$out/sil.lcmlog" --filter-config "$shipped" --json "$out/replay_shipped.json" > /dev/null

# A data directory that differs only in the shipped file's white pseudorange noise and ARW.
cp -r "$data" "$out/data"
sed -i -e 's/^pseudorange_sigma_m = 0.3$/pseudorange_sigma_m = 0.6/' -e 's/^arw_rad_per_rts = 2e-7$/arw_rad_per_rts = 4e-7/' \
  "$out/data/config/default.toml"
! cmp -s "$shipped" "$out/data/config/default.toml" || { echo "the edit of the copied default.toml did not apply"; exit 1; }
"$sdins" --data-dir "$out/data" replay "$out/sil.lcmlog" --json "$out/replay_changed.json" > /dev/null
"$sdins" montecarlo --runs 2 --duration 60 --models 15 --threads 1 --out "$out/mc" > /dev/null
"$sdins" --data-dir "$out/data" montecarlo --runs 2 --duration 60 --models 15 --threads 1 --out "$out/mc_changed" > /dev/null

# A broken or missing shipped file is an error that names it, before anything is flown.
cp -r "$data" "$out/broken"
echo 'gate_chi2 = "x"' >> "$out/broken/config/default.toml"
if "$sdins" --data-dir "$out/broken" replay "$out/sil.lcmlog" --json "$out/broken.json" 2> "$out/broken.err"; then
  echo "replay flew with a broken shipped configuration"; exit 1
fi
grep -q "default.toml" "$out/broken.err" || { cat "$out/broken.err"; exit 1; }
[ ! -e "$out/broken.json" ] || { echo "output written despite the error"; exit 1; }
rm "$out/broken/config/default.toml"
if "$sdins" --data-dir "$out/broken" montecarlo --runs 2 --duration 10 --out "$out/mc_broken" 2> "$out/missing.err"; then
  echo "montecarlo flew without the shipped configuration"; exit 1
fi
grep -q "default.toml" "$out/missing.err" || { cat "$out/missing.err"; exit 1; }

# A key renamed to carry its unit is refused with the new name.
printf '[gps]\nclock_h0 = 2e-19\n' > "$out/old.toml"
if "$sdins" sil --scenario "$out/old.toml" --duration 5 --lcm-url none 2> "$out/old.err"; then
  echo "the old key clock_h0 was accepted"; exit 1
fi
grep -q "'gps.clock_h0' was renamed to 'gps.clock_h0_s'" "$out/old.err" || { cat "$out/old.err"; exit 1; }

# One model selector: the same names and meanings in every command's help.
for c in sil replay fsw diagnose montecarlo; do "$sdins" $c --help > "$out/help_$c.txt" 2>&1 || true; done

/usr/bin/python3 - "$out" <<'PY'
import json, re, sys
d = sys.argv[1]
j = lambda n: json.load(open(f"{d}/{n}"))
sil, rep, shp, chg = j("sil.json"), j("replay.json"), j("replay_shipped.json"), j("replay_changed.json")
assert sil["initialised"], sil
assert rep["digest"] == sil["digest"] == shp["digest"], (rep["digest"], sil["digest"], shp["digest"])
assert chg["digest"] != sil["digest"], "replay did not fly the data directory's default.toml"
mc, mcc = j("mc/summary.json"), j("mc_changed/summary.json")
a, b = mc["models"][0]["final_filter_sigma_deg"], mcc["models"][0]["final_filter_sigma_deg"]
assert a != b, ("montecarlo did not fly the data directory's default.toml", a, b)
flight = "15 (15-state, misalignments as consider states), 24 (24-state, misalignments estimated)"
for c in ("sil", "replay", "fsw"):
    h = " ".join(open(f"{d}/help_{c}.txt").read().split())
    assert flight in h, (c, h)
# The diagnosis takes the same model names (one selector) but its 15-state baseline has no consider
# states: the misalignments are left out of it and tested as candidates.
h = " ".join(open(f"{d}/help_diagnose.txt").read().split())
assert "--baseline TEXT:{15,24}=15" in h and "misalignments are not modelled" in h and "consider" not in h, h
h = " ".join(open(f"{d}/help_montecarlo.txt").read().split())
assert flight + ", 15c (" in h and ", 15t (" in h, h
print("flight config ok: digest", sil["digest"], "with and without the shipped file; changed file ->", chg["digest"],
      "| montecarlo U filter sigma", a["U"], "->", b["U"])
PY
