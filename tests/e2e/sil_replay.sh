#!/usr/bin/env bash
# End to end: `sdins sil` flies the built-in scenario through the in-process CAN bus into the
# flight software and writes an LCM log; `sdins replay` re-runs the flight software on that log
# and must reproduce the run's navigation digest bit for bit, twice; a truncated and a corrupted
# copy of the log replay without crashing, with the damage counted.
set -euo pipefail
sdins=${1:?usage: sil_replay.sh SDINS OUTDIR}
out=${2:?usage: sil_replay.sh SDINS OUTDIR}
rm -rf "$out" && mkdir -p "$out"
"$sdins" sil --duration 150 --seed 4 --log "$out/sil.lcmlog" --lcm-url none --json "$out/sil.json"
"$sdins" replay "$out/sil.lcmlog" --json "$out/replay1.json" --log "$out/replay1.lcmlog"
"$sdins" replay "$out/sil.lcmlog" --json "$out/replay2.json"
"$sdins" replay "$out/replay1.lcmlog" --json "$out/replay3.json"   # the replay's own log is replayable
# Cut two thirds in, in the middle of an event (a cut on an event boundary is a shorter, valid log).
/usr/bin/python3 - "$out/sil.lcmlog" "$out/truncated.lcmlog" <<'PY'
import struct, sys
b = open(sys.argv[1], "rb").read()
i = b.rfind(b"\xed\xa1\xda\x01", 0, len(b) * 2 // 3)  # the LCM sync word of the event there
channel_len, data_len = struct.unpack(">ii", b[i + 20:i + 28])
open(sys.argv[2], "wb").write(b[:i + 28 + channel_len + data_len // 2])
PY
cp "$out/sil.lcmlog" "$out/corrupt.lcmlog"
# 4 KiB of garbage in the middle (random bytes from a fixed seed).
/usr/bin/python3 - "$out/corrupt.lcmlog" <<'PY'
import random, sys
p = sys.argv[1]
b = bytearray(open(p, "rb").read())
r = random.Random(7)
start = len(b) // 2
for i in range(start, start + 4096):
    b[i] = r.randrange(256)
open(p, "wb").write(bytes(b))
PY
"$sdins" replay "$out/truncated.lcmlog" --json "$out/truncated.json"
"$sdins" replay "$out/corrupt.lcmlog" --json "$out/corrupt.json"
/usr/bin/python3 - "$out" <<'PY'
import json, sys
d = sys.argv[1]
sil = json.load(open(f"{d}/sil.json"))
r1, r2, r3 = (json.load(open(f"{d}/replay{k}.json")) for k in (1, 2, 3))
tr, co = json.load(open(f"{d}/truncated.json")), json.load(open(f"{d}/corrupt.json"))
assert sil["mode"] == "sil" and sil["initialised"], sil
assert sil["nav_frames"] > 29000, sil["nav_frames"]
e = sil["final_error"]
assert sum(x * x for x in e["pos_enu_m"]) ** 0.5 < 15.0, e
assert sum(x * x for x in e["vel_enu_mps"]) ** 0.5 < 0.3, e
assert all(abs(a) < 0.05 for a in e["att_enu_deg"]), e
assert sil["executive"]["fsw_errors"] == 0 and sil["executive"]["cov_repairs"] == 0
assert sil["can_rx"]["rejections"] == 0, sil["can_rx"]
for r in (r1, r2, r3):
    assert r["digest"] == sil["digest"], (r["digest"], sil["digest"])
    assert r["nav_frames"] == sil["nav_frames"]
assert r1["inputs"]["rejected"] == 0 and r1["inputs"]["log_rejections"] == 0, r1["inputs"]
# Damaged logs: counted, never silent; the flight software still initialises and flies what is left.
assert tr["inputs"]["log_rejections"] >= 1 and tr["initialised"], tr["inputs"]
assert 0 < tr["nav_frames"] < sil["nav_frames"], tr["nav_frames"]
assert co["inputs"]["log_rejections"] + co["inputs"]["rejected"] >= 1 and co["initialised"], co["inputs"]
assert co["nav_frames"] > 0.9 * sil["nav_frames"], co["nav_frames"]
print("sil/replay ok: digest", sil["digest"], "| truncated:", tr["inputs"]["log_rejections"], "rejections,",
      tr["nav_frames"], "frames | corrupt:", co["inputs"]["log_rejections"], "+", co["inputs"]["rejected"], "rejections,",
      co["nav_frames"], "frames")
PY
