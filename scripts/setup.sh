#!/usr/bin/env bash
# Installs every Debian package Tessera needs (skipped when already present), then
# configures and builds into build/. Idempotent; a second run only rebuilds what changed.
#   scripts/setup.sh                      Release build, warnings as errors
#   TESSERA_WERROR=OFF scripts/setup.sh   warnings allowed
# demo.sh and test.sh both build through here with the same settings, so the second of them
# reuses the first one's build. ccache is used when it is installed.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libsuitesparse-dev libspectra-dev
  libopenblas0-serial  # optimised single-threaded BLAS behind CHOLMOD's supernodal factorizations
  libgtest-dev
  libfastrtps-dev libfastcdr-dev fastddsgen fastdds-tools default-jre-headless
  python3 python3-matplotlib
  iproute2 nftables openssl
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

JOBS=$(nproc 2>/dev/null || echo 2)
launcher=()
# The tests' precompiled header (tests/CMakeLists.txt) is cacheable only with this sloppiness.
command -v ccache >/dev/null &&
  launcher=("-DCMAKE_CXX_COMPILER_LAUNCHER=env;CCACHE_SLOPPINESS=pch_defines,time_macros;ccache")
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DTESSERA_WERROR="${TESSERA_WERROR:-ON}" \
  "${launcher[@]}" >/dev/null
cmake --build build -j "$JOBS"
