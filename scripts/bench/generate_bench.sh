#!/usr/bin/env bash
# Speed and memory of `tessera generate` at large sizes: for each kind, the generator's own
# time (`generate_s`), the g2o writing time (`write_s`), the whole process (wall, CPU) and
# its peak memory. The graph is written to a temporary folder and deleted.
# Usage: scripts/bench/generate_bench.sh [POSES=1000000] [ROBOTS=10] [TESSERA=build/bin/tessera]
set -euo pipefail
cd "$(dirname "$0")/../.."
POSES="${1:-1000000}"
ROBOTS="${2:-10}"
TESSERA="${3:-build/bin/tessera}"
[ -x "$TESSERA" ] || { echo "no $TESSERA (build first)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "needs /usr/bin/time (Debian package: time)" >&2; exit 2; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
printf "%-7s %8s %8s %9s %11s %8s %8s %8s %8s\n" kind poses edges g2o_MB generate_s write_s \
  wall_s cpu_s rss_MB
for kind in grid3d sphere torus city; do
  /usr/bin/time -o "$TMP/time" -f "%e %U %S %M" "$TESSERA" generate --kind "$kind" \
    --poses "$POSES" --robots "$ROBOTS" --seed 1 --out "$TMP/g.g2o" --json "$TMP/g.json" >/dev/null
  read -r wall user sys rss < "$TMP/time"
  field() { sed -n "s/.*\"$1\": \([0-9.e+-]*\).*/\1/p" "$TMP/g.json"; }
  printf "%-7s %8d %8d %9.0f %11.2f %8.2f %8.2f %8.2f %8.0f\n" "$kind" "$(field poses)" \
    "$(field edges)" "$(python3 -c "print($(stat -c %s "$TMP/g.g2o")/1e6)")" "$(field generate_s)" \
    "$(field write_s)" "$wall" "$(python3 -c "print($user+$sys)")" \
    "$(python3 -c "print($rss/1024)")"
  rm -f "$TMP/g.g2o"
done
echo "(load average now: $(cut -d' ' -f1-3 /proc/loadavg); the machine's 2 cores are shared)"
