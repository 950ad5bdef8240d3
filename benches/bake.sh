#!/usr/bin/env bash
# The diffusion bake's time, memory and table error on the paper's maps, the nav2 maps of
# ../shared/maps/real and a 3000 x 3000 forest of blocks at 0.05 m drawn by benches/maps/forest.py
# (issue 23). Each bake runs RUNS times (default 3); prints user CPU seconds and peak resident
# memory of each run (GNU time) and the bake's own error and Pearson lines.
# Usage: benches/bake.sh [RUNS]   (from the repository root, after a release build)
set -euo pipefail
runs=${1:-3}
bin=target/release/host-sim
shared=../shared/maps
out=$(mktemp -d)
python3 benches/maps/forest.py "$out/forest3000" 3000 0.05 7
maps=("$shared/bug_trap.png" "$shared/maze.png" "$shared/office.png"
      "$shared/real/depot.yaml" "$shared/real/warehouse.yaml" "$out/forest3000.yaml")
for m in "${maps[@]}"; do
  [ -f "$m" ] || { echo "skipped: $m not found"; continue; }
  for i in $(seq "$runs"); do
    /usr/bin/time -f "$(basename "$m") run $i: %U s user CPU, %e s wall, %M KB peak" \
      "$bin" bake --map "$m" --out "$out/table" >"$out/log" 2>"$out/time"
    tail -n 1 "$out/time"
  done
  grep -E "^largest error|Pearson|^table:" "$out/log" | sed 's/^/  /'
done
rm -rf "$out"
