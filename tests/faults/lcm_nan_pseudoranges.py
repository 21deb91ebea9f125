#!/usr/bin/env python3
"""Copies an LCM log, giving the first measurement of every 10th GNSS_RAW epoch a NaN pseudorange
(the fault case of tests/faults/counted_drops.sh). The messages are re-encoded by the Python code
lcm-gen generates from hal/lcm/*.lcm; the log framing (sync word, event number, timestamp, channel
length, data length, channel, data; big-endian) is read and written here. Prints the number of
measurements poisoned.

usage: lcm_nan_pseudoranges.py GENERATED_PYTHON_DIR IN.lcmlog OUT.lcmlog
"""
import struct
import sys

sys.path.insert(0, sys.argv[1])
from sdins import gnss_raw_epoch_t  # noqa: E402

SYNC = 0xEDA1DA01
data = open(sys.argv[2], "rb").read()
out = bytearray()
at = 0
epoch = 0
poisoned = 0
while at + 28 <= len(data):
    sync, num, ts, clen, dlen = struct.unpack_from(">IqqII", data, at)
    assert sync == SYNC, f"bad sync word at byte {at}"
    chan = data[at + 28:at + 28 + clen]
    body = data[at + 28 + clen:at + 28 + clen + dlen]
    at += 28 + clen + dlen
    if chan == b"GNSS_RAW":
        m = gnss_raw_epoch_t.decode(body)
        if epoch % 10 == 0 and m.n_meas > 0:
            m.meas[0].pseudorange_m = float("nan")
            body = m.encode()
            poisoned += 1
        epoch += 1
    out += struct.pack(">IqqII", SYNC, num, ts, len(chan), len(body)) + chan + body
open(sys.argv[3], "wb").write(bytes(out))
print(poisoned)
