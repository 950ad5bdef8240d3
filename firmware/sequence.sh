#!/usr/bin/env bash
# The whole office sequence on the firmware under QEMU (issue 25): all six goals in turn,
# with the paper's set and with the tuned one, on the SysTick clock at 168 MHz (QEMU's
# -icount model: 8 ns an instruction). About 1-4 minutes of QEMU per set.
#
#   firmware/sequence.sh [--check] [--hw-sqrt | --m0 | --riscv] [--robot-radius R]
#
# Writes docs/results/firmware/sequence.txt (docs/guides/firmware.md's table quotes it); with --hw-sqrt (nightly Rust, the
# FPU's square root: feature `hw-sqrt`) docs/results/firmware/sequence-hw-sqrt.txt; with --m0 the
# Cortex-M0+ build (firmware/m0-twin's `office`: soft float, SysTick at 25 MHz on QEMU's
# mps2-an385, the same 8 ns an instruction) docs/results/firmware/sequence-m0.txt; with --riscv the
# RISC-V build (firmware/riscv-twin's `office`: riscv32imac, soft float, the `time` counter at
# 10 MHz on QEMU's virt board) docs/results/firmware/sequence-riscv.txt. --check compares instead of
# writing. `.ci/run` runs all four with FIRMWARE_SEQUENCE=1. With --robot-radius R (metres) the
# office is exported for a robot of that radius (issue 41: its inflated grid in flash beside
# the map) and the figures go to docs/results/firmware/sequence-body-R.txt (the M4F build).
set -euo pipefail
cd "$(dirname "$0")/.."
source firmware/paths.sh
check=0
hw=0
m0=0
rv=0
radius=
while [ $# -gt 0 ]; do
  case "$1" in
    --check) check=1 ;;
    --hw-sqrt) hw=1 ;;
    --m0) m0=1 ;;
    --riscv) rv=1 ;;
    --robot-radius) radius=$2; shift ;;
    *) echo "unknown argument $1" >&2; exit 2 ;;
  esac
  shift
done
export BIAMRRT_FLASH_DIR="$PWD/target/flash"
args=(--profile firmware --example firmware --target thumbv7em-none-eabihf)
cargo=(cargo)
doc=docs/results/firmware/sequence.txt
dir=.
if [ "$hw" = 1 ]; then
  cargo=(cargo +nightly)
  args+=(--features firmware-example,hw-sqrt)
  doc=docs/results/firmware/sequence-hw-sqrt.txt
elif [ "$m0" = 1 ]; then
  dir=firmware/m0-twin
  args=(--release --bin office)
  doc=docs/results/firmware/sequence-m0.txt
elif [ "$rv" = 1 ]; then
  dir=firmware/riscv-twin
  args=(--release --bin office)
  doc=docs/results/firmware/sequence-riscv.txt
else
  args+=(--features firmware-example)
fi
if [ -n "$radius" ]; then
  doc=${doc%.txt}-body-$radius.txt
fi
out=target/$(basename "$doc")
: >"$out"
for set in paper tuned; do
  # The mission (the set, every goal) is the export's, beside the scenario it flies.
  cargo run --release -p host-sim -- export --scenarios ../shared/maps/scenarios.toml \
    --maps office --planners "$set" --all-goals --out target/flash \
    ${radius:+--robot-radius "$radius"} >/dev/null
  echo "== $set set" | tee -a "$out"
  if ! fw=$(cd "$dir" && timeout 1800 "${cargo[@]}" run "${args[@]}" 2>/dev/null); then
    echo "$fw"
    echo "the $set firmware failed (a goal not reached, a collision, or a panic)"
    exit 1
  fi
  # The M4F firmware's first line is the twin's (CI's business): keep the office lines.
  if [ "$m0" = 1 ] || [ "$rv" = 1 ]; then echo "$fw"; else echo "$fw" | tail -n +2; fi | tee -a "$out"
done
if [ "$check" = 1 ]; then
  diff -u "$doc" "$out"
else
  cp "$out" "$doc"
fi
