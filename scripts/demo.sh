#!/usr/bin/env bash
# Does all set-up and runs the main job: generate a multi-robot pose graph, solve it as a
# distributed system (a coordinator and 5 agent processes talking over DDS on this host,
# `tessera launch`) and print the summary.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
mkdir -p out
build/bin/tessera generate --kind grid3d --poses 1000 --robots 5 --seed 1 --out out/demo.g2o
build/bin/tessera launch out/demo.g2o --agents 5 --algorithm irbcd \
  --json out/demo.json --out out/demo_solution.g2o
