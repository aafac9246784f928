#!/usr/bin/env bash
# Installs the Debian packages listed in tools/debian-packages.txt (only the
# missing ones) and configures + builds the release tree in build/.
# Used by the README commands and by .ci/run, so there is one list and one build.
#   tools/setup.sh          everything: the renderer, the tests, the benchmarks, Slurm
#   tools/setup.sh render   only what the renderer needs (the README's first command)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
MODE="${1:-all}"
case "$MODE" in render|all) ;; *) echo "usage: tools/setup.sh [render]" >&2; exit 2;; esac
LIST="$ROOT/tools/debian-packages.txt"
# The render part is the list up to its "--- tests" line.
[ "$MODE" = render ] && LIST=$(sed '/^# --- tests/,$d' "$LIST") || LIST=$(cat "$LIST")
PKGS=$(echo "$LIST" | grep -v '^\s*#' | tr -s ' \n' ' ')
MISSING=""
for p in $PKGS; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || MISSING="$MISSING $p"
done
if [ -n "$MISSING" ]; then
  echo "[setup] installing:$MISSING" >&2
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends $MISSING >/dev/null
fi
JOBS=$(nproc 2>/dev/null || echo 2)
LAUNCHER=""
command -v ccache >/dev/null && LAUNCHER="-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"
# Hash paths relative to the checkout, so a fresh clone elsewhere on this
# machine (CI clones into a new folder each run) reuses the cache.
export CCACHE_BASEDIR="$ROOT" CCACHE_NOHASHDIR=true
if [ "$MODE" = render ]; then
    # The command alone: no test suite or benchmarks to configure or build
    # (a tree already configured with them keeps them).
    [ -f "$ROOT/build/CMakeCache.txt" ] || \
        cmake -S "$ROOT" -B "$ROOT/build" -G Ninja -DCMAKE_BUILD_TYPE=Release $LAUNCHER \
            -DVDBMARCH_BUILD_TESTS=OFF -DVDBMARCH_BUILD_BENCHMARKS=OFF >/dev/null
    cmake --build "$ROOT/build" -j "$JOBS" --target vdbmarch
else
    cmake -S "$ROOT" -B "$ROOT/build" -G Ninja -DCMAKE_BUILD_TYPE=Release $LAUNCHER \
        -DVDBMARCH_BUILD_TESTS=ON -DVDBMARCH_BUILD_BENCHMARKS=ON >/dev/null
    cmake --build "$ROOT/build" -j "$JOBS"
fi
