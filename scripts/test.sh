#!/usr/bin/env bash
# Does all set-up (packages, build with warnings as errors: the same build as demo.sh, so after
# it nothing is recompiled) and runs the whole test suite, which also installs the build into a
# temporary prefix and builds and runs examples/ against it (scripts/check_install.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cd build
ctest --output-on-failure -j "$(nproc 2>/dev/null || echo 2)" --timeout 900
