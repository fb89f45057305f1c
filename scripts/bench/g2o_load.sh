#!/usr/bin/env bash
# Load time of the g2o reader on every dataset in ../shared/datasets: the reader's own time
# (`load_s` from `tessera info --json`) and the whole `tessera info` process, best of REPEATS.
# Usage: scripts/bench/g2o_load.sh [REPEATS=5] [TESSERA=build/bin/tessera]
set -euo pipefail
cd "$(dirname "$0")/../.."
REPEATS="${1:-5}"
TESSERA="${2:-build/bin/tessera}"
DATA="${TESSERA_SHARED_DIR:-../shared}/datasets"
[ -x "$TESSERA" ] || { echo "no $TESSERA (build first)" >&2; exit 2; }
[ -d "$DATA" ] || { echo "no $DATA" >&2; exit 2; }
printf "%-30s %9s %7s %7s %11s %13s\n" dataset bytes poses edges "read_ms" "process_ms"
for f in $(ls -S "$DATA"/*.g2o); do
  best_load=""; best_proc=""
  for _ in $(seq "$REPEATS"); do
    t0=$(date +%s%N)
    json=$("$TESSERA" info "$f" --json - | sed -n '/^{/,/^}/p')
    t1=$(date +%s%N)
    load=$(echo "$json" | sed -n 's/.*"load_s": \([0-9.e+-]*\).*/\1/p')
    proc=$(( (t1 - t0) / 1000 ))
    best_load=$(python3 -c "print(min(float('$load'), float('${best_load:-inf}')))")
    [ -z "$best_proc" ] || [ "$proc" -lt "$best_proc" ] && best_proc=$proc
  done
  poses=$(echo "$json" | sed -n 's/.*"poses": \([0-9]*\).*/\1/p')
  edges=$(echo "$json" | sed -n 's/.*"edges": \([0-9]*\).*/\1/p')
  printf "%-30s %9d %7d %7d %11.1f %13.1f\n" "$(basename "$f")" "$(stat -c %s "$f")" "$poses" \
    "$edges" "$(python3 -c "print($best_load*1e3)")" "$(python3 -c "print($best_proc/1e3)")"
done
