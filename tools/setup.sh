#!/usr/bin/env bash
# Installs the Debian packages listed in tools/debian-packages.txt (only the
# missing ones) and configures + builds the release tree in build/.
# Used by the README commands and by .ci/run, so there is one list and one build.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PKGS=$(grep -v '^\s*#' "$ROOT/tools/debian-packages.txt" | tr -s ' \n' ' ')
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
cmake -S "$ROOT" -B "$ROOT/build" -G Ninja -DCMAKE_BUILD_TYPE=Release $LAUNCHER >/dev/null
cmake --build "$ROOT/build" -j "$JOBS"
