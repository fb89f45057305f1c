#!/usr/bin/env bash
# Fuzzes the g2o reader with libFuzzer (clang, ASan + UBSan). Standalone: not part of the
# default build or CI. Usage: scripts/fuzz_g2o.sh [SECONDS] [extra libFuzzer flags...]
# Builds into build-fuzz/, writes a small seed corpus to build-fuzz/seeds/, keeps the growing
# corpus in build-fuzz/corpus/ and crash reproducers in build-fuzz/artifacts/.
# Reproduce a finding: build-fuzz/g2o_reader_fuzz build-fuzz/artifacts/crash-...
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_TO_RUN="${1:-240}"
shift || true
CXX_BIN="${CXX:-$(command -v clang++-14 || command -v clang++)}"
OUT=build-fuzz

cmake -S tests/fuzz -B "$OUT" -DCMAKE_CXX_COMPILER="$CXX_BIN" -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$OUT" -j2 >/dev/null
mkdir -p "$OUT/seeds" "$OUT/corpus" "$OUT/artifacts"

# Seeds: small valid 2D and 3D graphs and the quirks of real files, plus a few broken lines.
seed() { printf '%b' "$2" >"$OUT/seeds/$1"; }
I2=' 10 0 0 10 0 5'
I3=' 4 0 0 0 0 0 4 0 0 0 0 4 0 0 0 6 0 0 6 0 6'
seed v2.g2o "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0.1\nVERTEX_SE2 2 2 0 0.2\nEDGE_SE2 0 1 1 0 0.1$I2\nEDGE_SE2 1 2 1 0 0.1$I2\nEDGE_SE2 2 0 -2 0 -0.2$I2\n"
seed novertex2.g2o "EDGE_SE2 0 1 1 0 0$I2\n\nEDGE_SE2 2 1 -1 0 0$I2\n   \nEDGE_SE2 1 2 1 0 0$I2\n"
seed v3.g2o "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 1 1 0 0 0 0 0.0998 0.995\nEDGE_SE3:QUAT 0 1 1 0 0 0 0 0.0998334 0.9950042$I3\nEDGE_SE3:QUAT 1 0 -1 0 0 0 0 -0.0998334 0.9950042$I3\nFIX 0\n"
seed novertex3.g2o "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1.0000001$I3\r\nEDGE_SE3:QUAT 1 2 1 0 0 0 0 0 1$I3\r\n# comment\n"
seed nonpd3.g2o "EDGE_SE3:QUAT 0 1 0 0 0 0 0 0 1 100 0 0 0 0 0 100 0 0 0 0 10 500 0 0 10 0 0 10 0 10\n"
seed toro2.g2o "VERTEX2 0 0 0 0\nVERTEX2 1 1 0 0.1\nEDGE2 0 1 1 0 0.1 10 0 10 5 0 0\nFIX 1\n"
seed toro3.g2o "VERTEX3 7 0 0 0 0 0 0\nVERTEX3 9 1 0 0 0.1 0.2 0.3\nEDGE3 7 9 1 0 0 0.1 0.2 0.3$I3\n"
seed gtsam2.g2o "EDGE_SE2 6989586621679009792 6989586621679009793 1 0 0$I2\nEDGE_SE2 6989586621679009793 7061644215716937728 1 0 0$I2\n"
seed bad.g2o "EDGE_SE2 0 0 1 0 0$I2\nEDGE_SE2 -1 1 nan 0 0$I2\nVERTEX_SE3:QUAT 0 0 0 0 0 0 0 0\nEDGE_SE2 0 1 1e999 0$I2\n"

# A dictionary of the format's words lets the fuzzer build valid records quickly.
cat >"$OUT/g2o.dict" <<'DICT'
"VERTEX_SE2"
"EDGE_SE2"
"VERTEX_SE3:QUAT"
"EDGE_SE3:QUAT"
"FIX"
"VERTEX2"
"EDGE2"
"VERTEX3"
"EDGE3"
"6989586621679009792"
"18446744073709551615"
"#"
"nan"
"inf"
"-1"
"1e999"
"1e-400"
"0.7071067811865476"
" 10 0 0 10 0 5"
" 4 0 0 0 0 0 4 0 0 0 0 4 0 0 0 6 0 0 6 0 6"
"\x0a"
"\x0d\x0a"
DICT

echo "fuzzing the g2o reader for ${SECONDS_TO_RUN}s ($OUT/g2o_reader_fuzz)"
set +e
"$OUT/g2o_reader_fuzz" "$OUT/corpus" "$OUT/seeds" -max_total_time="$SECONDS_TO_RUN" \
  -max_len=4096 -timeout=10 -rss_limit_mb=2048 -artifact_prefix="$OUT/artifacts/" \
  -print_final_stats=1 -dict="$OUT/g2o.dict" "$@" 2>&1 | tee "$OUT/last_run.log" | grep -E "^#[0-9]+[[:space:]]+(INITED|DONE)|ERROR|SUMMARY|stat::|crash-|timeout-|oom-"
rc=${PIPESTATUS[0]}
set -e
echo "libFuzzer exit code: $rc (0 = no crash); artifacts: $(ls "$OUT/artifacts" | wc -l)"
exit "$rc"
