"""Pieces the Python end-to-end scripts in this folder share (imported from beside them).

skip(why): "SKIPPED: why" and exit 77 (CTest: skipped).
recordings_dir(default): the one setting for the recordings (docs/data.md): $SDINS_RECORDINGS_DIR,
  else the default the test was given.
need_datasets(data, names, hint, noun) / need_convbin(): skip unless the data sets / RTKLIB's convbin are there.
fresh_dir(path): an empty directory at path (a previous run's removed).
run_sdins(sdins, *args, echo=False): `sdins ARGS`, its stdout; a failure prints its output and ends
  the script with "sdins ARGS failed with exit N". With echo the output's tails are printed always.
read_until(proc, stream, found, timeout_s): reads a child's pipe until found(text so far) holds.
"""
import os
import select
import shutil
import subprocess
import sys
import time


def skip(why):
    print(f"SKIPPED: {why}")
    sys.exit(77)


def recordings_dir(default):
    return os.environ.get("SDINS_RECORDINGS_DIR") or default


def need_datasets(data, names, hint, noun="data set"):
    for d in names:
        if not os.path.isdir(os.path.join(data, d)):
            skip(f"{noun} {os.path.join(data, d)} is missing ({hint})")


def need_convbin():
    if shutil.which("convbin") is None:
        skip("RTKLIB's convbin is not installed (Debian package rtklib, in tools/setup)")


def fresh_dir(path):
    shutil.rmtree(path, ignore_errors=True)
    os.makedirs(path)


def run_sdins(sdins, *args, echo=False):
    p = subprocess.run([sdins, *args], capture_output=True, text=True)
    if echo:
        print(p.stdout[-6000:], p.stderr[-2000:])
    if p.returncode != 0:
        if not echo:
            print(p.stdout, p.stderr)
        raise SystemExit(f"sdins {' '.join(args)} failed with exit {p.returncode}")
    return p.stdout


def read_until(proc, stream, found, timeout_s):
    """(True, text) as soon as found(text) holds for the text read so far; (False, text) once the
    pipe closes or timeout_s runs out, with proc killed."""
    deadline = time.time() + timeout_s
    buf = ""
    while time.time() < deadline:
        r, _, _ = select.select([stream], [], [], max(0.0, deadline - time.time()))
        if not r:
            break
        chunk = os.read(stream.fileno(), 4096).decode(errors="replace")
        if not chunk:
            break
        buf += chunk
        if found(buf):
            return True, buf
    proc.kill()
    return False, buf
