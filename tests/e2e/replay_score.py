#!/usr/bin/python3
"""End to end: `sdins replay` scores itself, checked against an independent computation.

usage: replay_score.py SDINS WORKDIR

A simulated flight (`sdins sim`, TRUTH = the simulator's truth) is replayed with GNSS outages and
every navigation frame logged (--nav-decimation 1). This script recomputes the score from the
logs alone (`sdins log export` of NAV_SOLUTION and TRUTH): the truth interpolated linearly to each
frame (attitude by normalised quaternion interpolation), position differences through ECEF and
the ENU rotation at the truth (not the radii the scorer uses), Euler angles from the quaternions,
the outage windows from the initialisation time; and requires the scorer's JSON to agree:
horizontal/vertical position, velocity and roll/pitch/heading RMS and maximum, and each outage's
error at its end. The CSV and the outage figure must be written, and a log without TRUTH must
refuse --score-json.
"""
import bisect
import csv
import json
import math
import os
import shutil
import subprocess
import sys

sdins, work = sys.argv[1:3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def run(*args, ok=True):
    p = subprocess.run([sdins, *args], capture_output=True, text=True)
    if ok and p.returncode != 0:
        print(p.stdout, p.stderr)
        raise SystemExit(f"sdins {' '.join(args)} failed with exit {p.returncode}")
    return p


def table(log, channel):
    path = os.path.join(work, channel + ".csv")
    run("log", "export", log, "--channel", channel, "--csv", path)
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


A, F = 6378137.0, 1.0 / 298.257223563
E2 = F * (2 - F)


def ecef(lat, lon, h):
    n = A / math.sqrt(1 - E2 * math.sin(lat) ** 2)
    return ((n + h) * math.cos(lat) * math.cos(lon), (n + h) * math.cos(lat) * math.sin(lon),
            (n * (1 - E2) + h) * math.sin(lat))


def enu_error(nav, ref):
    a, b = ecef(*nav), ecef(*ref)
    d = [a[i] - b[i] for i in range(3)]
    lat, lon = ref[0], ref[1]
    e = -math.sin(lon) * d[0] + math.cos(lon) * d[1]
    n = -math.sin(lat) * math.cos(lon) * d[0] - math.sin(lat) * math.sin(lon) * d[1] + math.cos(lat) * d[2]
    u = math.cos(lat) * math.cos(lon) * d[0] + math.cos(lat) * math.sin(lon) * d[1] + math.sin(lat) * d[2]
    return e, n, u


def euler(q):
    """roll, pitch, heading [rad] of q (w, x, y, z: body -> ENU), C_b_ned = Rz(heading) Ry(pitch) Rx(roll)."""
    w, x, y, z = q
    c = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    ned = [c[1], c[0], [-v for v in c[2]]]  # rows: N, E, D of body -> ENU
    return math.atan2(ned[2][1], ned[2][2]), -math.asin(max(-1.0, min(1.0, ned[2][0]))), math.atan2(ned[1][0], ned[0][0])


def wrap_deg(d):
    return (d + 180.0) % 360.0 - 180.0


class Acc:
    def __init__(self):
        self.n, self.s2, self.mx = 0, 0.0, 0.0

    def add(self, x):
        self.n += 1
        self.s2 += x * x
        self.mx = max(self.mx, abs(x))

    def rms(self):
        return math.sqrt(self.s2 / self.n)


def near(a, b, tol, what):
    assert abs(a - b) <= tol, f"{what}: scorer {a} vs independent {b} (tolerance {tol})"


# 1. The simulated flight and its scored replay.
sim_log = os.path.join(work, "sim.lcmlog")
run("sim", "--seed", "11", "--duration", "150", "--log", sim_log)
out_log, rep_json, score_json = (os.path.join(work, n) for n in ("out.lcmlog", "replay.json", "score.json"))
score_csv, score_png = os.path.join(work, "score.csv"), os.path.join(work, "outages.png")
L, P, F0 = 10.0, 40.0, 30.0
text = run("replay", sim_log, "--nav-decimation", "1", "--log", out_log, "--json", rep_json, "--outages", str(L), str(P),
           str(F0), "--score-json", score_json, "--score-csv", score_csv, "--score-plot", score_png).stdout
print(text)
assert "score against TRUTH" in text and "simulator_truth" in text, "the replay printed no score with the sidecar's label"
assert "NEES" in text and "only as good as the reference's own sigma" in text, "no NEES caveat printed"
for p in (score_csv, score_png):
    assert os.path.getsize(p) > 0, f"{p} not written"
s = json.load(open(score_json))
init = json.load(open(rep_json))["init_t_s"]
assert s["reference"]["label"]["kind"] == "simulator_truth"

# 2. The independent computation.
nav, tru = table(out_log, "NAV_SOLUTION"), table(sim_log, "TRUTH")
tq = list(zip(tru["q_b_n_wxyz[0]"], tru["q_b_n_wxyz[1]"], tru["q_b_n_wxyz[2]"], tru["q_b_n_wxyz[3]"]))
h, v, vel, roll, pitch, head = Acc(), Acc(), Acc(), Acc(), Acc(), Acc()
windows = {}
frames = 0
for k, t in enumerate(nav["t_s"]):
    if nav["valid"][k] != 1 or t < init:
        continue
    frames += 1
    j = bisect.bisect_left(tru["t_s"], t)
    if j == len(tru["t_s"]) or (tru["t_s"][j] != t and (j == 0 or tru["t_s"][j] - tru["t_s"][j - 1] > 1.0)):
        continue
    i0 = j if tru["t_s"][j] == t else j - 1
    w = 0.0 if i0 == j else (t - tru["t_s"][i0]) / (tru["t_s"][j] - tru["t_s"][i0])

    def lerp(key):
        return (1 - w) * tru[key][i0] + w * tru[key][j]

    e, n, u = enu_error((nav["lat_rad"][k], nav["lon_rad"][k], nav["height_m"][k]), (lerp("lat_rad"), lerp("lon_rad"), lerp("height_m")))
    h.add(math.hypot(e, n))
    v.add(u)
    dv = [nav[f"vel_enu_mps[{i}]"][k] - lerp(f"vel_enu_mps[{i}]") for i in range(3)]
    vel.add(math.sqrt(sum(x * x for x in dv)))
    qa, qb = tq[i0], tq[j]
    if sum(a * b for a, b in zip(qa, qb)) < 0:
        qb = [-x for x in qb]
    q = [(1 - w) * a + w * b for a, b in zip(qa, qb)]
    qn = math.sqrt(sum(x * x for x in q))
    r_ref = euler([x / qn for x in q])
    r_nav = (nav["roll_rad"][k], nav["pitch_rad"][k], nav["heading_rad"][k])
    for acc, a, b in zip((roll, pitch, head), r_nav, r_ref):
        acc.add(wrap_deg(math.degrees(a - b)))
    if t >= init + F0:
        kk = int(math.floor((t - init - F0) / P))
        since = t - init - F0 - kk * P
        win = windows.setdefault(kk, {"complete": False})
        if since < L:
            win["end"] = (math.hypot(e, n), u)
    for kk, win in windows.items():
        if t >= init + F0 + kk * P + L:
            win["complete"] = True

sc = s["position"]
near(s["frames"]["scored"], frames, 0, "frames scored")
near(sc["horizontal"]["rms_m"], h.rms(), 2e-3, "horizontal RMS")
near(sc["horizontal"]["max_m"], h.mx, 2e-3, "horizontal max")
near(sc["vertical"]["rms_m"], v.rms(), 2e-3, "vertical RMS")
near(sc["vertical"]["max_m"], v.mx, 2e-3, "vertical max")
near(s["velocity"]["norm"]["rms_mps"], vel.rms(), 1e-6, "velocity RMS")
near(s["velocity"]["norm"]["max_mps"], vel.mx, 1e-6, "velocity max")
for name, acc in (("roll", roll), ("pitch", pitch), ("heading", head)):
    near(s["attitude"][name]["rms_deg"], acc.rms(), 1e-4, f"{name} RMS")
    near(s["attitude"][name]["max_deg"], acc.mx, 1e-4, f"{name} max")
sw = {w["index"]: w for w in s["outages"]["windows"]}
assert sorted(sw) == sorted(windows), f"outage windows: scorer {sorted(sw)}, independent {sorted(windows)}"
for kk, win in windows.items():
    assert sw[kk]["complete"] == win["complete"], f"outage {kk} completeness"
    near(sw[kk]["end_horizontal_m"], win["end"][0], 2e-3, f"outage {kk} horizontal error at its end")
    near(sw[kk]["end_vertical_m"], win["end"][1], 2e-3, f"outage {kk} vertical error at its end")
done = [w["end"][0] for w in windows.values() if w["complete"]]
near(s["outages"]["end_horizontal"]["rms_m"], math.sqrt(sum(x * x for x in done) / len(done)), 2e-3, "outage end RMS")
print(f"scorer agrees with the independent computation over {frames} frames and {len(windows)} outages: horizontal RMS "
      f"{h.rms():.3f} m, vertical RMS {v.rms():.3f} m, heading RMS {head.rms():.4f} deg, outage end RMS "
      f"{s['outages']['end_horizontal']['rms_m']:.3f} m")

# 3. No reference: --score-json is refused with the reason; a plain replay still runs.
bare = os.path.join(work, "bare.lcmlog")
shutil.copy(out_log, bare)  # the replay's own log carries no TRUTH (the flight software never sees it)
p = run("replay", bare, "--score-json", os.path.join(work, "none.json"), ok=False)
assert p.returncode != 0 and "no usable reference on TRUTH" in p.stderr, p.stderr
assert not os.path.exists(os.path.join(work, "none.json"))
print("replay_score: OK")
