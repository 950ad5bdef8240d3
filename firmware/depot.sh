#!/usr/bin/env bash
# A fine nav2 map on the firmware under QEMU (issue 42): depot (604 x 307 cells at 0.05 m)
# exported to flash, all three goals in turn on the SysTick clock at 168 MHz (QEMU's -icount
# model: 8 ns an instruction, so the figures are deterministic), with the paper's set and
# with the tuned one. About 40 s of QEMU per set.
#
#   firmware/depot.sh [--check]
#
# Fails when a goal is missed, a collision or a panic happens, a call overruns t_exp by more
# than 1 ms, or the firmware leaves the flash (256 KiB) or RAM (96 KiB) budget. Writes
# docs/results/firmware/depot.txt (docs/guides/firmware.md quotes it after `<!-- docs/results/firmware/depot.txt -->`);
# --check compares instead of writing (`.ci/run` does).
set -euo pipefail
cd "$(dirname "$0")/.."
source firmware/paths.sh
check=0
if [ "${1:-}" = --check ]; then check=1; fi
LLVM_SIZE=$(find "$(rustc --print sysroot)" -name llvm-size -type f | head -n 1)
export BIAMRRT_FLASH_DIR="$PWD/target/flash-depot"
args=(--profile firmware --example firmware --target thumbv7em-none-eabihf --features firmware-example)
elf=target/thumbv7em-none-eabihf/firmware/examples/firmware
doc=docs/results/firmware/depot.txt
out=target/firmware-depot.txt
: >"$out"
for set in paper tuned; do
  # The mission (the set, every goal) is the export's, beside the scenario it flies.
  cargo run --release -p host-sim -- export --scenarios ../shared/maps/real/scenarios.toml \
    --maps depot --planners "$set" --all-goals --out target/flash-depot >/dev/null
  if ! fw=$(timeout 900 cargo run "${args[@]}" 2>/dev/null); then
    echo "$fw"
    echo "the depot firmware ($set set) failed (a goal not reached, a collision, or a panic)"
    exit 1
  fi
  # The first line is the twin's (checked against the host's by .ci/run's office step).
  fw=$(echo "$fw" | tail -n +2)
  overrun=$(echo "$fw" | sed -n 's/^per-call time: .*overrun \([0-9]*\) us).*$/\1/p')
  stack=$(echo "$fw" | sed -n 's/^stack high-water: \([0-9]*\) bytes$/\1/p')
  read -r flash ram < <("$LLVM_SIZE" -A "$elf" | awk -v stack="$stack" '
    $1 == ".vector_table" || $1 == ".text" || $1 == ".rodata" { flash += $2 }
    $1 == ".data" { flash += $2; ram += $2 }
    $1 == ".bss" || $1 == ".uninit" { ram += $2 }
    END { print flash, ram + stack }')
  {
    echo "== $set set"
    echo "$fw"
    echo "flash $flash bytes, RAM $ram bytes with the stack (limits 262144 and 98304)"
  } | tee -a "$out"
  if [ -z "$overrun" ] || [ "$overrun" -gt 1000 ]; then
    echo "the $set set's worst call overran t_exp by more than 1 ms (${overrun:-no figure} us)"
    exit 1
  fi
  if [ -z "$stack" ] || [ "$flash" -gt 262144 ] || [ "$ram" -gt 98304 ]; then
    echo "the $set set's firmware leaves the flash or RAM budget"
    exit 1
  fi
done
if [ "$check" = 1 ]; then
  if ! diff -u "$doc" "$out"; then
    echo "the depot firmware's figures changed: run firmware/depot.sh and copy $doc into the block of docs/guides/firmware.md after <!-- docs/results/firmware/depot.txt -->"
    exit 1
  fi
  awk '/^<!-- docs\/results\/firmware\/depot.txt -->$/ { on = 1; next }
    on && /^```text$/ { next }
    on && /^```$/ { exit }
    on { print }' docs/guides/firmware.md | diff -u "$doc" -
else
  cp "$out" "$doc"
fi
