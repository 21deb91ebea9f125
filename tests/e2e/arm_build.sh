#!/usr/bin/env bash
# Bare-metal build gate (docs/baremetal.md): configures and builds the arm-cortex-m7 preset
# (fsw/ only, gcc-arm-none-eabi, newlib-nano) and checks the image: Cortex-M7 hard-float
# attributes, the flight application (and its executive) of both paper layouts linked, the vector table at the start of flash,
# no heap allocator; prints flash and RAM from arm-none-eabi-size.
set -euo pipefail
src=${1:?usage: arm_build.sh SOURCE_DIR}
build="$src/build/arm-cortex-m7"
cd "$src"
cmake --preset arm-cortex-m7 > /dev/null
cmake --build --preset arm-cortex-m7 | tail -n 8
elf="$build/fsw/baremetal/sdins_fsw_m7.elf"
[ -s "$elf" ] || { echo "no image: $elf"; exit 1; }

attrs=$(arm-none-eabi-readelf -A "$elf")
for want in "Tag_CPU_arch: v7E-M" "Tag_FP_arch: FPv5/FP-D16" "Tag_ABI_VFP_args: VFP registers"; do
  grep -q "$want" <<< "$attrs" || { echo "missing ELF attribute '$want':"; echo "$attrs"; exit 1; }
done

syms=$(arm-none-eabi-nm -C "$elf")
need=("T main" "T Reset_Handler"
      "fsw::Executive<fsw::ErrorStateLayout<(fsw::Block)0, (fsw::Block)1, (fsw::Block)2, (fsw::Block)3, (fsw::Block)4, (fsw::Block)9> >::tick("
      "fsw::Executive<fsw::ErrorStateLayout<(fsw::Block)0, (fsw::Block)1, (fsw::Block)2, (fsw::Block)3, (fsw::Block)4, (fsw::Block)5, (fsw::Block)6, (fsw::Block)9> >::tick("
      "::propagate(fsw::EkfTransition<" "::run_ekf_group()" "::update(fsw::GnssEpoch const&" "::take_correction(" "fsw::Strapdown::step("
      # The one dispatch (FlightApp::on_event); the compiler may inline on_gnss and on_almanac into
      # it, so their work is checked by what they call (gnss_epoch_from_raw, GpsAlmanacTable::set).
      "::on_event(fsw::InputEvent const&" "::on_imu(fsw::ImuSample const&" "fsw::GpsAlmanacTable::set("
      "fsw::gnss_epoch_from_raw(" "fsw::gnss_pvt(")
for s in "${need[@]}"; do
  grep -qF -- "$s" <<< "$syms" || { echo "symbol not linked: $s"; exit 1; }
done
if grep -qE " [TtWU] (malloc|_malloc_r|free|_free_r|calloc|realloc|_Znwj|_Znaj)$" <<< "$syms"; then
  echo "a heap allocator is linked into the image:"; grep -E " [TtWU] (malloc|_malloc_r|free|_free_r|calloc|realloc|_Znwj|_Znaj)$" <<< "$syms"
  exit 1
fi

# Vector table: word 0 the initial stack pointer (end of DTCM), word 1 Reset_Handler with the Thumb bit.
read -r sp reset < <(arm-none-eabi-objcopy -O binary -j .isr_vector "$elf" /dev/stdout | od -An -t x4 -N 8)
handler=$(arm-none-eabi-nm "$elf" | awk '$3 == "Reset_Handler" {print $1}')
isr=$(arm-none-eabi-objdump -h "$elf" | awk '$2 == ".isr_vector" {print $4}')
[ "$isr" = "08000000" ] || { echo ".isr_vector at $isr, not at the start of flash"; exit 1; }
[ "$sp" = "20020000" ] || { echo "initial SP $sp, expected 20020000 (end of DTCM)"; exit 1; }
[ $((16#$reset)) -eq $((16#$handler | 1)) ] || { echo "reset vector $reset != Reset_Handler $handler | 1"; exit 1; }

arm-none-eabi-size -A "$elf" | awk '$1 ~ /^\.(isr_vector|text|init_array|data|bss|stack)$/'
arm-none-eabi-size -A "$elf" | awk '
  $1 == ".isr_vector" || $1 == ".text" || $1 == ".init_array" || $1 == ".ARM.exidx" { flash += $2 }
  $1 == ".data" { flash += $2; ram += $2 }
  $1 == ".bss" { ram += $2 }
  $1 == ".stack" { stack = $2 }
  END { printf "sdins_fsw_m7.elf: flash %d B, static RAM %d B (.data + .bss), stack reserved %d B\n", flash, ram, stack }'
arm-none-eabi-size -t "$build/fsw/libsdins_fsw.a" | awk '/\(TOTALS\)/ { printf "libsdins_fsw.a (Cortex-M7): text %d B, static RAM %d B (.data %d + .bss %d)\n", $1, $2 + $3, $2, $3 }'
arm-none-eabi-nm -S -C --radix=d "$elf" | awk '/g_app(24|15)$/ { n = $NF; sub(/^.*::/, "", n); printf "  %s (static): %d B\n", n, $2 + 0 }'
