#!/usr/bin/env bash
# libFuzzer runs of the readers (issue 12): the scene parser and --set
# overrides, the OBJ/PLY mesh readers, and EXR images. The tree is built
# with clang and -fsanitize=fuzzer-no-link,address,undefined in build-fuzz;
# each harness starts from a seed corpus of the project's own files.
# Usage: tools/fuzz.sh [RUNS]    executions per harness (default 1000000),
#        or MAX_SECONDS per harness (default 3600), whichever comes first;
#        HARNESSES="scene_json mesh exr" picks some. Findings are written to
#        build-fuzz/findings/ and make the script exit 1.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${BUILD:-$ROOT/build-fuzz}"
RUNS="${1:-1000000}"
JOBS="${JOBS:-$(nproc)}"
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ is needed (apt-get install clang)"; exit 1; }
LAUNCHER=""
command -v ccache >/dev/null && LAUNCHER="-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"
cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ $LAUNCHER \
    -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DVDBMARCH_FUZZ=ON -DVDBMARCH_BUILD_TESTS=OFF -DVDBMARCH_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$BUILD" -j "$JOBS" --target fuzz_scene_json fuzz_mesh fuzz_exr fuzz_vdb

# Seed corpora: the project's scenes, meshes and an image of its own.
C="$BUILD/corpus"
rm -rf "$C"; mkdir -p "$C/scene_json" "$C/mesh" "$C/exr" "$C/vdb" "$BUILD/findings"
cp "$ROOT"/vdb_samples/*.json "$ROOT"/vdb_samples/scenes/*.json "$C/scene_json/"
printf '{"render": {"spp": 2}}\n#set render.max_depth=3' > "$C/scene_json/with_set.json"
{ printf '\0'; cat "$ROOT/vdb_samples/scenes/knot.obj"; } > "$C/mesh/knot.obj"
{ printf '\1'; printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n'; } > "$C/mesh/tri_ascii.ply"
python3 - "$C/mesh/tri_binary.ply" <<'PY'
import struct, sys
h = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
body = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<B3i", 3, 0, 1, 2)
open(sys.argv[1], "wb").write(b"\x01" + h + body)
PY
# VDB: the project's small samples (first byte 0: a volume, 1: a cache).
{ printf '\0'; cat "$ROOT/vdb_samples/sparse.vdb"; } > "$C/vdb/sparse.vdb"
if [ -x "$ROOT/build/bin/vdbmarch" ]; then
  "$ROOT/build/bin/vdbmarch" bake "$ROOT/vdb_samples/sparse.json" -o "$C/cache.vdb" --photons 2000 -q 2>/dev/null || true
  [ -f "$C/cache.vdb" ] && { printf '\1'; cat "$C/cache.vdb"; } > "$C/vdb/cache.vdb" && rm -f "$C/cache.vdb"
  "$ROOT/build/bin/vdbmarch" render "$ROOT/vdb_samples/sparse.json" -o "$C/exr/small.exr" --res 8x6 --spp 1 -q
fi

# One harness: its log, its findings, a line of figures; returns 1 on a finding.
run_harness() {
  local h="$1" rc=0 extra=""
  echo "== fuzz_$h: $RUNS runs"
  mkdir -p "$BUILD/findings/$h"
  # A small ASan quarantine: OpenEXR allocates what a damaged header asks
  # for (1.6 GB for a 1 kB file, then fails to read it, an error), and a
  # quarantine of such blocks would look like running out of memory.
  # OpenVDB's reader crashes on damaged input (the commands isolate it): count
  # those crashes across forked runs instead of stopping at the first.
  [ "$h" = vdb ] && extra="-fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1"
  ASAN_OPTIONS="detect_leaks=1:quarantine_size_mb=16" "$BUILD/bin/fuzz_$h" "$C/$h" -runs="$RUNS" $extra \
      -max_total_time="${MAX_SECONDS:-3600}" -max_len=65536 -timeout=10 -rss_limit_mb=4096 -artifact_prefix="$BUILD/findings/$h/" -print_final_stats=1 \
      > "$BUILD/findings/$h.log" 2>&1 || rc=$?
  grep -E "^#[0-9]+ +(DONE|INITED)|stat::number_of_executed_units|stat::average_exec_per_sec|ERROR|SUMMARY|crashes:" \
      "$BUILD/findings/$h.log" | sed "s/^/fuzz_$h: /" || true
  if [ "$h" = vdb ]; then
    echo "fuzz_vdb: $(ls "$BUILD/findings/$h/" 2>/dev/null | wc -l) inputs that crash OpenVDB in-process (isolated by the commands; see docs/robustness.md)"
  elif [ $rc -ne 0 ] || ls "$BUILD/findings/$h/" 2>/dev/null | grep -q .; then
    echo "fuzz_$h: exit $rc, findings in $BUILD/findings/$h/ (log: $BUILD/findings/$h.log)"; return 1
  fi
  return 0
}

# PARALLEL=1 runs the harnesses side by side (one core each) instead of in turn.
status=0
pids=()
for h in ${HARNESSES:-scene_json mesh exr vdb}; do
  if [ "${PARALLEL:-0}" = 1 ]; then run_harness "$h" & pids+=($!); else run_harness "$h" || status=1; fi
done
for p in "${pids[@]}"; do wait "$p" || status=1; done
exit $status
