#!/usr/bin/python3
"""The part of tools/vcan/vcan-hil that runs inside the emulated Linux guest (or by hand on any
Linux with vcan: see docs/running.md, "HIL over SocketCAN (vcan)").

usage: guest.py JOB.json        (JOB names the sdins binary, the unit tests, seeds and the output dir)

On vcan0 (CAN FD, MTU 72), in this order, each step's outputs written to the job's out_dir:
  1. the SocketCAN unit tests (CanBusSocketCan.*): none may skip;
  2. lockstep: `sdins fsw` and `sdins bus-sim --lockstep` over socketcan:vcan0, `candump -L vcan0`
     recording the bus beside them, and cansend/cangen injecting foreign and malformed frames while
     the run goes on (the list is INJECTED below; every frame is to be counted by the fsw);
  3. real time: both with --realtime for realtime_s seconds, candump recording again.
The host side (vcan-hil) judges the outputs: digests against `sdins sil`, the candump logs read back
by `sdins can dump` and `sdins replay --candump`, the injected frames counted exactly.
Exit 0 when every step ran and wrote its outputs; otherwise non-zero with the reason on stdout.
"""
import binascii
import json
import os
import shutil
import signal
import subprocess
import sys
import time

IFACE = "vcan0"


def log(msg):
    print(f"vcan-guest: {msg}", flush=True)


def run(cmd, timeout, **kw):
    """Runs CMD, prints its output; raises with the output when it fails."""
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, **kw)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stdout}{p.stderr}")
    return p.stdout


def vcan_up():
    if subprocess.run(["ip", "link", "show", IFACE], capture_output=True).returncode != 0:
        run(["ip", "link", "add", "dev", IFACE, "type", "vcan"], 30)  # else: a bench's own vcan0
    run(["ip", "link", "set", IFACE, "mtu", "72", "up"], 30)
    return run(["ip", "-details", "link", "show", IFACE], 30).strip()


def fsw_ack_frame(run_id, imu_frames):
    """A well-formed FSW_ACK (id 0x041, 24 bytes, CRC per hal/can/sdins.dbc) of another run."""
    payload = run_id.to_bytes(4, "little") + imu_frames.to_bytes(4, "little") + bytes(14)
    crc = binascii.crc_hqx(bytes([0x41, 0x00]) + payload, 0xFFFF)
    return "041##1" + (payload + crc.to_bytes(2, "little")).hex().upper()


# What is injected during the lockstep run, and the counter each frame must land in (fsw --json).
BURST = 100  # unknown-ID frames sent back to back by cangen
INJECTED = [
    # (cansend frame, fsw counter, what it is)
    ("123#0011223344556677", "unknown_id", "classic frame, unknown standard ID"),
    ("7FF##1" + "11" * 12, "unknown_id", "FD frame, unknown standard ID"),
    ("12345678##1" + "22" * 8, "unknown_id", "FD frame, extended ID"),
    ("010##1" + "33" * 8, "bad_length", "IMU_SAMPLE ID, FD, 8 bytes (48 expected)"),
    ("020##1" + "44" * 20, "bad_length", "GPS_EPOCH ID, FD, 20 bytes (24 expected)"),
    ("010#1122334455667788", "bad_length", "IMU_SAMPLE ID as a classic frame (FD expected)"),
    ("040#0102030405060708", "control_rejected", "SIM_CONTROL ID as a classic frame"),
    ("010##1" + "55" * 48, "bad_crc", "IMU_SAMPLE, right length, CRC wrong"),
    (fsw_ack_frame(0xDEADBEEF, 1234), "foreign_acks", "FSW_ACK of another run (valid CRC)"),
    ("123#R", "bus_unsupported", "remote frame (the transport rejects it)"),
]


def inject(out_dir):
    """Sends INJECTED and a BURST of unknown-ID frames; returns what was sent."""
    sent = []
    for frame, counter, what in INJECTED:
        run(["cansend", IFACE, frame], 30)
        sent.append({"frame": frame, "counter": counter, "what": what})
    # cangen: BURST classic frames, ID 0x7A0, 8 bytes, no gap (-g 0), as fast as the socket takes them.
    run(["cangen", IFACE, "-I", "7A0", "-L", "8", "-D", "i", "-g", "0", "-n", str(BURST)], 60)
    sent.append({"frame": "7A0#<8 bytes> x%d (cangen -g 0)" % BURST, "counter": "unknown_id", "count": BURST,
                 "what": "burst of unknown-ID classic frames"})
    with open(os.path.join(out_dir, "injected.json"), "w") as f:
        json.dump(sent, f, indent=1)
    return sent


def pin(cpu):
    """taskset -c CPU: vcan hands a frame to the network stack on the sending CPU (netif_rx), so
    frames a process sends from two CPUs can overtake each other; one sender, one CPU keeps them in order."""
    return ["taskset", "-c", str(cpu % os.cpu_count())] if os.cpu_count() > 1 else []


def start(cmd, out_dir, name):
    out = open(os.path.join(out_dir, name + ".out"), "w")
    return subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT), out


def wait_text(path, text, timeout_s, proc):
    deadline = time.time() + timeout_s
    while time.time() < deadline:
        if os.path.exists(path) and text in open(path, errors="replace").read():
            return
        if proc.poll() is not None:
            break
        time.sleep(0.05)
    raise RuntimeError(f"no '{text}' in {path} within {timeout_s} s (exit {proc.poll()}):\n"
                       + (open(path, errors="replace").read() if os.path.exists(path) else "(no output)"))


def candump_start(out_dir, name):
    """candump -L on vcan0 into NAME.log; returns the process once it listens."""
    # Into the guest's memory (/dev/shm), copied out at the end: writing through 9p under emulation
    # is slow enough for candump's socket to overflow. -r: a receive buffer as large as the fsw's.
    logf = open(os.path.join("/dev/shm", name + ".log"), "w")
    errf = open(os.path.join(out_dir, name + ".err"), "w")
    p = subprocess.Popen(["candump", "-L", "-r", str(4 << 20), IFACE], stdout=logf, stderr=errf)
    time.sleep(0.5)  # candump has no "listening" line; it binds within milliseconds
    if p.poll() is not None:
        raise RuntimeError(f"candump exited {p.returncode}: {open(errf.name).read()}")
    return p, logf


def candump_stop(p, logf, out_dir):
    p.send_signal(signal.SIGINT)  # candump ends its loop and flushes stdout
    p.wait(timeout=30)
    logf.close()
    shutil.move(logf.name, os.path.join(out_dir, os.path.basename(logf.name)))


def finish(p, f, what, timeout_s):
    try:
        p.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        p.kill()
        p.wait()
        f.close()
        raise RuntimeError(f"{what} did not finish within {timeout_s} s:\n" + open(f.name).read())
    f.close()
    if p.returncode != 0:
        raise RuntimeError(f"{what} exit {p.returncode}:\n" + open(f.name).read())


def unit_tests(job, out_dir):
    js = os.path.join(out_dir, "gtest_socketcan.json")
    p = subprocess.run([job["unit_tests"], "--gtest_filter=CanBusSocketCan.*", "--gtest_output=json:" + js],
                       capture_output=True, text=True, timeout=300)
    open(os.path.join(out_dir, "gtest_socketcan.out"), "w").write(p.stdout + p.stderr)
    if p.returncode != 0:
        raise RuntimeError(f"CanBusSocketCan.* failed (exit {p.returncode}):\n{p.stdout}{p.stderr}")
    log("CanBusSocketCan.* passed")


def lockstep(job, out_dir):
    sdins, bus = job["sdins"], "socketcan:" + IFACE
    d = os.path.join(out_dir, "lockstep")
    os.makedirs(d, exist_ok=True)
    dump, dumpf = candump_start(d, "candump")
    fsw, fswf = start(pin(1) + [sdins, "fsw", "--can", bus, "--lcm-url", "none", "--idle-timeout", "30",
                       "--json", os.path.join(d, "fsw.json"), "--log", os.path.join(d, "fsw.lcmlog")], d, "fsw")
    wait_text(fswf.name, "listening", 60, fsw)
    t0 = time.time()
    sim, simf = start(pin(0) + [sdins, "bus-sim", "--can", bus, "--lockstep", "--duration", str(job["duration_s"]),
                       "--seed", str(job["seed"]), "--json", os.path.join(d, "bus_sim.json")], d, "bus_sim")
    # Inject once the run is under way (the fsw has acknowledged frames), while it goes on.
    deadline = time.time() + 120
    while os.path.getsize(dumpf.name) < 200000 and sim.poll() is None and time.time() < deadline:
        time.sleep(0.05)  # candump's output (block-buffered) past 200 kB: about 1300 frames into the run
    inject(d)
    injected_during_run = sim.poll() is None
    finish(sim, simf, "sdins bus-sim --lockstep", job["timeout_s"])
    wall = time.time() - t0
    finish(fsw, fswf, "sdins fsw", 120)
    candump_stop(dump, dumpf, d)
    if not injected_during_run:
        raise RuntimeError("the run ended before the injection did: lengthen duration_s")
    log(f"lockstep run done in {wall:.1f} s wall")
    return {"wall_s": wall, "injected_during_run": injected_during_run}


def realtime(job, out_dir):
    sdins, bus = job["sdins"], "socketcan:" + IFACE
    d = os.path.join(out_dir, "realtime")
    os.makedirs(d, exist_ok=True)
    dump, dumpf = candump_start(d, "candump")
    fsw, fswf = start(pin(1) + [sdins, "fsw", "--can", bus, "--lcm-url", "none", "--realtime", "--idle-timeout", "20",
                       "--json", os.path.join(d, "fsw.json")], d, "fsw")
    wait_text(fswf.name, "listening", 60, fsw)
    t0 = time.time()
    sim, simf = start(pin(0) + [sdins, "bus-sim", "--can", bus, "--realtime", "--duration", str(job["realtime_s"]),
                       "--seed", str(job["seed"]), "--json", os.path.join(d, "bus_sim.json")], d, "bus_sim")
    finish(sim, simf, "sdins bus-sim --realtime", job["realtime_s"] * 4 + 120)
    wall = time.time() - t0
    finish(fsw, fswf, "sdins fsw --realtime", 120)
    candump_stop(dump, dumpf, d)
    log(f"realtime run done in {wall:.1f} s wall")
    return {"wall_s": wall}


def main():
    job = json.load(open(sys.argv[1]))
    out_dir = job["out_dir"]
    result = {"ok": False, "steps": {}}
    t0 = time.time()
    try:
        result["uname"] = os.uname().release
        result["vcan0"] = vcan_up()
        log("vcan0 up (CAN FD, MTU 72)")
        unit_tests(job, out_dir)
        result["steps"]["unit_tests"] = True
        result["steps"]["lockstep"] = lockstep(job, out_dir)
        result["steps"]["realtime"] = realtime(job, out_dir)
        result["ok"] = True
    except Exception as e:  # every failure goes back to the host with its text
        result["error"] = f"{type(e).__name__}: {e}"
        log("FAILED: " + result["error"])
    result["guest_wall_s"] = time.time() - t0
    with open(os.path.join(out_dir, "guest.json.tmp"), "w") as f:
        json.dump(result, f, indent=1)
    os.rename(os.path.join(out_dir, "guest.json.tmp"), os.path.join(out_dir, "guest.json"))
    return 0 if result["ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
