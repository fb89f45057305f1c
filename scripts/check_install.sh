#!/usr/bin/env bash
# Installs a build tree into a temporary prefix, builds examples/ against it as a project of its
# own (find_package(Tessera)) and runs the examples on a small generated graph: the centralized
# and the in-process distributed solve, one agent of a DDS run hosted by host_agent (the
# coordinator and the other agent are the installed executables), and a whole DDS run launched
# by launch_run from the prefix's executables.
#   scripts/check_install.sh [BUILD_DIR]      (default: build; DDS domains $TESSERA_EXAMPLE_DOMAIN,
#   14, and $TESSERA_EXAMPLE_LAUNCH_DOMAIN, 39)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${1:-$root/build}" && pwd)
tmp=$(mktemp -d /tmp/tessera-install-XXXXXX)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix

cmake --install "$build" --prefix "$prefix" > "$tmp/install.log"
test -f "$prefix/lib/cmake/Tessera/TesseraConfig.cmake"
test -f "$prefix/lib/cmake/Tessera/TesseraConfigVersion.cmake"
# Only public headers are installed.
if find "$prefix/include" -name '*.hpp' | grep -v "^$prefix/include/tessera/" | grep -q .; then
  echo "check_install: headers outside include/tessera/ were installed" >&2
  exit 1
fi
launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S "$root/examples" -B "$tmp/ex" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release \
  "${launcher[@]}" > "$tmp/configure.log"
cmake --build "$tmp/ex" -j2 > "$tmp/build.log"

"$prefix/bin/tessera" generate --kind grid3d --poses 200 --robots 2 --seed 3 --out "$tmp/g.g2o" \
  > /dev/null
"$tmp/ex/solve_centralized" "$tmp/g.g2o"
"$tmp/ex/solve_distributed" "$tmp/g.g2o" 3

if [ -x "$tmp/ex/host_agent" ]; then
  domain=${TESSERA_EXAMPLE_DOMAIN:-14}
  run=examples-$$
  "$prefix/bin/tessera-coordinator" --agents 2 --run-id "$run" --domain "$domain" \
    --graph "$tmp/g.g2o" --summary "$tmp/summary.json" > "$tmp/coordinator.log" 2>&1 &
  coordinator=$!
  "$prefix/bin/tessera-agent" --graph "$tmp/g.g2o" --robots 2 --id 1 --run-id "$run" \
    --domain "$domain" > "$tmp/agent1.log" 2>&1 &
  agent=$!
  status=0
  timeout 180 "$tmp/ex/host_agent" "$tmp/g.g2o" 2 0 "$run" "$domain" || status=$?
  wait "$coordinator" || status=$?
  wait "$agent" || status=$?
  if [ "$status" -ne 0 ] || ! grep -q '"rounds"' "$tmp/summary.json"; then
    echo "check_install: the run with the hosted agent failed" >&2
    tail -5 "$tmp/coordinator.log" "$tmp/agent1.log" >&2
    exit 1
  fi
  echo "hosted agent: run $run finished, summary has its rounds"
fi
if [ -x "$tmp/ex/launch_run" ]; then
  # launch() finds the executables of a package installed into a prefix other than the
  # configured one (Tessera_BINDIR).
  if ! timeout 300 "$tmp/ex/launch_run" "$tmp/g.g2o" 2 "${TESSERA_EXAMPLE_LAUNCH_DOMAIN:-39}" \
    > "$tmp/launch.log" 2>&1 || ! grep -q "done, exit code 0" "$tmp/launch.log"; then
    echo "check_install: the launched run failed" >&2
    tail -5 "$tmp/launch.log" >&2
    exit 1
  fi
  echo "launched run: done"
fi
echo "check_install: OK (prefix, find_package(Tessera), examples)"
