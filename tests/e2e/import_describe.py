#!/usr/bin/python3
"""End to end: `sdins import describe` (docs/own-recording.md).

usage: import_describe.py roundtrip SDINS WORKDIR [SEEDS]
       import_describe.py recordings SDINS DATA_DIR DESCRIPTIONS_DIR WORKDIR

roundtrip: `sdins sim` flies 60 s (IMU increments at 1 kHz, TRUTH at 10 Hz with attitude). Its IMU and
TRUTH channels are exported, then written as text tables in random formats: CSV or whitespace,
header names or column numbers, shuffled columns, random units (rad/deg, m/s/mm/s, deg/rad/1e-7 deg,
m/mm, ms/us/ns/s), a random signed axis permutation with its fixed rotation, and a random time base
(GPS week + TOW, GPS seconds, UNIX/UTC with its leap seconds, or a local clock fitted to GPS time
through the clock pair of the GNSS rows with a declared latency). A 1 Hz GNSS solution table is made
from TRUTH (speed + course + vertical speed with a random sign, sigmas from HDOP/VDOP through the
stated model, fix types mapped to solution kinds). Each variant is imported with a description file
and checked against the simulated log:
  - IMU: every sample back, t_s within 2 us of GPS time, increments within 1e-12 rad / 1e-12 m/s
    plus 1e-9 relative (the units' rounding);
  - TRUTH: position within 2 cm (1e-7 deg steps are 1.1 cm), velocity within 1e-6 m/s, attitude
    within 1e-6 deg;
  - GNSS_PVT: position within 2 cm of TRUTH, velocity within 1e-6 m/s (with the vertical sign right);
  - the summary: the clock fit's drift within 0.01 ppm of the one put in and its residual below 1 us,
    the leap seconds (14 s in 2007) reported for UNIX time;
  - replay with the starting filter configuration the import wrote: the navigation solution of every
    variant equals that of the canonical variant (SI units, FRD axes, GPS TOW) within 1 mm, 1e-5 m/s
    and 1e-5 deg, and the canonical replay is within 5 m of TRUTH.

recordings: each of the three recordings imported through its description file
(docs/datasets/*.import.toml) gives the same bytes as its dedicated preset (rtklib, psins).
Exit 77 (CTest: skipped) without the recordings ($SDINS_RECORDINGS_DIR, else DATA_DIR) or convbin.
"""
import csv
import hashlib
import math
import os
import random
import shutil
import subprocess
import sys

from e2e_common import fresh_dir, need_convbin, need_datasets, recordings_dir, run_sdins  # beside this script

WEEK0_UNIX = 315964800
GPS_WEEK_S = 604800.0


run = run_sdins  # run(sdins, *args)


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def sha(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


# ------------------------------------------------------------------------------------------------
# Geometry (the flight software's conventions: ENU navigation frame, FRD body)

def c_b_n_from_euler(r, p, h):
    cr, sr, cp, sp, ch, sh = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(h), math.sin(h)
    ned = [[cp * ch, -cr * sh + sr * sp * ch, sr * sh + cr * sp * ch],
           [cp * sh, cr * ch + sr * sp * sh, -sr * ch + cr * sp * sh],
           [-sp, sr * cp, cr * cp]]
    return [ned[1], ned[0], [-x for x in ned[2]]]


def euler_from_c_b_n(c):
    ned = [c[1], c[0], [-x for x in c[2]]]
    pitch = math.asin(max(-1.0, min(1.0, -ned[2][0])))
    roll = math.atan2(ned[2][1], ned[2][2])
    heading = math.atan2(ned[1][0], ned[0][0]) % (2 * math.pi)
    return roll, pitch, heading


def rot_xyz(rpy_deg):
    """C (body = C * v) of the description's rotation_deg: the transpose of Rz(y) Ry(p) Rx(r)."""
    r, p, y = (math.radians(a) for a in rpy_deg)
    rx = [[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]]
    ry = [[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]]
    rz = [[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]]
    m = matmul(rz, matmul(ry, rx))
    return [[m[j][i] for j in range(3)] for i in range(3)]


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def matvec(a, v):
    return [sum(a[i][k] * v[k] for k in range(3)) for i in range(3)]


def transpose(a):
    return [[a[j][i] for j in range(3)] for i in range(3)]


def c_n_e(lat, lon):
    sl, cl, so, co = math.sin(lat), math.cos(lat), math.sin(lon), math.cos(lon)
    return [[-so, -sl * co, cl * co], [co, -sl * so, cl * so], [0.0, cl, sl]]


def angle_diff_deg(a, b):
    return abs((math.degrees(a - b) + 180.0) % 360.0 - 180.0)


# ------------------------------------------------------------------------------------------------
# Tables in random formats

ANGLE = {"rad": 1.0, "deg": math.pi / 180.0, "1e-7 deg": 1e-7 * math.pi / 180.0}
LENGTH = {"m": 1.0, "mm": 1e-3}
DV = {"m/s": 1.0, "mm/s": 1e-3}
TIME = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
SPEED = {"m/s": 1.0, "cm/s": 1e-2, "km/h": 1.0 / 3.6}


class Table:
    """Columns by name -> values per row; written with a random layout."""

    def __init__(self, rng, name, canonical):
        self.rng, self.name, self.canonical = rng, name, canonical
        self.cols = []  # (name, values)

    def add(self, name, values):
        self.cols.append((name, values))

    def write(self, path):
        rng = self.rng
        order = list(range(len(self.cols)))
        if not self.canonical:
            rng.shuffle(order)
        self.whitespace = not self.canonical and rng.random() < 0.5
        self.header = self.canonical or rng.random() < 0.6
        sep = " " if self.whitespace else ","
        n = len(self.cols[0][1])
        with open(path, "w") as f:
            if not self.canonical:
                f.write("# exported by tests/e2e/import_describe.py\n")
            if self.header:
                f.write(sep.join(self.cols[i][0] for i in order) + "\n")
            for k in range(n):
                f.write(sep.join(repr(float(self.cols[i][1][k])) if not isinstance(self.cols[i][1][k], int)
                                 else str(self.cols[i][1][k]) for i in order) + "\n")
        self.position = {self.cols[i][0]: j for j, i in enumerate(order)}
        self.path = path

    def ref(self, name):
        return f'"{name}"' if self.header else str(self.position[name] + 1)

    def layout(self):
        s = f'file = "{os.path.basename(self.path)}"\nformat = "{"whitespace" if self.whitespace else "csv"}"\n'
        s += f"header = {'true' if self.header else 'false'}\n"
        if not self.canonical:
            s += 'comment = "#"\n'
        return s


def pick(rng, table, canonical, default):
    return default if canonical else rng.choice(list(table))


def time_base(rng, canonical):
    return "gps_tow" if canonical else rng.choice(["gps_tow", "gps_seconds", "unix", "local"])


def leap_2007():
    return 14  # GPS - UTC from 2006-01-01 to 2008-12-31


class Clock:
    """A local clock: local_s = (gps_s - g0) * (1 + drift) + offset."""

    def __init__(self, rng, g0):
        self.g0 = g0
        self.drift = rng.uniform(-80e-6, 80e-6)
        self.offset = rng.uniform(10.0, 5000.0)

    def local(self, gps_s):
        return (gps_s - self.g0) * (1.0 + self.drift) + self.offset


def time_values(base, tscale, week, tow, clock):
    """The column values for GPS times (week, tow) on a base, in the column's unit."""
    g = week * GPS_WEEK_S + tow
    if base == "gps_tow":
        return tow / tscale
    if base == "gps_seconds":
        return g / tscale
    if base == "unix":
        return (g + WEEK0_UNIX - leap_2007()) / tscale
    return clock.local(g) / tscale


def time_toml(base, col, unit, week):
    s = f'time = {{ column = {col}, unit = "{unit}", base = "{base}"'
    if base == "gps_tow":
        s += f", week = {week}"
    return s + " }\n"


def variant(sdins, work, sim, rng, canonical, tag):
    d = os.path.join(work, tag)
    os.makedirs(d)
    imu, truth, raw = sim["IMU"], sim["TRUTH"], sim["GNSS_RAW"]
    week = int(raw[0]["gps_week"])
    tow0 = round(float(raw[0]["gps_tow_s"]) - float(raw[0]["t_s"]))  # GPS time of sim t_s = 0
    clock = Clock(rng, week * GPS_WEEK_S + tow0)
    latency = 0.0 if canonical else rng.choice([0.0, 0.05, 0.2])
    tb = time_base(rng, canonical)
    desc = f'name = "roundtrip-{tag}"\n'
    info = {"base": tb, "latency": latency, "drift": clock.drift}

    # IMU: increments, random units, axes (signed permutation that is a rotation) and a fixed rotation.
    gu, au = pick(rng, {"rad": 1, "deg": 1}, canonical, "rad"), pick(rng, DV, canonical, "m/s")
    tu = pick(rng, {"s": 1, "ms": 1, "us": 1} if tb != "gps_seconds" else {"s": 1, "ms": 1}, canonical, "s")
    perms = [(0, 1, 2), (1, 2, 0), (2, 0, 1), (1, 0, 2), (0, 2, 1), (2, 1, 0)]
    while True:
        perm = rng.choice(perms) if not canonical else (0, 1, 2)
        signs = [rng.choice([1, -1]) for _ in range(3)] if not canonical else [1, 1, 1]
        m = [[0.0] * 3 for _ in range(3)]
        for i in range(3):
            m[i][perm[i]] = signs[i]
        det = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
        if det > 0:
            break
    axes = ",".join(("-" if signs[i] < 0 else "") + "xyz"[perm[i]] for i in range(3))
    rot = [0.0, 0.0, 0.0] if canonical or rng.random() < 0.5 else [rng.uniform(-10, 10) for _ in range(3)]
    body_from_sensor = matmul(rot_xyz(rot), m)
    sensor_from_body = transpose(body_from_sensor)
    t_imu = Table(rng, "imu", canonical)
    gyro_s, accel_s = [[], [], []], [[], [], []]
    for r in imu:
        th = matvec(sensor_from_body, [float(r[f"dtheta_rad[{i}]"]) for i in range(3)])
        dv = matvec(sensor_from_body, [float(r[f"dv_mps[{i}]"]) for i in range(3)])
        for i in range(3):
            gyro_s[i].append(th[i] / (1.0 if gu == "rad" else math.pi / 180.0))
            accel_s[i].append(dv[i] / DV[au])
    t_imu.add("t", [time_values(tb, TIME[tu], week, tow0 + float(r["t_s"]), clock) for r in imu])
    for i, a in enumerate("xyz"):
        t_imu.add(f"g{a}", gyro_s[i])
        t_imu.add(f"a{a}", accel_s[i])
    t_imu.write(os.path.join(d, "imu.txt"))
    desc += "\n[imu]\n" + t_imu.layout() + 'kind = "increments"\n'
    desc += f'gyro = {{ columns = [{t_imu.ref("gx")}, {t_imu.ref("gy")}, {t_imu.ref("gz")}], unit = "{gu}" }}\n'
    desc += f'accel = {{ columns = [{t_imu.ref("ax")}, {t_imu.ref("ay")}, {t_imu.ref("az")}], unit = "{au}" }}\n'
    desc += f'axes = "{axes}"\n'
    if rot != [0.0, 0.0, 0.0]:
        desc += f"rotation_deg = [{rot[0]!r}, {rot[1]!r}, {rot[2]!r}]\n"
    desc += time_toml(tb, t_imu.ref("t"), tu, week)
    info.update(gyro=gu, accel=au, time=tu, axes=axes, rotation=rot)

    # GNSS solutions at 1 Hz from TRUTH: speed + course + vertical speed, HDOP/VDOP sigmas, fix types.
    gb = "gps_tow" if canonical else rng.choice(["gps_tow", "gps_seconds", "unix"])
    vsign = 1 if canonical else rng.choice([1, -1])
    lu = pick(rng, ANGLE, canonical, "deg")
    hu = pick(rng, LENGTH, canonical, "m")
    su = pick(rng, SPEED, canonical, "m/s")
    fix_codes = {"3": "single", "4": "dgps"}
    g_rows = [r for r in truth if abs(float(r["t_s"]) - round(float(r["t_s"]))) < 1e-6]
    t_g = Table(rng, "gnss", canonical)
    t_g.add("tow", [time_values(gb, 1.0, week, tow0 + float(r["t_s"]), clock) for r in g_rows])
    t_g.add("boot_ms", [clock.local(week * GPS_WEEK_S + tow0 + float(r["t_s"]) + latency) * 1e3 for r in g_rows])
    t_g.add("lat", [float(r["lat_rad"]) / ANGLE[lu] for r in g_rows])
    t_g.add("lon", [float(r["lon_rad"]) / ANGLE[lu] for r in g_rows])
    t_g.add("alt", [float(r["height_m"]) / LENGTH[hu] for r in g_rows])
    ve = [float(r["vel_enu_mps[0]"]) for r in g_rows]
    vn = [float(r["vel_enu_mps[1]"]) for r in g_rows]
    vu = [float(r["vel_enu_mps[2]"]) for r in g_rows]
    t_g.add("speed", [math.hypot(e, n) / SPEED[su] for e, n in zip(ve, vn)])
    t_g.add("course", [math.degrees(math.atan2(e, n)) % 360.0 for e, n in zip(ve, vn)])
    t_g.add("vs", [vsign * u / SPEED[su] for u in vu])
    t_g.add("hdop", [1.2] * len(g_rows))
    t_g.add("vdop", [1.9] * len(g_rows))
    t_g.add("fix", [3 if k % 7 else 4 for k in range(len(g_rows))])
    t_g.write(os.path.join(d, "gnss.txt"))
    desc += "\n[gnss]\n" + t_g.layout()
    desc += time_toml(gb, t_g.ref("tow"), "s", week)
    if tb == "local":
        desc += f'local_clock = {{ column = {t_g.ref("boot_ms")}, unit = "ms" }}\nlatency_s = {latency!r}\n'
    desc += f'lat = {{ column = {t_g.ref("lat")}, unit = "{lu}" }}\nlon = {{ column = {t_g.ref("lon")}, unit = "{lu}" }}\n'
    desc += f'height = {{ column = {t_g.ref("alt")}, unit = "{hu}", datum = "ellipsoid" }}\n'
    desc += (f'velocity = {{ form = "speed_course", columns = [{t_g.ref("speed")}, {t_g.ref("course")}, {t_g.ref("vs")}], '
             f'unit = "{su}", course_unit = "deg", vertical_positive = "{"up" if vsign > 0 else "down"}" }}\n')
    desc += f'sigma_model = {{ hdop = {t_g.ref("hdop")}, vdop = {t_g.ref("vdop")}, uere_by_kind_m = {{ single = 2.0, dgps = 0.8 }} }}\n'
    desc += "vel_sigma_mps = 0.1\n"
    desc += f'quality = {{ column = {t_g.ref("fix")}, map = {{ ' + ", ".join(f'"{k}" = "{v}"' for k, v in fix_codes.items()) + " } }\n"
    info.update(gnss_base=gb, vertical=vsign, latlon=lu, height=hu, speed=su)

    # Reference: TRUTH with velocity in a random frame and attitude in random angle units.
    rb = "gps_tow" if canonical else rng.choice(["gps_tow", "gps_seconds", "unix"])
    vf = "enu" if canonical else rng.choice(["enu", "ned", "ecef"])
    au2 = pick(rng, {"rad": 1, "deg": 1}, canonical, "rad")
    t_r = Table(rng, "reference", canonical)
    t_r.add("t", [time_values(rb, 1.0, week, tow0 + float(r["t_s"]), clock) for r in truth])
    t_r.add("lat", [float(r["lat_rad"]) / ANGLE[lu] for r in truth])
    t_r.add("lon", [float(r["lon_rad"]) / ANGLE[lu] for r in truth])
    t_r.add("h", [float(r["height_m"]) / LENGTH[hu] for r in truth])
    vel = []
    for r in truth:
        v = [float(r[f"vel_enu_mps[{i}]"]) for i in range(3)]
        if vf == "ned":
            v = [v[1], v[0], -v[2]]
        elif vf == "ecef":
            v = matvec(c_n_e(float(r["lat_rad"]), float(r["lon_rad"])), v)
        vel.append(v)
    for i in range(3):
        t_r.add(f"v{i}", [v[i] for v in vel])
    for k in ("roll_rad", "pitch_rad", "heading_rad"):
        t_r.add(k[:-4], [float(r[k]) / (1.0 if au2 == "rad" else math.pi / 180.0) for r in truth])
    t_r.write(os.path.join(d, "reference.txt"))
    desc += "\n[reference]\nkind = \"simulation\"\n" + t_r.layout()
    desc += time_toml(rb, t_r.ref("t"), "s", week)
    desc += f'lat = {{ column = {t_r.ref("lat")}, unit = "{lu}" }}\nlon = {{ column = {t_r.ref("lon")}, unit = "{lu}" }}\n'
    desc += f'height = {{ column = {t_r.ref("h")}, unit = "{hu}" }}\n'
    desc += f'velocity = {{ form = "{vf}", columns = [{t_r.ref("v0")}, {t_r.ref("v1")}, {t_r.ref("v2")}], unit = "m/s" }}\n'
    desc += f'attitude = {{ columns = [{t_r.ref("roll")}, {t_r.ref("pitch")}, {t_r.ref("heading")}], unit = "{au2}" }}\n'
    info.update(ref_base=rb, ref_velocity=vf, attitude=au2)

    with open(os.path.join(d, "recording.toml"), "w") as f:
        f.write(desc)
    log = os.path.join(d, "imported.lcmlog")
    text = run(sdins, "import", "describe", os.path.join(d, "recording.toml"), "--log", log)
    import json
    with open(log + ".json") as f:
        summary = json.load(f)
    return d, log, summary, text, info, (week, tow0)


def check_variant(sdins, sim, d, log, summary, info, week_tow0):
    week, tow0 = week_tow0
    out = {}
    for ch in ("IMU", "TRUTH", "GNSS_PVT"):
        run(sdins, "log", "export", log, "--channel", ch, "--csv", os.path.join(d, ch + ".csv"))
        out[ch] = read_csv(os.path.join(d, ch + ".csv"))
    imu0, imu1 = sim["IMU"], out["IMU"]
    assert len(imu1) == len(imu0), f"{d}: {len(imu1)} IMU samples imported of {len(imu0)}"
    worst_t = worst_th = worst_dv = 0.0
    for a, b in zip(imu0, imu1):
        worst_t = max(worst_t, abs(float(b["t_s"]) - tow0 - float(a["t_s"])))
        for i in range(3):
            x, y = float(a[f"dtheta_rad[{i}]"]), float(b[f"dtheta_rad[{i}]"])
            worst_th = max(worst_th, abs(x - y) / (1e-12 + 1e-9 * abs(x)))
            x, y = float(a[f"dv_mps[{i}]"]), float(b[f"dv_mps[{i}]"])
            worst_dv = max(worst_dv, abs(x - y) / (1e-12 + 1e-9 * abs(x)))
    # 2 us, plus the latency's length on the drifting local clock (the latency is declared in seconds).
    tol_t = 2e-6 + 1.5 * info["latency"] * abs(info["drift"]) if info["base"] == "local" else 2e-6
    assert worst_t <= tol_t, f"{d}: IMU time off by {worst_t} s (tolerance {tol_t} s)"
    assert worst_th <= 1.0 and worst_dv <= 1.0, f"{d}: IMU increments off ({worst_th}, {worst_dv} x tolerance)"
    tr0, tr1 = sim["TRUTH"], out["TRUTH"]
    assert len(tr1) == len(tr0), f"{d}: {len(tr1)} TRUTH samples of {len(tr0)}"
    worst_p = worst_v = worst_a = 0.0
    for a, b in zip(tr0, tr1):
        lat = float(a["lat_rad"])
        dn = (float(b["lat_rad"]) - lat) * 6.37e6
        de = (float(b["lon_rad"]) - float(a["lon_rad"])) * 6.37e6 * math.cos(lat)
        worst_p = max(worst_p, math.sqrt(dn * dn + de * de + (float(b["height_m"]) - float(a["height_m"])) ** 2))
        worst_v = max(worst_v, max(abs(float(a[f"vel_enu_mps[{i}]"]) - float(b[f"vel_enu_mps[{i}]"])) for i in range(3)))
        for k in ("roll_rad", "pitch_rad", "heading_rad"):
            worst_a = max(worst_a, angle_diff_deg(float(a[k]), float(b[k])))
    assert worst_p <= 0.02 and worst_v <= 1e-6 and worst_a <= 1e-6, \
        f"{d}: TRUTH off by {worst_p} m, {worst_v} m/s, {worst_a} deg"
    truth_by_t = {round(float(r["t_s"]) + tow0, 3): r for r in tr0}
    worst_gp = worst_gv = 0.0
    for p in out["GNSS_PVT"]:
        r = truth_by_t[round(float(p["t_s"]), 3)]
        lat = float(r["lat_rad"])
        dn = (float(p["lat_rad"]) - lat) * 6.37e6
        de = (float(p["lon_rad"]) - float(r["lon_rad"])) * 6.37e6 * math.cos(lat)
        worst_gp = max(worst_gp, math.sqrt(dn * dn + de * de + (float(p["height_m"]) - float(r["height_m"])) ** 2))
        worst_gv = max(worst_gv, max(abs(float(p[f"vel_enu_mps[{i}]"]) - float(r[f"vel_enu_mps[{i}]"])) for i in range(3)))
    assert len(out["GNSS_PVT"]) == 60, f"{d}: {len(out['GNSS_PVT'])} solutions of 60"
    assert worst_gp <= 0.02 and worst_gv <= 1e-6, f"{d}: GNSS_PVT off by {worst_gp} m, {worst_gv} m/s"
    if info["base"] == "local":
        f = summary["time_fit"]
        assert abs(f["drift_ppm"] - info["drift"] * -1e6 / (1 + info["drift"])) < 0.01, f"{d}: drift {f['drift_ppm']} ppm"
        assert f["residual_rms_s"] < 1e-6, f"{d}: clock fit residual {f['residual_rms_s']} s"
    if "unix" in (info["base"], info["gnss_base"], info["ref_base"]):
        assert summary["leap_seconds"]["gps_minus_utc_s"] == [14], summary.get("leap_seconds")
    assert summary["reference"] == {"kind": "simulation", "source": os.path.join(d, "reference.txt"), "has_attitude": True}, \
        summary["reference"]
    assert not summary["warnings"], f"{d}: warnings {summary['warnings']}"
    return {"imu_t_us": worst_t * 1e6, "truth_m": worst_p, "pvt_m": worst_gp}


def replay_nav(sdins, d, log, filter_config):
    out = os.path.join(d, "replay.lcmlog")
    run(sdins, "replay", log, "--filter-config", filter_config, "--log", out)
    run(sdins, "log", "export", out, "--channel", "NAV_SOLUTION", "--csv", os.path.join(d, "nav.csv"))
    return read_csv(os.path.join(d, "nav.csv"))


def roundtrip(sdins, work, seeds):
    fresh_dir(work)
    sim_log = os.path.join(work, "sim.lcmlog")
    run(sdins, "sim", "--seed", "7", "--duration", "60", "--log", sim_log)
    sim = {}
    for ch in ("IMU", "TRUTH", "GNSS_RAW"):
        path = os.path.join(work, f"sim_{ch}.csv")
        run(sdins, "log", "export", sim_log, "--channel", ch, "--csv", path)
        sim[ch] = read_csv(path)
    d, log, summary, text, info, wt = variant(sdins, work, sim, random.Random(0), True, "canonical")
    print(text)
    res = check_variant(sdins, sim, d, log, summary, info, wt)
    print(f"canonical: {res}")
    base_nav = replay_nav(sdins, d, log, summary["filter_config"])
    assert len(base_nav) > 1000, f"canonical replay: {len(base_nav)} navigation outputs"
    # Against TRUTH (GNSS = TRUTH at 1 Hz with 1-2 m sigmas): the run navigates. The nearest TRUTH
    # sample (10 Hz) moved along its velocity to the output's time.
    tr = {round(float(r["t_s"]) * 10): r for r in sim["TRUTH"]}
    worst, compared = 0.0, 0
    for n in base_nav:
        t = float(n["t_s"]) - wt[1]
        r = tr.get(round(t * 10))
        if r is None or n["valid"] in ("0", "false"):
            continue
        dt = t - float(r["t_s"])
        lat = float(r["lat_rad"])
        dn = (float(n["lat_rad"]) - lat) * 6.37e6 - float(r["vel_enu_mps[1]"]) * dt
        de = (float(n["lon_rad"]) - float(r["lon_rad"])) * 6.37e6 * math.cos(lat) - float(r["vel_enu_mps[0]"]) * dt
        worst = max(worst, math.hypot(dn, de))
        compared += 1
    assert compared > 500, f"canonical replay: only {compared} outputs compared with TRUTH"
    assert worst < 5.0, f"canonical replay {worst} m from TRUTH"
    print(f"canonical replay: {len(base_nav)} outputs, {compared} compared: at most {worst:.3f} m horizontally from TRUTH")
    for seed in seeds:
        rng = random.Random(seed)
        d, log, summary, text, info, wt = variant(sdins, work, sim, rng, False, f"seed{seed}")
        res = check_variant(sdins, sim, d, log, summary, info, wt)
        nav = replay_nav(sdins, d, log, summary["filter_config"])
        assert len(nav) == len(base_nav), f"seed {seed}: {len(nav)} navigation outputs, canonical {len(base_nav)}"
        # Output by output; a time tag nearer one IMU sample's boundary may move the frame grouping
        # by a sample (1 ms), so the canonical state is moved along its velocity to the variant's time.
        wp = wv = wa = wdt = 0.0
        for a, b in zip(base_nav, nav):
            dt = float(b["t_s"]) - float(a["t_s"])
            wdt = max(wdt, abs(dt))
            lat = float(a["lat_rad"])
            dn = (float(b["lat_rad"]) - lat) * 6.37e6 - float(a["vel_enu_mps[1]"]) * dt
            de = (float(b["lon_rad"]) - float(a["lon_rad"])) * 6.37e6 * math.cos(lat) - float(a["vel_enu_mps[0]"]) * dt
            du = float(b["height_m"]) - float(a["height_m"]) - float(a["vel_enu_mps[2]"]) * dt
            wp = max(wp, math.sqrt(dn * dn + de * de + du * du))
            wv = max(wv, max(abs(float(a[f"vel_enu_mps[{i}]"]) - float(b[f"vel_enu_mps[{i}]"])) for i in range(3)))
            for k in ("roll_rad", "pitch_rad", "heading_rad"):
                wa = max(wa, angle_diff_deg(float(a[k]), float(b[k])))
        print(f"seed {seed}: {info}\n  import {res}; replay vs canonical: {wp:.2e} m, {wv:.2e} m/s, {wa:.2e} deg "
              f"(outputs up to {wdt * 1e3:.3f} ms apart)")
        # Within 1 mm, 1e-5 m/s, 1e-5 deg; a one-sample shift adds its motion over 1 ms (accelerations of
        # a few m/s^2, rates of a few deg/s).
        tol_v, tol_a = 1e-5 + 10.0 * wdt, 1e-5 + 5.0 * wdt
        assert wdt <= 1.1e-3, f"seed {seed}: outputs {wdt} s apart"
        assert wp <= 1e-3 and wv <= tol_v and wa <= tol_a, f"seed {seed}: replay differs by {wp} m, {wv} m/s, {wa} deg"
    cli_faults(sdins, os.path.join(work, "canonical"))
    print("round trip: OK")


def cli_faults(sdins, d):
    """Refusals: an output onto an input named by the description, a description error; nothing written."""
    imu = os.path.join(d, "imu.txt")
    before = sha(imu)
    p = subprocess.run([sdins, "import", "describe", os.path.join(d, "recording.toml"), "--log", imu],
                       capture_output=True, text=True)
    assert p.returncode != 0 and "refusing to overwrite an input" in p.stderr, (p.returncode, p.stderr)
    assert sha(imu) == before, "the IMU table was overwritten"
    bad = os.path.join(d, "bad.toml")
    with open(bad, "w") as f:
        f.write('[imu]\nfile = "imu.txt"\nkind = "rate"\n')
    out = os.path.join(d, "bad.lcmlog")
    p = subprocess.run([sdins, "import", "describe", bad, "--log", out], capture_output=True, text=True)
    assert p.returncode != 0 and f"{bad}:3:8: 'imu.kind' must be \"rates\" or \"increments\"" in p.stderr, p.stderr
    for f in (out, out + ".json", os.path.join(d, "bad.filter.toml")):
        assert not os.path.exists(f), f"{f} written by a refused import"
    print("refusals: OK")


def recordings(sdins, data, descriptions, work):
    data = recordings_dir(data)
    need_datasets(data, ("gnss-imu-drive", "gnss-imu-walk", "psins-tc"), "set SDINS_RECORDINGS_DIR, docs/data.md",
                  noun="recording")
    need_convbin()
    fresh_dir(work)
    for r, preset in (("gnss-imu-drive", "rtklib"), ("gnss-imu-walk", "rtklib"), ("psins-tc", "psins")):
        a, b = os.path.join(work, r + ".preset.lcmlog"), os.path.join(work, r + ".described.lcmlog")
        run(sdins, "import", preset, os.path.join(data, r), "--log", a)
        run(sdins, "import", "describe", os.path.join(descriptions, r + ".import.toml"), "--data", os.path.join(data, r),
            "--log", b)
        ha, hb = sha(a), sha(b)
        print(f"{r}: preset {preset} {ha}, description {hb}")
        assert ha == hb, f"{r}: the description's log differs from the {preset} preset's"
    # The RINEX 3 route: convbin's files of the walk (kept) described as obs + nav give the same log.
    keep = os.path.join(work, "walk.keep.lcmlog")
    js = os.path.join(work, "walk.keep.json")
    run(sdins, "import", "rtklib", os.path.join(data, "gnss-imu-walk"), "--keep-temp", "--log", keep, "--json", js)
    import json
    with open(js) as f:
        tmp = json.load(f)["convbin"]["temp_dir"]
    try:
        with open(os.path.join(descriptions, "gnss-imu-walk.import.toml")) as f:
            text = f.read()
        text = text.replace('format = "ubx"', 'format = "rinex3"').replace(
            'ubx = "gnss_1730.ubx"', f'obs = "{tmp}/raw.obs"\nnav = "{tmp}/raw.nav"')
        desc = os.path.join(work, "walk-rinex.import.toml")
        with open(desc, "w") as f:
            f.write(text)
        rin = os.path.join(work, "walk.rinex.lcmlog")
        run(sdins, "import", "describe", desc, "--data", os.path.join(data, "gnss-imu-walk"), "--log", rin)
        print(f"gnss-imu-walk through RINEX 3 obs + nav: {sha(rin)}")
        assert sha(rin) == sha(keep), "the walk through its RINEX files differs from the ubx route"
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print("recordings: OK")


if __name__ == "__main__":
    if sys.argv[1] == "roundtrip":
        seeds = [int(s) for s in sys.argv[4].split(",")] if len(sys.argv) > 4 else [1, 2, 3, 4, 5, 6]
        roundtrip(sys.argv[2], sys.argv[3], seeds)
    else:
        recordings(*sys.argv[2:6])
