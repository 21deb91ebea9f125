#!/usr/bin/env python3
"""Writes an LCM log with known messages for the `sdins log` end-to-end test.

The messages are encoded by the Python code lcm-gen generates from hal/lcm/*.lcm (an encoder
independent of the project's C++), and the log framing is written here by hand from the LCM log
format (sync word, event number, timestamp, channel length, data length, channel, data;
big-endian). Also writes damage the reader must survive: a wrong-type and a cut message on IMU,
garbage between events and a truncated last event. Prints the expected values as JSON.

usage: lcm_write_known_log.py GENERATED_PYTHON_DIR OUT.lcmlog
"""
import json
import struct
import sys

sys.path.insert(0, sys.argv[1])
from sdins import (ekf_state_t, filter_health_t, gnss_raw_epoch_t, gnss_raw_meas_t, gps_almanac_t,  # noqa: E402
                   imu_sample_t, nav_solution_t, truth_t)

out_path = sys.argv[2]
events = []  # (channel, bytes, timestamp_us)


def add(channel, data, t_s):
    events.append((channel, data, int(round(t_s * 1e6))))


imu = []
for k in range(100):
    m = imu_sample_t()
    m.t_s = 0.001 * (k + 1)
    m.utime = int(round(m.t_s * 1e6))
    m.dt_s = 0.001
    m.dtheta_rad = [1e-5 * k, -2.5e-6, 3.0e-7 * (k % 7)]
    m.dv_mps = [0.001 * k, 0.0, -0.0098]
    m.counter = k
    m.status = imu_sample_t.STATUS_GYRO_SATURATED if k == 50 else 0
    imu.append(m)
    add("IMU", m.encode(), m.t_s)
    if k == 10:  # a navigation solution on the IMU channel: wrong type
        add("IMU", nav_solution_t().encode(), m.t_s)
    if k == 20:  # an IMU message cut short: decode failure
        add("IMU", m.encode()[:-3], m.t_s)

gnss = []
for t, n in ((0.02, 5), (0.05, 0), (0.08, 16)):
    e = gnss_raw_epoch_t()
    e.t_s = t
    e.utime = int(round(t * 1e6))
    e.gps_week = 2290
    e.gps_tow_s = 345600.0 + t
    e.n_meas = n
    e.meas = []
    for k in range(16):
        x = gnss_raw_meas_t()
        if k < n:
            x.prn = 1 + k
            x.pseudorange_m = 2.0e7 + 1000.5 * k
            x.pseudorange_rate_mps = -300.25 + k
            x.cn0_dbhz = 35.0 + 0.5 * k
        e.meas.append(x)
    gnss.append(e)
    add("GNSS_RAW", e.encode(), t)

for prn in (3, 17):
    a = gps_almanac_t()
    a.t_s = 0.0
    a.prn = prn
    a.eccentricity = 0.01
    a.toa_s = 319488.0
    a.inclination_rad = 0.96
    a.sqrt_a_sqrtm = 5153.6
    a.week_mod_1024 = 199
    add("GPS_ALMANAC", a.encode(), 0.0)

for k in range(20):
    for cls, ch in ((nav_solution_t, "NAV_SOLUTION"), (truth_t, "TRUTH")):
        m = cls()
        m.t_s = 0.005 * (k + 1)
        m.utime = int(round(m.t_s * 1e6))
        m.lat_rad, m.lon_rad, m.height_m = 0.61, 2.21, 1000.0 + k
        m.vel_enu_mps = [250.0, -1.5 * k, 0.25]
        m.q_b_n_wxyz = [1.0, 0.0, 0.0, 0.0]
        m.heading_rad = 1.5
        if cls is nav_solution_t:
            m.valid = True
            m.ekf_updated = (k == 19)
        add(ch, m.encode(), m.t_s)
    if k == 9:
        events.append(("GARBAGE", None, 0))  # marker: 50 bytes of junk here

layout15 = [0, 3, 6, 9, 12, -1, -1, -1, -1, 15, -1, -1] + [-1] * 6
for t in (0.05, 0.1):
    s = ekf_state_t()
    s.t_s = t
    s.utime = int(round(t * 1e6))
    s.n_states = 17
    s.block_offset = layout15
    s.consider_mask = 0
    s.sigma = [0.1 * (i + 1) if i < 17 else 0.0 for i in range(72)]
    s.accel_bias_mps2 = [1e-4, 2e-4, 3e-4]
    s.clock_bias_m = 12.5
    s.channel_prn = [0] * 12
    add("EKF_STATE", s.encode(), t)
    h = filter_health_t()
    h.t_s = t
    h.utime = s.utime
    h.ekf_runs = int(t * 20)
    h.n_obs = 2
    h.prn = [5, 9] + [0] * 14
    h.pr_outcome = [1, 2] + [0] * 14
    h.pr_innovation_m = [1.5, -40.0] + [0.0] * 14
    add("FILTER_HEALTH", h.encode(), t)

for k in range(3):
    add("FOREIGN", bytes([0x42] * (10 + k)), 0.001 * k)

# Two EKF models on one channel: cannot be one CSV.
for n_states, offsets in ((17, layout15), (26, [0, 3, 6, 9, 12, 15, 18, -1, -1, 24, -1, -1] + [-1] * 6)):
    s = ekf_state_t()
    s.n_states = n_states
    s.block_offset = offsets
    s.sigma = [1.0] * 72
    s.channel_prn = [0] * 12
    add("EKF_MIXED", s.encode(), 0.2)

with open(out_path, "wb") as f:
    n = 0
    for channel, data, ts in events:
        if data is None:
            f.write(bytes([0x5A] * 50))
            continue
        ch = channel.encode()
        f.write(struct.pack(">IqqII", 0xEDA1DA01, n, ts, len(ch), len(data)))
        f.write(ch)
        f.write(data)
        n += 1
    # A last event cut short inside its data.
    data = imu[0].encode()
    f.write(struct.pack(">IqqII", 0xEDA1DA01, n, 999, 3, len(data)) + b"IMU" + data[:20])

expected = {
    "imu": [{"t_s": m.t_s, "dtheta_rad": list(m.dtheta_rad), "dv_mps": list(m.dv_mps), "counter": m.counter,
             "status": m.status} for m in imu],
    "gnss_n_meas": [e.n_meas for e in gnss],
}
print(json.dumps(expected))
