#!/usr/bin/env bash
# Renders the README gallery (docs/gallery/*.png) from the bundled sample scenes.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$ROOT/docs/gallery"
mkdir -p "$OUT"
for s in cloud plume sparse glass; do
  res=320x240; [ "$s" = plume ] && res=240x320
  "$ROOT/build/bin/vdbmarch" render "$ROOT/vdb_samples/$s.json" -o "/tmp/vdbmarch_gallery_$s.exr" \
      --png "$OUT/$s.png" --res "$res" --spp "${SPP:-16}"
done
