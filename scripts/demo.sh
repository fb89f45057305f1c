#!/usr/bin/env bash
# Does all set-up and runs the main job: generate a multi-robot pose graph, solve it and
# print the summary.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
mkdir -p out
build/bin/tessera generate --kind grid3d --poses 1000 --robots 5 --seed 1 --out out/demo.g2o
build/bin/tessera solve out/demo.g2o --algorithm centralized --json out/demo.json --out out/demo_solution.g2o
