#!/usr/bin/env bash
# End-to-end: `sdins analyze` on a shortened default scenario writes every promised output and the
# analysis names gamma_yz and gamma_zy (and only them) as accumulating the heading error.
set -euo pipefail
sdins=${1:?usage: analyze.sh SDINS OUTDIR}
out=${2:?usage: analyze.sh SDINS OUTDIR}
rm -rf "$out"
"$sdins" analyze --out "$out" --duration 600
for f in analysis.json summary.md alignment.csv turns.csv bank_turn.png rotation.png \
         bank_turn_xy.csv bank_turn_zy.csv rotation_z_xz_5.csv rotation_x_zx_10.csv; do
  [ -s "$out/$f" ] || { echo "missing or empty: $out/$f"; exit 1; }
done
/usr/bin/python3 - "$out/analysis.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
bt = j["bank_turn"]
assert sorted(bt) == ["xy", "xz", "yx", "yz", "zx", "zy"], sorted(bt)
for name, c in bt.items():
    assert isinstance(c["accumulates"], bool) and isinstance(c["u_error_per_turn_arcsec"], float), name
    assert c["accumulates"] == (name in ("yz", "zy")), (name, c)
assert bt["yz"]["u_error_per_turn_arcsec"] > 20 and bt["zy"]["u_error_per_turn_arcsec"] > 20
assert len(j["single_axis_rotation"]) == 12
assert all(r["deviation_pct_of_peak"] < 2.0 for r in j["single_axis_rotation"])
print("analysis.json ok:", {k: round(v["u_error_per_turn_arcsec"], 2) for k, v in bt.items()})
PY
