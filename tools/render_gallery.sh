#!/usr/bin/env bash
# Renders the README gallery with what a user gets by default: the automatic
# method, a time budget (photons, cache and denoiser included), the PNG
# denoised. The bundled samples go to docs/gallery/*.png (320x240, TIME_SMALL
# seconds each), the paper's scenes next to their scene files
# (vdb_samples/scenes/*.png, 640x480, TIME seconds each); cloud_sun needs
# ../shared/assets. Usage: tools/render_gallery.sh   (TIME=16 TIME_SMALL=8)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="$ROOT/build/bin/vdbmarch"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
render() {  # scene png resolution seconds
  "$BIN" render "$1" -o "$TMP/out.exr" --png "$2" --res "$3" --time "$4" --method auto -q
  # A 256-colour palette keeps the committed PNG small.
  if convert -version 2>/dev/null | grep -q ImageMagick; then convert "$2" -colors 256 "PNG8:$2"; fi
}
for s in cloud cloud_sky plume sparse glass; do
  res=320x240; [ "$s" = plume ] && res=240x320
  render "$ROOT/vdb_samples/$s.json" "$ROOT/docs/gallery/$s.png" "$res" "${TIME_SMALL:-8}"
done
for s in exp1_point exp1_sphere exp2_collimated fig3b_spots fig4_caustic cloud_sun plume_emission; do
  if [ "$s" = cloud_sun ] && [ ! -d "$ROOT/../shared/assets" ]; then
    echo "render_gallery: ../shared/assets is absent: cloud_sun skipped" >&2
    continue
  fi
  render "$ROOT/vdb_samples/scenes/$s.json" "$ROOT/vdb_samples/scenes/$s.png" 640x480 "${TIME:-16}"
done
