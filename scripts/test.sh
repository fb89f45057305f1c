#!/usr/bin/env bash
# Does all set-up (packages, build with warnings as errors) and runs the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
TESSERA_WERROR=ON scripts/setup.sh
cd build
ctest --output-on-failure -j "$(nproc 2>/dev/null || echo 2)" --timeout 900
