#!/usr/bin/env bash
# Renders the README gallery (docs/gallery/*.png) from the bundled sample scenes.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$ROOT/docs/gallery"
mkdir -p "$OUT"
# Each with its own samples per pixel unless SPP is set.
for s in cloud cloud_sky plume sparse glass; do
  res=320x240; [ "$s" = plume ] && res=240x320
  "$ROOT/build/bin/vdbmarch" render "$ROOT/vdb_samples/$s.json" -o "/tmp/vdbmarch_gallery_$s.exr" \
      --png "$OUT/$s.png" --res "$res" ${SPP:+--spp "$SPP"}
done

# The paper's scenes (vdb_samples/scenes), 640x480 with their own method
# (guided), a PNG next to each scene. TIME seconds per scene, photons and
# cache included; cloud_sun needs ../shared/assets.
for s in exp1_point exp1_sphere exp2_collimated fig3b_spots fig4_caustic cloud_sun plume_emission; do
  if [ "$s" = cloud_sun ] && [ ! -d "$ROOT/../shared/assets" ]; then
    echo "render_gallery: ../shared/assets is absent: cloud_sun skipped" >&2
    continue
  fi
  "$ROOT/build/bin/vdbmarch" render "$ROOT/vdb_samples/scenes/$s.json" -o "/tmp/vdbmarch_gallery_$s.exr" \
      --png "$ROOT/vdb_samples/scenes/$s.png" --time "${TIME:-60}"
  # A 256-colour palette keeps the committed PNG small (noise compresses badly).
  if command -v convert >/dev/null; then
    convert "$ROOT/vdb_samples/scenes/$s.png" -colors 256 "PNG8:$ROOT/vdb_samples/scenes/$s.png"
  fi
done
