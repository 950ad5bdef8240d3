#!/usr/bin/env bash
# The whole office sequence on the firmware under QEMU (issue 25): all six goals in turn,
# with the paper's set and with the tuned one, on the SysTick clock at 168 MHz (QEMU's
# -icount model: 8 ns an instruction). About 4 minutes of QEMU per set. Writes
# docs/firmware-sequence.txt (the README quotes it); `.ci/run` runs it with FIRMWARE_SEQUENCE=1.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo run --release -p host-sim -- export --scenarios ../shared/maps/scenarios.toml \
  --scenario office --out target/flash >/dev/null
export BIAMRRT_FLASH_DIR="$PWD/target/flash" BIAMRRT_GOALS=all
args=(--profile firmware --example firmware --target thumbv7em-none-eabihf --features firmware-example)
out=target/firmware-sequence.txt
: >"$out"
for set in paper tuned; do
  if [ "$set" = tuned ]; then export BIAMRRT_TUNED=1; else unset BIAMRRT_TUNED; fi
  echo "== $set set" | tee -a "$out"
  # The twin line is CI's business; keep the office sequence's lines.
  if ! fw=$(timeout 1800 cargo run "${args[@]}" 2>/dev/null); then
    echo "$fw"
    echo "the $set firmware failed (a goal not reached, a collision, or a panic)"
    exit 1
  fi
  echo "$fw" | tail -n +2 | tee -a "$out"
done
if [ "${1:-}" = --check ]; then
  diff -u docs/firmware-sequence.txt "$out"
else
  cp "$out" docs/firmware-sequence.txt
fi
