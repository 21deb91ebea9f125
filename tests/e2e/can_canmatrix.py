#!/usr/bin/python3
"""Independent decoder check of the sdins CAN protocol.

`sdins can encode` flies a short scenario and writes the protocol frames to a candump log and,
alongside, a CSV of the physical value every signal must decode to (taken from the encoder's
inputs, with the tolerance the protocol promises). This script reads the log with python-can's
candump reader, decodes every frame with python3-canmatrix against hal/can/sdins.dbc, checks the
CRC with Python's own CRC-CCITT (binascii.crc_hqx), and compares every decoded signal with the
CSV. It also checks the stream's structure: IMU counters +1, one GPS_EPOCH followed by
GpsNumMeas GPS_MEAS frames of its sequence number, the whole almanac present.

usage: can_canmatrix.py SDINS DBC WORKDIR
"""
import binascii
import csv
import os
import subprocess
import sys

import can
import canmatrix.formats
from canmatrix import ArbitrationId


def main():
    sdins, dbc, work = sys.argv[1], sys.argv[2], sys.argv[3]
    os.makedirs(work, exist_ok=True)
    log = os.path.join(work, "encoded.log")
    exp = os.path.join(work, "expected.csv")
    subprocess.run([sdins, "can", "encode", "--duration", "2.5", "--out", log, "--expected", exp], check=True)

    db = canmatrix.formats.loadp_flat(dbc)
    frames = {f.arbitration_id.id: f for f in db.frames}
    # Sensor frames, and the lockstep flow control (SIM_CONTROL, FSW_ACK: decoded from a recorded HIL
    # run by tests/e2e/hil.py lockstep).
    assert sorted(frames) == [0x010, 0x020, 0x021, 0x030, 0x040, 0x041], sorted(frames)
    for f in frames.values():
        assert f.is_fd, f"{f.name} is not marked CAN FD in the DBC"

    decoded = {}  # line -> (message name, {signal: phys})
    counts = {}
    msgs = list(can.LogReader(log))
    for line, m in enumerate(msgs, start=1):
        assert not m.is_extended_id, f"line {line}: extended id"
        assert m.is_fd and m.bitrate_switch, f"line {line}: not an FD/BRS frame"
        fr = frames.get(m.arbitration_id)
        assert fr is not None, f"line {line}: unknown id {m.arbitration_id:#x}"
        data = bytes(m.data)
        assert len(data) == fr.size, f"line {line}: {fr.name} length {len(data)} != DBC {fr.size}"
        crc = binascii.crc_hqx(bytes([m.arbitration_id & 0xFF, m.arbitration_id >> 8]) + data[:-2], 0xFFFF)
        assert crc == int.from_bytes(data[-2:], "little"), f"line {line}: CRC mismatch"
        sig = {name: v.phys_value for name, v in fr.decode(data).items()}
        decoded[line] = (fr.name, sig)
        counts[fr.name] = counts.get(fr.name, 0) + 1

    # Every expected value against canmatrix's decoding.
    checked = 0
    worst = {}
    with open(exp) as fh:
        for row in csv.DictReader(fh):
            line = int(row["line"])
            name, sig = decoded[line]
            assert name == row["message"], f"line {line}: {name} != {row['message']}"
            got = float(sig[row["signal"]])
            want = float(row["value"])
            tol = float(row["tolerance"])
            err = abs(got - want)
            assert err <= tol, f"line {line} {row['signal']}: canmatrix {got!r}, expected {want!r} +- {tol!r}"
            key = row["signal"]
            worst[key] = max(worst.get(key, 0.0), err / tol if tol > 0 else 0.0)
            checked += 1

    # Stream structure.
    counter = None
    pending = None  # (seq, remaining)
    prns = set()
    for line in sorted(decoded):
        name, sig = decoded[line]
        if name == "IMU_SAMPLE":
            c = int(sig["ImuCounter"])
            assert counter is None or c == counter + 1, f"line {line}: counter {c} after {counter}"
            counter = c
        elif name == "GPS_EPOCH":
            assert pending is None or pending[1] == 0, f"line {line}: epoch before the last one's measurements"
            pending = (int(sig["GpsEpochSeq"]), int(sig["GpsNumMeas"]))
            assert int(sig["GpsTimeValid"]) == 1
        elif name == "GPS_MEAS":
            assert pending is not None and pending[1] > 0, f"line {line}: measurement without a header"
            assert int(sig["GpsMeasEpochSeq"]) == pending[0], f"line {line}: wrong epoch sequence"
            pending = (pending[0], pending[1] - 1)
        elif name == "GPS_ALMANAC":
            prns.add(int(sig["AlmPrn"]))

    assert counts.get("IMU_SAMPLE") == 2500, counts
    assert counts.get("GPS_EPOCH") == 2, counts
    assert counts.get("GPS_MEAS", 0) >= 8, counts
    assert len(prns) >= 24, prns
    print(f"canmatrix decoded {len(msgs)} frames {counts}; {checked} signal values within tolerance")
    print("worst error / tolerance per signal: " + ", ".join(f"{k}={v:.3f}" for k, v in sorted(worst.items())))


if __name__ == "__main__":
    main()
