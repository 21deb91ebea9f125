#!/usr/bin/env python3
"""Compares the QEMU image's target replay output with the host's (tests/e2e/target_qemu.sh;
docs/baremetal-qemu.md) and writes the JSON report. Exit 1 on a mismatch or a budget overrun."""
import argparse
import json
import os
import shlex
import struct
import sys

# The tolerance of matches_host and its reason. Both builds use -ffp-contract=off (no fused
# multiply-add on the M7), but newlib's libm (target) and glibc's (host) round sin, cos, atan2, ...
# differently in the last bit for a few percent of the arguments (the libm probe measures it on
# every run), and the host's Eigen sums its SSE2 packet reductions in another order than the M7's
# scalar Eigen (a host build with -DEIGEN_DONT_VECTORIZE differs from the default one by as much;
# docs/baremetal-qemu.md). The first differing result appears at the
# initialisation (the single-point fix: Kepler's equation, atan2), and the stable filter carries it
# as a last-bits difference. Observed over 40 s: lat/lon 4e-16 rad, h 6e-9 m, velocity 1.5e-10 m/s,
# quaternion 2e-13, P relative 1.2e-13, NIS relative 3e-9. The tolerances are 100-1000x those and
# far below any real divergence (a wrong input or configuration moves these by > 1e-3). Counts
# (frames, epochs, measurements used, health counters) must be equal exactly.
TOL_ABS = {"t_s": 0.0, "lat_rad": 1e-13, "lon_rad": 1e-13, "h_m": 1e-6, "vel_e_mps": 1e-8, "vel_n_mps": 1e-8,
           "vel_u_mps": 1e-8, "qw": 1e-10, "qx": 1e-10, "qy": 1e-10, "qz": 1e-10, "clock_bias_m": 1e-6,
           "clock_drift_mps": 1e-8, "pr_used": 0, "prr_used": 0}
TOL_REL = {"nis_sum": 1e-6, "sigma": 1e-10}

FRAME_FIELDS = ["t_s", "lat_rad", "lon_rad", "h_m", "vel_e_mps", "vel_n_mps", "vel_u_mps", "qw", "qx", "qy", "qz"]
EPOCH_FIELDS = ["t_s", "clock_bias_m", "clock_drift_mps", "nis_sum"]  # then pr_used prr_used (decimal), sqrt(diag P)

# The budget: an estimate, not a measurement. A 400 MHz Cortex-M7 (e.g. STM32H743) retiring an
# assumed 0.5 instructions per cycle on this double-precision code (the M7 dual-issues integer
# work, but FPv5-D16 double multiplies and divides/square roots take several cycles each);
# QEMU counts instructions, not cycles.
# Group budgets: the 200 Hz group its 5 ms period; the 1 Hz group its deadline, the
# ekf_latency_frames frames (10 x 5 ms = 50 ms) after its release at which its correction lands
# (fsw/executive.hpp), of which the 200 Hz group takes its share first (preemption).
CPU_HZ = 400e6
IPC_ASSUMED = 0.5
FRAME_S = 0.005
EKF_DEADLINE_S = 0.050


def dbl(h):
    return struct.unpack("<d", struct.pack("<Q", int(h, 16)))[0]


def parse(path):
    out = {"F": {}, "E": {}, "T": {}, "D": {}, "S": {}, "I": {}, "C": None, "END": None, "DWT": None, "STACK": None, "other": []}
    with open(path) as f:
        for line in f:
            w = line.split()
            if not w:
                continue
            tag = w[0]
            if tag == "C":
                out["C"] = w[1:]
            elif tag == "END":
                out["END"] = w[-2:]  # result, write error (the image's line names them first)
            elif tag == "DWT":
                out["DWT"] = w[-3:]
            elif tag == "STACK":
                out["STACK"] = [int(x) for x in w[-2:]]
            elif tag[0] in "FETDSI" and tag[1:] in ("24", "15"):
                out[tag[0]].setdefault(tag[1:], []).append(w[1:])
            else:
                out["other"].append(line.rstrip())
    return out


def pct(sorted_vals, p):
    if not sorted_vals:
        return None
    k = min(len(sorted_vals) - 1, int(round(p / 100.0 * (len(sorted_vals) - 1))))
    return sorted_vals[k]


def compare_rows(a_rows, b_rows, names, n_hex_head, n_dec):
    """Bitwise equality, per-field max |a - b| (and relative for nis_sum and the P diagonal) and the
    fields out of tolerance; rows: n_hex_head hex, n_dec decimal, then hex (the P diagonal)."""
    n = min(len(a_rows), len(b_rows))
    bit_equal = len(a_rows) == len(b_rows)
    diff, rel = {}, {}
    for i in range(n):
        a, b = a_rows[i], b_rows[i]
        if a != b:
            bit_equal = False
        if len(a) != len(b):
            diff["row_length"] = 1
            continue
        for k, (x, y) in enumerate(zip(a, b)):
            if n_hex_head <= k < n_hex_head + n_dec:
                name = ["pr_used", "prr_used"][k - n_hex_head]
                diff[name] = max(diff.get(name, 0), abs(int(x) - int(y)))
                continue
            name = names[k] if k < n_hex_head else "sigma"
            u, v = dbl(x), dbl(y)
            diff[name] = max(diff.get(name, 0.0), abs(u - v))
            if name in TOL_REL:
                scale = max(abs(u), abs(v))
                rel[name] = max(rel.get(name, 0.0), abs(u - v) / scale if scale > 0 else 0.0)
    out_of_tol = [k for k, v in diff.items() if k in TOL_ABS and v > TOL_ABS[k]]
    out_of_tol += [k for k, v in rel.items() if v > TOL_REL[k]]
    if "row_length" in diff or len(a_rows) != len(b_rows):
        out_of_tol.append("rows")
    return bit_equal, diff, rel, out_of_tol, n


def libm_probe(d):
    """Per function: results compared, results that differ, the largest difference in ULP."""
    def read(p):
        with open(p) as f:
            return [l.split() for l in f if l.startswith("L")]
    try:
        h, i = read(f"{d}/libm_host.txt"), read(f"{d}/libm_image.txt")
    except OSError:
        return None
    if len(h) != len(i) or not h:
        return {"error": f"{len(h)} host results, {len(i)} image results"}
    out = {}
    for (fh, xh), (fi, xi) in zip(h, i):
        e = out.setdefault(fh[1:], {"results": 0, "differ": 0, "max_ulp": 0})
        e["results"] += 1
        if fh != fi:
            e["error"] = "function order differs"
        if xh != xi:
            e["differ"] += 1
            e["max_ulp"] = max(e["max_ulp"], abs(int(xh, 16) - int(xi, 16)))
    for e in out.values():
        e["fraction"] = e["differ"] / e["results"]
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--elf", required=True)
    ap.add_argument("--qemu-version", required=True)
    ap.add_argument("--qemu-args", required=True)
    ap.add_argument("--qemu-wall-s", type=float, required=True)
    ap.add_argument("--arm-compile-commands", required=True)
    ap.add_argument("--host-compile-commands", required=True)
    ap.add_argument("--json", required=True)
    a = ap.parse_args()
    d = a.out
    host, image = parse(f"{d}/host.txt"), parse(f"{d}/image.txt")
    problems = []
    if image["END"] is None or image["END"][0] != "0" or image["END"][1] != "0":
        problems.append(f"the image's replay did not end cleanly: END {image['END']}")
    if host["END"] is None or host["END"][0] != "0":
        problems.append(f"the host replay did not end cleanly: END {host['END']}")
    if image["other"]:
        problems.append(f"unexpected image output: {image['other'][:3]}")

    fpu = None
    calib = None
    if image["C"]:
        mvfr0, mvfr1, mvfr2, cpacr = (int(x, 16) for x in image["C"][:4])
        # MVFR0[11:8] double precision, [7:4] single precision (2: supported incl. divide/sqrt [23:16]).
        fpu = {"mvfr0": f"0x{mvfr0:08x}", "mvfr1": f"0x{mvfr1:08x}", "mvfr2": f"0x{mvfr2:08x}",
               "cpacr": f"0x{cpacr:08x}", "double_precision": (mvfr0 >> 8) & 0xF == 2,
               "single_precision": (mvfr0 >> 4) & 0xF == 2, "fma": (mvfr1 >> 28) & 0xF == 1,
               "registers_d16": mvfr0 & 0xF == 1}
        calib = {"loop_instructions": int(image["C"][4]), "systick_ticks": int(image["C"][5])}
        calib["instructions_per_tick"] = calib["loop_instructions"] / calib["systick_ticks"] if calib["systick_ticks"] else None
    else:
        problems.append("no C line (FPU registers, calibration) from the image")
    ipt = 40.0  # 25 MHz SysTick (processor clock of QEMU's mps2) at 1 ns per instruction (-icount shift=0)
    if calib and calib["instructions_per_tick"] and abs(calib["instructions_per_tick"] - ipt) > 0.5:
        problems.append(f"SysTick calibration {calib['instructions_per_tick']:.3f} instructions/tick, expected {ipt}")

    hil = {m: json.load(open(f"{d}/replay{m}.json")) for m in ("24", "15")}
    models = {}
    matches = True
    budget_instr = CPU_HZ * FRAME_S * IPC_ASSUMED
    budget_epoch = CPU_HZ * EKF_DEADLINE_S * IPC_ASSUMED
    notes = []
    over_budget = False
    for m in ("24", "15"):
        fh, fi = host["F"].get(m, []), image["F"].get(m, [])
        eh, ei = host["E"].get(m, []), image["E"].get(m, [])
        f_equal, f_diff, f_rel, f_bad, nf = compare_rows(fh, fi, FRAME_FIELDS, len(FRAME_FIELDS), 0)
        e_equal, e_diff, e_rel, e_bad, ne = compare_rows(eh, ei, EPOCH_FIELDS, len(EPOCH_FIELDS), 2)
        dh, di = host["D"].get(m, [[None]])[0], image["D"].get(m, [[None]])[0]
        sh, si = host["S"].get(m, [[None]])[0], image["S"].get(m, [[None]])[0]
        digest_host = dh[0]
        hil_digest = hil[m]["digest"]
        bit_identical = f_equal and e_equal and dh == di and sh == si
        # D lines: digest, frames, epochs (the digest differs when any bit does); S lines: health.
        match = not f_bad and not e_bad and dh[1:] == di[1:] and sh == si and nf > 0 and ne > 0
        matches = matches and match
        if digest_host != hil_digest or int(dh[1]) != hil[m]["nav_frames"]:
            problems.append(f"model {m}: the host replay of the recorded input ({digest_host}, {dh[1]} frames) is not "
                            f"HIL's replay of the log ({hil_digest}, {hil[m]['nav_frames']} frames)")
        if not match:
            problems.append(f"model {m}: the image's output differs from the host's beyond the tolerance: "
                            f"{f_bad + e_bad}, counts {dh[1:]} vs {di[1:]}, health {sh == si}")
        # Instruction counts (SysTick ticks x instructions per tick), per frame.
        t_rows = image["T"].get(m, [])
        frames_200, epochs_1 = [], []
        gnss_conv = []
        # T rows: frame, 200 Hz group ticks (IMU path incl. landing a correction), on_gnss ticks,
        # released flag, 1 Hz group ticks (run apart, after the frame that released it).
        for frame, imu_t, gnss_t, released, ekf_t in ((int(r[0]), int(r[1]), int(r[2]), r[3] == "1", int(r[4]))
                                                      for r in t_rows):
            frames_200.append(((imu_t + gnss_t) * ipt, frame))
            if released:
                epochs_1.append((ekf_t * ipt, frame))
            if gnss_t:
                gnss_conv.append(gnss_t * ipt)

        def stats(rows):
            if not rows:
                return None
            v = sorted(x for x, _ in rows)
            worst = max(rows)
            return {"count": len(v), "median": pct(v, 50), "p99": pct(v, 99), "p999": pct(v, 99.9), "max": worst[0],
                    "max_frame": worst[1], "max_t_s": dbl(fi[worst[1]][0]) if worst[1] < len(fi) else None}

        pre = image["I"].get(m, [[0, 0]])[0]
        instr = {"frame_200hz": stats(frames_200), "epoch_1hz": stats(epochs_1),
                 "gnss_conversion_max": max(gnss_conv) if gnss_conv else None,
                 "pre_init_on_imu_max": int(pre[0]) * ipt, "pre_init_on_gnss_max": int(pre[1]) * ipt}
        for k, budget in (("frame_200hz", budget_instr), ("epoch_1hz", budget_epoch)):
            s = instr[k]
            if s is None:
                problems.append(f"model {m}: no instruction counts for {k}")
                continue
            s["budget_instructions"] = budget
            s["budget_fraction"] = s["max"] / budget
            s["estimated_max_ms_at_400mhz"] = s["max"] / IPC_ASSUMED / CPU_HZ * 1e3
            if s["max"] > budget:
                over_budget = True
                problems.append(f"model {m}: {k} worst {s['max']:.0f} instructions > budget {budget:.0f}")
        for k in ("pre_init_on_imu_max", "pre_init_on_gnss_max"):
            if instr[k] > budget_instr:
                over_budget = True
                problems.append(f"model {m}: {k} {instr[k]:.0f} instructions > budget {budget_instr:.0f}")
        models[m] = {"matches_host": match, "bit_identical": bit_identical, "frames": nf, "epochs": ne,
                     "frames_host": len(fh), "frames_image": len(fi),
                     "max_abs_diff": {"frame": f_diff, "epoch": e_diff},
                     "max_rel_diff": {"frame": f_rel, "epoch": e_rel},
                     "digest": {"image": di[0] if di else None, "host": digest_host, "hil_replay": hil_digest},
                     "health_image": si, "instructions": instr}

    def flags(path, needle):
        try:
            for e in json.load(open(path)):
                if e["file"].endswith(needle):
                    cmd = e.get("command") or " ".join(e.get("arguments", []))
                    return [t for t in shlex.split(cmd) if t.startswith(("-O", "-m", "-f", "-std", "-D"))]
        except (OSError, ValueError, KeyError):
            pass
        return None

    stack = None
    if image["STACK"]:
        used, reserved = image["STACK"]
        stack = {"used_bytes": used, "reserved_bytes": reserved,
                 "method": "the stack painted at start, the deepest overwritten word at the end"}
        # Using all of it means the paint is gone to the bottom: an overflow into .bss is possible.
        if used >= reserved:
            problems.append(f"stack: {used} of {reserved} B used (overflow possible)")
    else:
        problems.append("no STACK line from the image")
    probe = libm_probe(d)
    if probe is None or "error" in probe:
        problems.append(f"libm probe: {probe}")
    report = {
        "matches_host": matches,
        "bit_identical": all(models[m]["bit_identical"] for m in models),
        "tolerance": {"abs": TOL_ABS, "rel": TOL_REL,
                      "reason": "newlib (target) and glibc (host) libm round sin/cos/tan/asin/atan2/hypot differently "
                                "in the last bit for some arguments (libm_probe), and the host's Eigen vectorizes "
                                "(SSE2) where the M7's is scalar; both builds use -ffp-contract=off"},
        "libm_probe": probe,
        "stack": stack,
        "frames": models["24"]["frames"],
        "max_abs_diff": models["24"]["max_abs_diff"],
        "models": models,
        "instructions": {
            "worst_200hz_frame": {m: models[m]["instructions"]["frame_200hz"]["max"] if models[m]["instructions"]["frame_200hz"] else None for m in models},
            "worst_1hz_epoch": {m: models[m]["instructions"]["epoch_1hz"]["max"] if models[m]["instructions"]["epoch_1hz"] else None for m in models},
            "source": "QEMU -icount shift=0 (1 instruction = 1 ns virtual time), SysTick on the 25 MHz processor clock "
                      "read around each FlightApp call: ticks x 40 instructions (+-40 per call)",
            "per_frame": "200 Hz group: a navigation frame, the on_imu calls that make it (landing a correction "
                         "included) plus the on_gnss conversions that arrived in it; 1 Hz group: one run of "
                         "run_ekf_group() (propagation, update, correction), counted apart from the frame that released it",
            "budget": {"cpu_hz": CPU_HZ, "ipc_assumed": IPC_ASSUMED, "frame_s": FRAME_S, "ekf_deadline_s": EKF_DEADLINE_S,
                       "instructions_per_frame": budget_instr, "instructions_per_epoch": budget_epoch,
                       "note": "an estimate, not a measurement: QEMU counts instructions, a real M7's cycles "
                               "depend on its pipeline, caches and TCM placement"},
            "calibration": calib,
        },
        "fpu": fpu,
        "dwt_probe": ({"ctrl": image["DWT"][0], "cyccnt_before": image["DWT"][1], "cyccnt_after": image["DWT"][2],
                       "modelled": image["DWT"][1] != image["DWT"][2]} if image["DWT"] else None),
        "qemu": {"version": a.qemu_version, "args": a.qemu_args, "wall_s": a.qemu_wall_s},
        "image": {"elf": os.path.abspath(a.elf), "size_bytes": os.path.getsize(a.elf)},
        "flags": {"arm_fsw": flags(a.arm_compile_commands, "fsw/src/ekf.cpp"),
                  "host_fsw": flags(a.host_compile_commands, "fsw/src/ekf.cpp")},
        "input": {"bytes": os.path.getsize(f"{d}/input.bin")},
        "problems": problems,
        "notes": notes,
    }
    with open(a.json, "w") as f:
        json.dump(report, f, indent=2)
    for m in ("24", "15"):
        r = models[m]
        i = r["instructions"]
        print(f"model {m}: matches_host {r['matches_host']} (bit_identical {r['bit_identical']}), {r['frames']} frames, {r['epochs']} epochs, digest "
              f"{r['digest']['image']} (host {r['digest']['host']}, HIL replay {r['digest']['hil_replay']})")
        if i["frame_200hz"] and i["epoch_1hz"]:
            print(f"  instructions: 200 Hz frame median {i['frame_200hz']['median']:.0f} p99.9 {i['frame_200hz']['p999']:.0f} "
                  f"max {i['frame_200hz']['max']:.0f}; 1 Hz epoch median {i['epoch_1hz']['median']:.0f} max "
                  f"{i['epoch_1hz']['max']:.0f}; before init: on_imu {i['pre_init_on_imu_max']:.0f}, on_gnss "
                  f"{i['pre_init_on_gnss_max']:.0f}; budgets (estimates) {budget_instr:.0f} per 5 ms frame, "
                  f"{budget_epoch:.0f} per 1 Hz run (its 50 ms deadline)")
        print("  max_abs_diff:", json.dumps(r["max_abs_diff"]))
    if probe and "error" not in probe:
        print("libm probe (results differing newlib vs glibc):",
              ", ".join(f"{k} {v['differ']}/{v['results']} (max {v['max_ulp']} ulp)" for k, v in probe.items()))
    if stack:
        print(f"stack: {stack['used_bytes']} of {stack['reserved_bytes']} B used (high-water mark)")
    print("fpu:", json.dumps(fpu), "| qemu:", a.qemu_version, f"{a.qemu_wall_s:.1f} s")
    for n in notes:
        print("NOTE:", n)
    for p in problems:
        print("PROBLEM:", p)
    return 1 if problems or not matches or over_budget else 0


if __name__ == "__main__":
    sys.exit(main())
