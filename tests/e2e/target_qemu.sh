#!/usr/bin/env bash
# The Cortex-M7 image runs, in QEMU (docs/baremetal-qemu.md; issue 16). Builds the bare-metal image
# for QEMU's mps2-an500 (preset arm-cortex-m7, target sdins_fsw_mps2), records a short simulated
# bank-to-turn flight with GNSS (`sdins sil`, its LCM log -> `sdins_target record`), runs the image
# on it under qemu-system-arm -icount shift=0 with a time limit, runs the host replay of the same
# input (`sdins_target replay`: the same replay source on the host's sdins_fsw), checks the host
# replay against HIL's own replay of the log (`sdins replay`: the same navigation digest), compares
# the image's output with the host's field by field and writes the JSON report:
#   matches_host, frames, max_abs_diff per field, instructions (worst 200 Hz frame, worst 1 Hz epoch,
#   the budget), qemu version, fpu registers, compile flags.
# Also runs the libm probe on both (fsw/baremetal/replay.hpp): how often newlib and glibc round the
# functions fsw/ calls differently, the reason the image cannot be bit-identical to the host.
# Fails on a mismatch, a QEMU failure or timeout, or an instruction count over the budget.
# Usage: target_qemu.sh SOURCE_DIR SDINS SDINS_TARGET OUTDIR [DURATION_S]
set -euo pipefail
src=${1:?usage: target_qemu.sh SOURCE_DIR SDINS SDINS_TARGET OUTDIR [DURATION_S]}
sdins=${2:?}; sdins_target=${3:?}; out=${4:?}; duration=${5:-40}
qemu=${SDINS_QEMU:-qemu-system-arm}
command -v "$qemu" > /dev/null || { echo "$qemu not found (Debian: qemu-system-arm; tools/setup)"; exit 1; }
command -v arm-none-eabi-g++ > /dev/null || { echo "arm-none-eabi-g++ not found (tools/setup)"; exit 1; }
rm -rf "$out" && mkdir -p "$out"
sdins=$(realpath "$sdins"); sdins_target=$(realpath "$sdins_target")

# 1. The image (fsw/ for the Cortex-M7 with the mps2-an500 board port).
(cd "$src" && cmake --preset arm-cortex-m7 > "$out/arm_configure.log" &&
 cmake --build --preset arm-cortex-m7 --target sdins_fsw_mps2 > "$out/arm_build.log") ||
  { tail -n 30 "$out/arm_build.log" 2>/dev/null; echo "the arm-cortex-m7 build failed"; exit 1; }
elf="$src/build/arm-cortex-m7/fsw/baremetal/sdins_fsw_mps2.elf"
[ -s "$elf" ] || { echo "no image: $elf"; exit 1; }

# 2. The recorded input: a simulated flight through HIL's CAN path, its LCM log, HIL's replay digests.
"$sdins" sil --duration "$duration" --seed 4 --log "$out/sil.lcmlog" --lcm-url none --json "$out/sil.json" > "$out/sil.txt"
for m in 24 15; do "$sdins" replay "$out/sil.lcmlog" --model $m --json "$out/replay$m.json" > /dev/null; done
# The flight configuration HIL flies: the shipped config/default.toml of sdins' data directory.
SDINS_DATA_DIR="$(dirname "$sdins")/../share/sdins" "$sdins_target" record "$out/sil.lcmlog" "$out/input.bin"

# 3. The host replay and the image under QEMU (1 instruction = 1 ns of virtual time; SysTick at the
#    board's 25 MHz processor clock counts every 40 instructions).
"$sdins_target" replay "$out/input.bin" "$out/host.txt"
# Bad input gets a clear error: a cut header (2, kBadHeader), an input cut inside an event's
# payload or its head (5, kTruncated), a wrong payload size (4, kBadEvent).
size=$(stat -c %s "$out/input.bin")
head -c 100 "$out/input.bin" > "$out/bad_header.bin"
head -c $((size - 10)) "$out/input.bin" > "$out/bad_truncated.bin"
head -c $((size - 64 - 4)) "$out/input.bin" > "$out/bad_head.bin"
"$(command -v python3)" - "$out/input.bin" "$out/bad_event.bin" <<'PY'
import struct, sys
b = bytearray(open(sys.argv[1], "rb").read())
n_fp = struct.unpack_from("<I", b, 8)[0]
cfg = struct.unpack_from("<I", b, 12)[0]
first_event = 12 + 4 * n_fp + cfg
struct.pack_into("<I", b, first_event + 4, struct.unpack_from("<I", b, first_event + 4)[0] + 8)
open(sys.argv[2], "wb").write(bytes(b))
PY
for bad in header:2 truncated:5 head:5 event:4; do
  f=${bad%%:*}; want=${bad##*:}
  if "$sdins_target" replay "$out/bad_$f.bin" "$out/bad_$f.txt" 2> "$out/bad_$f.err"; then
    echo "sdins_target replay accepted bad_$f.bin"; exit 1
  fi
  grep -q "replay result $want" "$out/bad_$f.err" || { cat "$out/bad_$f.err"; echo "bad_$f.bin: expected result $want"; exit 1; }
done
qemu_args=(-M mps2-an500 -cpu cortex-m7 -nographic -monitor none -serial none -icount shift=0
           -semihosting-config "enable=on,target=native,arg=sdins_fsw_mps2,arg=input.bin,arg=image.txt,arg=dwt"
           -kernel "$elf")
start=$(date +%s%N)
rc=0
(cd "$out" && timeout "${SDINS_QEMU_TIMEOUT:-240}" "$qemu" "${qemu_args[@]}" > qemu_console.txt 2>&1) || rc=$?
end=$(date +%s%N)
cat "$out/qemu_console.txt"
[ $rc -eq 0 ] || { echo "QEMU failed (exit $rc; 124: the time limit)"; exit 1; }
# The libm probe on both builds (the reason the outputs may differ in the last bits).
"$sdins_target" libm "$out/libm_host.txt"
(cd "$out" && timeout 60 "$qemu" "${qemu_args[@]/arg=image.txt,arg=dwt/arg=libm_image.txt,arg=libm}" \
   > qemu_libm_console.txt 2>&1) || { cat "$out/qemu_libm_console.txt"; echo "QEMU libm probe failed"; exit 1; }

# 4. Compare and report.
compare() {  # compare DIR JSON
  "$(command -v python3)" "$src/tests/e2e/target_compare.py" --out "$1" --elf "$elf" \
    --qemu-version "$("$qemu" --version | head -n 1)" --qemu-args "${qemu_args[*]}" \
    --qemu-wall-s "$(( (end - start) / 1000000 ))e-3" --arm-compile-commands "$src/build/arm-cortex-m7/compile_commands.json" \
    --host-compile-commands "$(dirname "$(dirname "$(dirname "$sdins_target")")")/compile_commands.json" --json "$2"
}
rc=0
compare "$out" "${SDINS_TARGET_JSON:-$out/target.json}" || rc=$?

# 5. The comparison must be able to fail: the image's output with one height 1e-5 m off.
neg="$out/negative" && mkdir -p "$neg"
for f in host.txt replay24.json replay15.json input.bin libm_host.txt libm_image.txt; do ln -sf "../$f" "$neg/$f"; done
"$(command -v python3)" - "$out/image.txt" "$neg/image.txt" <<'PY'
import struct, sys
lines = open(sys.argv[1]).read().split("\n")
frames = [i for i, l in enumerate(lines) if l.startswith("F24 ")]
k = frames[len(frames) // 2]
w = lines[k].split()
h = struct.unpack("<d", struct.pack("<Q", int(w[4], 16)))[0] + 1e-5
w[4] = "%016x" % struct.unpack("<Q", struct.pack("<d", h))[0]
lines[k] = " ".join(w)
open(sys.argv[2], "w").write("\n".join(lines))
PY
if compare "$neg" "$neg/target.json" > "$neg/compare.txt" 2>&1 || ! grep -q "beyond the tolerance: \['h_m'\]" "$neg/compare.txt"; then
  cat "$neg/compare.txt"; echo "the comparison did not catch a 1e-5 m height difference in one frame"; exit 1
fi
echo "negative check: a 1e-5 m height difference in one frame fails the comparison"
exit $rc
