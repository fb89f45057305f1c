#!/usr/bin/env bash
# Measures the DDS transport on this host (figures for docs/dds-runtime.md):
#  1. discovery: tessera-dds-ping pairs (participant creation -> readiness barrier passed)
#     and full coordinator + N agent runs (coordinator start -> all announcements);
#  2. pose-block round trips of 1000 poses (and other sizes) between two processes;
#  3. Fast DDS files in /dev/shm after everything has shut down.
# usage: scripts/bench/dds_transport.sh [BUILD_DIR]   (default build; needs tessera-dds-ping,
#        tessera-agent, tessera-coordinator built)
set -euo pipefail
BUILD=${1:-build}
BIN=$BUILD/bin
DOMAIN=210
for exe in tessera-dds-ping tessera-agent tessera-coordinator; do
  [[ -x $BIN/$exe ]] || { echo "missing $BIN/$exe (build it first)" >&2; exit 2; }
done
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
shm_before=$(ls /dev/shm | grep -c fastrtps || true)

echo "== pose-block round trips (two processes, one host) =="
for spec in "1000 4 3" "1000 5 3" "1000 3 2" "100 5 3" "10000 5 3"; do
  set -- $spec
  "$BIN/tessera-dds-ping" --role echo --domain $DOMAIN --run-id bench --poses "$1" --rank "$2" --dim "$3" \
    --count 200 > /dev/null &
  echo_pid=$!
  "$BIN/tessera-dds-ping" --role ping --domain $DOMAIN --run-id bench --poses "$1" --rank "$2" --dim "$3" --count 200
  wait $echo_pid
done

echo "== discovery: participant pairs (10 starts) =="
for k in $(seq 1 10); do
  "$BIN/tessera-dds-ping" --role echo --domain $DOMAIN --run-id disc$k --poses 1 --count 1 > /dev/null &
  echo_pid=$!
  "$BIN/tessera-dds-ping" --role ping --domain $DOMAIN --run-id disc$k --poses 1 --count 1 | sed 's/ poses=.*//'
  wait $echo_pid
done

echo "== discovery: coordinator + agents (coordinator start -> all N announced) =="
python3 - "$tmp/g.g2o" <<'PY'
import math, sys
n = 300
lines = [f"VERTEX_SE2 {k} {k} 0 0" for k in range(n)]
lines += [f"EDGE_SE2 {k} {k+1} 1 0 0 100 0 0 100 0 400" for k in range(n - 1)]
lines += [f"EDGE_SE2 {k} {(k * 7 + 3) % n} 0 0 0 100 0 0 100 0 400" for k in range(0, n, 5) if (k * 7 + 3) % n != k]
open(sys.argv[1], "w").write("\n".join(lines) + "\n")
PY
for N in 3 5 10; do
  for k in 1 2 3; do
    run="bench-n$N-$k"
    "$BIN/tessera-coordinator" --agents $N --run-id $run --domain $DOMAIN --summary "$tmp/s.json" 2> /dev/null &
    c=$!
    for ((i = 0; i < N; i++)); do
      "$BIN/tessera-agent" --graph "$tmp/g.g2o" --robots $N --id $i --run-id $run --domain $DOMAIN 2> /dev/null &
    done
    wait
    python3 -c "import json,sys; s=json.load(open('$tmp/s.json')); print(f\"N={s['agents']} discovery_ms={s['discovery_ms']:.0f} total_ms={s['total_ms']:.0f}\")"
  done
done

shm_after=$(ls /dev/shm | grep -c fastrtps || true)
echo "== /dev/shm: Fast DDS files before $shm_before, after $shm_after =="
