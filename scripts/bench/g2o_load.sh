#!/usr/bin/env bash
# Load time of the g2o reader on every dataset in ../shared/datasets: the reader's own time
# (`load_s` from `tessera info --json`) and the whole `tessera info` process (start-up, reading,
# printing), best of REPEATS each.
# Usage: scripts/bench/g2o_load.sh [REPEATS=5] [TESSERA=build/bin/tessera]
set -euo pipefail
cd "$(dirname "$0")/../.."
REPEATS="${1:-5}"
TESSERA="${2:-build/bin/tessera}"
DATA="${TESSERA_SHARED_DIR:-../shared}/datasets"
[ -x "$TESSERA" ] || { echo "no $TESSERA (build first)" >&2; exit 2; }
[ -d "$DATA" ] || { echo "no $DATA" >&2; exit 2; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
TIMEFORMAT=%R
printf "%-30s %9s %7s %7s %9s %11s\n" dataset bytes poses edges read_ms process_ms
for f in $(ls -S "$DATA"/*.g2o); do
  : >"$TMP/loads"
  : >"$TMP/procs"
  for _ in $(seq "$REPEATS"); do
    { time "$TESSERA" info "$f" --json "$TMP/info.json" >/dev/null; } 2>>"$TMP/procs"
    sed -n 's/.*"load_s": \([0-9.e+-]*\).*/\1/p' "$TMP/info.json" >>"$TMP/loads"
  done
  # The first match: the per-robot list further down has "poses" too.
  poses=$(sed -n 's/^  "poses": \([0-9]*\).*/\1/p' "$TMP/info.json" | head -1)
  edges=$(sed -n 's/^  "edges": \([0-9]*\).*/\1/p' "$TMP/info.json" | head -1)
  read_ms=$(sort -g "$TMP/loads" | head -1 | awk '{printf "%.1f", $1 * 1000}')
  proc_ms=$(sort -g "$TMP/procs" | head -1 | awk '{printf "%.0f", $1 * 1000}')
  printf "%-30s %9d %7d %7d %9s %11s\n" "$(basename "$f")" "$(stat -c %s "$f")" "$poses" "$edges" \
    "$read_ms" "$proc_ms"
done
