#!/usr/bin/python3
"""python-can as an independent peer of the sdins udp:PORT transport (both directions).

  1. python-can Bus(interface="udp_multicast") sends -> `sdins can record` receives
  2. `sdins can play` sends -> python-can Bus receives
  3. `python3 -m can.player` (python-can's log player) -> `sdins can record`
  4. `sdins can play` -> `python3 -m can.logger` (python-can's logger), whose log `sdins can dump` reads

The frames are the protocol's own (`sdins can encode`, 1 s of the default scenario: IMU samples,
a GPS epoch, the almanac). Every received frame must equal the sent one (ID, FD flags, payload),
and `sdins can dump` must decode the received logs with zero rejections. All waits are bounded.
Exit 77 (CTest: skipped) with the reason when python-can cannot use multicast on this host.

usage: can_python_peer.py SDINS WORKDIR
"""
import os
import re
import signal
import subprocess
import sys
import time

import can
from e2e_common import read_until  # beside this script

GROUPS = ["ff15:7079:7468:6f6e:6465:6d6f:6d63:6173", "239.74.163.2"]  # python-can's IPv6 / IPv4 defaults


def frames_of(path):
    return [m for m in can.LogReader(path) if not m.is_error_frame]


def same(a, b):
    return (a.arbitration_id == b.arbitration_id and a.is_extended_id == b.is_extended_id and a.is_fd == b.is_fd
            and a.bitrate_switch == b.bitrate_switch and bytes(a.data) == bytes(b.data))


def compare(sent, got, what):
    assert len(got) == len(sent), f"{what}: received {len(got)} frames, sent {len(sent)}"
    for i, (a, b) in enumerate(zip(sent, got)):
        assert same(a, b), f"{what}: frame {i} differs: sent {a}, received {b}"
    print(f"{what}: {len(got)} frames identical")


def wait_for_line(proc, stream, pattern, timeout_s):
    """Reads lines from a child's pipe until one matches (bounded)."""
    ok, buf = read_until(proc, stream, lambda text: re.search(pattern, text), timeout_s)
    if not ok:
        raise AssertionError(f"no '{pattern}' from {proc.args} within {timeout_s} s; got: {buf!r}")
    return buf


def dump_health(sdins, log):
    out = subprocess.run([sdins, "can", "dump", "--log", log, "--quiet"], check=True, capture_output=True, text=True,
                         timeout=60).stdout
    health = dict(re.findall(r"(\w+)=(\d+)", out.split("health:")[1].splitlines()[0]))
    return {k: int(v) for k, v in health.items()}, out


def check_decodes(sdins, log, n_imu, what):
    h, out = dump_health(sdins, log)
    bad = ["unknown_id", "bad_length", "bad_crc", "unsupported_frame", "imu_missing", "imu_duplicate",
           "imu_out_of_order", "gps_meas_missing", "gps_duplicate", "gps_out_of_order", "almanac_invalid"]
    assert all(h[k] == 0 for k in bad), f"{what}: rejections in {out}"
    assert h["imu_delivered"] == n_imu and h["gps_epochs_delivered"] == 1 and h["almanac_delivered"] >= 24, out
    print(f"{what}: sdins can dump decodes {h['imu_delivered']} IMU samples, {h['gps_epochs_delivered']} epoch, "
          f"{h['almanac_delivered']} almanac entries, no rejections")


def usable_group(port):
    """The first python-can default group on which two python-can buses on this host reach each
    other (the IPv6 default needs a multicast-capable interface; an isolated lo only does IPv4
    after `ip route add 224.0.0.0/4 dev lo`), or None and the reasons."""
    reasons = []
    for group in GROUPS:
        try:
            with can.Bus(interface="udp_multicast", channel=group, port=port) as a, \
                    can.Bus(interface="udp_multicast", channel=group, port=port) as b:
                a.send(can.Message(arbitration_id=0x7FF, is_extended_id=False, data=b"probe"))
                if b.recv(timeout=1.0) is not None:
                    return group, ""
                reasons.append(f"{group}: sent datagram not received within 1 s")
        except Exception as e:  # noqa: BLE001 - any failure means: not usable here
            reasons.append(f"{group}: {e!r}")
    return None, "; ".join(reasons)


def main():
    sdins, work = sys.argv[1], sys.argv[2]
    os.makedirs(work, exist_ok=True)
    base = 30000 + (os.getpid() % 5000) * 4
    src = os.path.join(work, "src.log")
    subprocess.run([sdins, "can", "encode", "--duration", "1", "--out", src], check=True, timeout=60)
    sent = frames_of(src)
    n_imu = sum(1 for m in sent if m.arbitration_id == 0x010)

    group, why = usable_group(base)
    if group is None:
        print(f"SKIP: python-can udp_multicast cannot deliver on this host: {why}")
        return 77
    print(f"multicast group {group}")

    # 1. python-can Bus -> sdins can record
    port = base
    rx_log = os.path.join(work, "from_python.log")
    rec = subprocess.Popen([sdins, "can", "record", "--can", f"udp:[{group}]:{port}?scope=lan", "--out", rx_log, "--count",
                            str(len(sent)), "--timeout", "10"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    wait_for_line(rec, rec.stderr, "listening", 10)
    with can.Bus(interface="udp_multicast", channel=group, port=port) as bus:
        for i, m in enumerate(sent):
            bus.send(m)
            if i % 20 == 19:
                time.sleep(0.002)
    rec.wait(timeout=30)
    assert rec.returncode == 0, f"sdins can record failed: {rec.stdout.read().decode()}"
    compare(sent, frames_of(rx_log), "python-can Bus -> sdins")
    check_decodes(sdins, rx_log, n_imu, "python-can Bus -> sdins")

    # 2. sdins can play -> python-can Bus
    port = base + 1
    got = []
    with can.Bus(interface="udp_multicast", channel=group, port=port) as bus:
        play = subprocess.Popen([sdins, "can", "play", src, "--can", f"udp:[{group}]:{port}?scope=lan", "--gap", "0.0001"],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        deadline = time.time() + 20
        while len(got) < len(sent) and time.time() < deadline:
            m = bus.recv(timeout=1.0)
            if m is not None:
                got.append(m)
        play.wait(timeout=30)
        assert play.returncode == 0, play.stderr.read().decode()
        extra = bus.recv(timeout=0.2)
        assert extra is None, f"more frames than sent: {extra}"
    compare(sent, got, "sdins -> python-can Bus")
    assert all(m.timestamp > 1.6e9 for m in got)

    # 3. python -m can.player -> sdins can record
    port = base + 2
    rx_log = os.path.join(work, "from_player.log")
    rec = subprocess.Popen([sdins, "can", "record", "--can", f"udp:[{group}]:{port}?scope=lan", "--out", rx_log, "--count",
                            str(len(sent)), "--timeout", "10"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    wait_for_line(rec, rec.stderr, "listening", 10)
    subprocess.run([sys.executable, "-m", "can.player", "-i", "udp_multicast", "-c", group, f"--port={port}", src],
                   check=True, timeout=60, stdout=subprocess.DEVNULL)
    rec.wait(timeout=30)
    assert rec.returncode == 0, f"sdins can record failed: {rec.stdout.read().decode()}"
    compare(sent, frames_of(rx_log), "can.player -> sdins")

    # 4. sdins can play -> python -m can.logger
    port = base + 3
    py_log = os.path.join(work, "by_can_logger.log")
    logger = subprocess.Popen([sys.executable, "-u", "-m", "can.logger", "-i", "udp_multicast", "-c", group,
                               f"--port={port}", "-f", py_log], stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    wait_for_line(logger, logger.stdout, "Can Logger", 15)
    subprocess.run([sdins, "can", "play", src, "--can", f"udp:[{group}]:{port}?scope=lan", "--gap", "0.0001"], check=True, timeout=60,
                   stdout=subprocess.DEVNULL)
    time.sleep(0.5)
    logger.send_signal(signal.SIGINT)
    logger.wait(timeout=15)
    compare(sent, frames_of(py_log), "sdins -> can.logger")
    check_decodes(sdins, py_log, n_imu, "sdins -> can.logger (log read by sdins)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
