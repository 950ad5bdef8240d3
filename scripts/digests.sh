#!/usr/bin/env bash
# Digests of what a user sees, so a change that should alter nothing (a refactor: issue 43)
# can show it: run before and after, compare the lines. Each line is a SHA-256 of a run's
# rows with the wall-clock columns left out (everything else is seeded and on the virtual
# clock, so it repeats bit for bit on any machine).
#
#   scripts/digests.sh [OUT]            # OUT defaults to target/digests (about 20 min on 2 cores)
#   scripts/digests.sh OUT --quick      # the twin, bench and door rows only (about 3 min)
#
# - twin: the host twin line (`cargo run --release --example twin`), which the firmware,
#   the M0+ and the RISC-V twins must print too (CI checks that);
# - firmware-office: docs/results/firmware/office.txt, which CI regenerates under QEMU and diffs;
# - experiment: all 20 planners on bug_trap, maze and office, one seed, virtual clock
#   (runs.csv without run_wall_s);
# - bench: every leg of the shared scenarios, two seeds, virtual clock (bench.csv);
# - moving-door: the door scene, two seeds (runs.csv).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-target/digests}
quick=${2:-}
mkdir -p "$out"
cargo build --release -p host-sim --quiet
sim=target/release/host-sim
scen=../shared/maps/scenarios.toml
if [ ! -f "$scen" ]; then
  echo "digests: $scen is absent (the shared maps sit beside the clone)" >&2
  exit 1
fi
digest() { sha256sum | cut -c1-16; }

echo "twin $(cargo run --release --quiet --example twin | digest)"
echo "firmware-office $(digest <docs/results/firmware/office.txt)"
"$sim" bench --planners paper --scenarios "$scen" --clock virtual --seeds 2 --no-grid --out "$out/bench" >/dev/null
echo "bench $(digest <"$out/bench/bench.csv")"
"$sim" moving --kinds door --seeds 2 --out "$out/moving" >/dev/null
echo "moving-door $(digest <"$out/moving/runs.csv")"
if [ "$quick" != --quick ]; then
  "$sim" experiment --planners all --scenarios "$scen" --maps bug_trap,maze,office --repeats 1 \
    --clock virtual --out "$out/experiment" >/dev/null
  # run_wall_s is the last column: the wall time a run took.
  echo "experiment $(sed 's/,[^,]*$//' "$out/experiment/runs.csv" | digest)"
fi
