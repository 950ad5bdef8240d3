#!/usr/bin/env bash
# Regenerates every page of docs/ that a command makes, from the data committed beside it.
#
#   scripts/docs.sh [--check] [--firmware]
#
# Always: the configuration and command-line references (`host-sim params`, `host-sim
# cli-reference`) and each results page
# (`docs/results/STUDY/README.md` and its charts, by `host-sim report` or `compare` from
# `data/` and the hand-written `notes.md`; `docs/results/baselines/*/README.md` from each
# bench's `data/`). These take seconds; with --check the pages are
# made in a temporary folder and compared instead of written (the tests
# `docs_configuration_is_the_parameter_table` and `docs_results_is_the_report_of_its_data`
# check the same in `cargo test`).
#
# --firmware also flies the firmware under QEMU and rewrites what it measured (about 30-60
# minutes): docs/results/firmware/depot.txt (firmware/depot.sh), the office sequences of every target
# (firmware/sequence.sh and its --hw-sqrt, --m0, --riscv and --robot-radius 0.3 forms) and
# the firmware guide's table (firmware/table.py --write). docs/results/firmware/office.txt and the
# board's size table in docs/guides/board.md are the CI run's (`.ci/run` prints what to copy when
# they differ).
#
# Not regenerated here: docs/results/body/README.md (scripts/body-figures.sh) and
# docs/results/clearance/README.md (scripts/clearance-figures.py), runs of minutes each with their
# own scripts, and the lab notebook, which records measurements as they were made.
set -euo pipefail
cd "$(dirname "$0")/.."
check=0
firmware=0
for a in "$@"; do
  case "$a" in
    --check) check=1 ;;
    --firmware) firmware=1 ;;
    *) echo "usage: scripts/docs.sh [--check] [--firmware]" >&2; exit 2 ;;
  esac
done
cargo build --release -p host-sim -q
sim=target/release/host-sim
out=docs
if [ "$check" = 1 ]; then
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
  mkdir -p "$out/results"
  for s in docs/results/*/; do
    s=$(basename "$s")
    mkdir -p "$out/results/$s"
  done
fi

mkdir -p "$out/reference"
"$sim" params >"$out/reference/configuration.md"
"$sim" cli-reference >"$out/reference/cli.md"

for s in full-speed pace sigma fig7 fig7-full fig7-reference fig10 fig10-hold; do
  d=docs/results/$s
  "$sim" report --results "$d/data" --out "$out/results/$s/README.md" --notes "$d/notes.md" \
    >/dev/null
  if [ "$check" = 1 ]; then
    # The page names the folders it was made from.
    sed -i "s|$out/results/$s|$d|g" "$out/results/$s/README.md"
  fi
done
# The benches against the baselines: each folder's page from its bench.json and bench.csv.
for d in docs/results/baselines/*/; do
  d=${d%/}
  mkdir -p "$out/results/baselines/$(basename "$d")"
  "$sim" report --results "$d/data" --out "$out/results/baselines/$(basename "$d")/README.md" \
    --notes "$d/notes.md" >/dev/null
  if [ "$check" = 1 ]; then
    sed -i "s|$out/results/baselines|docs/results/baselines|g" \
      "$out/results/baselines/$(basename "$d")/README.md"
  fi
done
p=docs/results/printed
variants=""
for v in alg4-take alg6-take alg6-cost alg6-clear alg4-free alg5-gate alg6-clear-outside all; do
  variants="$variants $v=$p/data/$v"
done
# shellcheck disable=SC2086
"$sim" compare --base "$p/data/none" $variants "meet-all-pairs=$p/data/meet" \
  --out "$out/results/printed/README.md" --notes "$p/notes.md" >/dev/null
# The reference's wait rule at the paper's pace, against the pace folder.
"$sim" compare --base docs/results/pace/data wait-from-set=docs/results/pace/wait-from-set \
  --out "$out/results/pace/wait-from-set.md" --notes docs/results/pace/wait-from-set-notes.md >/dev/null
if [ "$check" = 1 ]; then
  sed -i "s|$out/results/printed|$p|g" "$out/results/printed/README.md"
  sed -i "s|$out/results/pace|docs/results/pace|g" "$out/results/pace/wait-from-set.md"
  stale=0
  for f in reference/configuration.md reference/cli.md results/{full-speed,pace,sigma,fig7,fig7-full,fig7-reference,fig10,fig10-hold,printed}/README.md \
    results/pace/wait-from-set.md $(cd docs && ls results/baselines/*/README.md); do
    if ! diff -q "docs/$f" "$out/$f" >/dev/null; then
      echo "docs/$f is stale: run scripts/docs.sh"
      stale=1
    fi
  done
  [ "$stale" = 0 ] && echo "the generated pages of docs/ are current"
  exit "$stale"
fi
echo "regenerated docs/reference/configuration.md, docs/reference/cli.md and docs/results/*/README.md"

if [ "$firmware" = 1 ]; then
  firmware/depot.sh
  for a in "" --hw-sqrt --m0 --riscv "--robot-radius 0.3"; do
    # shellcheck disable=SC2086
    firmware/sequence.sh $a
  done
  python3 firmware/table.py --write
fi
