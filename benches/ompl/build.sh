#!/usr/bin/env bash
# Builds the OMPL harness into target/ompl/rrt_connect (needs libompl-dev, OMPL 1.5.2 on Debian).
set -euo pipefail
cd "$(dirname "$0")/../.."
mkdir -p target/ompl
g++ -O2 -std=c++17 -I/usr/include/ompl-1.5 -I/usr/include/eigen3 \
  benches/ompl/rrt_connect.cpp -o target/ompl/rrt_connect -lompl
echo "target/ompl/rrt_connect"
