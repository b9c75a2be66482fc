#!/usr/bin/env bash
# Renders every preset in presets/ at 128×128 after 8 animated frames into OUT/<preset>/
# (final.png, final.hdr.exr). Used to check that a restructuring changes no image:
#   bash scripts/render_presets.sh /tmp/before   # on the old commit
#   bash scripts/render_presets.sh /tmp/after    # on the new one
#   bash scripts/render_presets.sh --compare /tmp/before /tmp/after
set -euo pipefail
cd "$(dirname "$0")/.."
export WGPU_BACKEND="${WGPU_BACKEND:-vulkan}"
bin=target/debug/gi-lab
if [ "${1:-}" = "--compare" ]; then
  status=0
  for d in "$2"/*/; do
    p=$(basename "$d")
    a="$2/$p/final.hdr.exr"; b="$3/$p/final.hdr.exr"
    if cmp -s "$a" "$b"; then echo "$p: bit-identical"
    else echo "$p: DIFFERS: $("$bin" compare "$b" "$a" 2>&1 | tr '\n' ' ')"; status=1; fi
  done
  exit $status
fi
out="$1"
cargo build -q -p gi-lab
for f in presets/*.ron; do
  p=$(basename "$f" .ron)
  "$bin" render --preset "$f" --size 128x128 --frames 8 --buffer final.hdr --out "$out/$p" >/dev/null
  echo "$p rendered"
done
