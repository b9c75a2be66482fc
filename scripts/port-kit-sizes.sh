#!/usr/bin/env bash
# Writes docs/port-kit-sizes.md: for the four papers' presets and a mix, the port kit that
# `gi-lab export --port-kit` writes on the embedded default scene from its camera (passes,
# steps, resources, shader modules, translations, golden files, size on disk), at SIZE and
# FRAMES (320x180 and 4, the command's defaults, unless given). Run it again when the kit's
# contents change.
#
#   bash scripts/port-kit-sizes.sh [SIZE] [FRAMES]
set -euo pipefail
cd "$(dirname "$0")/.."
export WGPU_BACKEND="${WGPU_BACKEND:-vulkan}"
SIZE="${1:-320x180}"
FRAMES="${2:-4}"
bin=target/debug/gi-lab
cargo build -q -p gi-lab
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
out=docs/port-kit-sizes.md
{
  echo "# Port kit sizes"
  echo
  echo "Written by \`scripts/port-kit-sizes.sh\` at commit $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- render app shaders presets || echo ' (with uncommitted changes)'), $(date -u +%Y-%m-%d):"
  echo "\`gi-lab export --preset P --port-kit DIR --size $SIZE --frames $FRAMES\` on the embedded default scene from its camera."
  echo "Golden files count the distinct files (a frame that repeats an earlier one's contents names its file)."
  echo
  echo "| preset | passes | steps | resources | shader modules | entry points translated | golden files | size on disk |"
  echo "|---|---:|---:|---:|---:|---:|---:|---:|"
  for p in knecht-cornell-256 nguyen-hcb gautron-ic-splatting soler-quarter-4-64 soler-near-knecht-far; do
    "$bin" export --preset "presets/$p.ron" --port-kit "$tmp/$p" --size "$SIZE" --frames "$FRAMES" >/dev/null 2>&1
    row=$(python3 - "$tmp/$p/manifest.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
steps = sum(len(p["steps"]) for p in m["passes"])
files = {o["file"] for f in m["golden"] for o in f["inputs"] + [x for p in f["passes"] for x in p["outputs"]]}
print(f'{len(m["passes"])} | {steps} | {len(m["resources"])} | {len(m["shaders"])} | {len(m["translations"])} | {len(files)}')
PY
)
    size=$(du -sh "$tmp/$p" | cut -f1)
    echo "| \`$p\` | $row | $size |"
    rm -rf "${tmp:?}/$p"
  done
} >"$out"
echo "wrote $out"
