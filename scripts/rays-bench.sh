#!/usr/bin/env bash
# The GPU rays of issue #56 against the CPU's (docs/performance.md, "The GPU truth"): first
# `gi-lab bench --suite rays` (rays and paths per second on the default scene and every scene
# of assets/), then for each shipped scene the truth traced three times at SIZE and SPP from
# its default view: the CPU tracer (seed 1), the CPU tracer again (seed 2: the noise floor),
# the GPU tracer (seed 1), and the FLIP of each against the first. Prints the commit, the
# adapter, the size and spp. Run from the repository root after `cargo build` (or set
# GI_LAB_BIN=target/release/gi-lab):
#
#   bash scripts/rays-bench.sh [SIZE] [SPP]      # defaults 64x64 and 1024
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${GI_LAB_BIN:-target/debug/gi-lab}"
[ -x "$bin" ] || { echo "scripts/rays-bench.sh: build first (cargo build)" >&2; exit 1; }
size="${1:-64x64}"
spp="${2:-1024}"
out="$(mktemp -d /tmp/gi-lab-rays.XXXXXX)"
trap 'rm -rf "$out"' EXIT
echo "commit $(git rev-parse --short HEAD)$(git diff --quiet || echo ' (with local changes)'), $(date -u +%F), $bin"
"$bin" bench --suite rays --size "$size" --spp 16 2>/dev/null
echo
echo "truths at $size, $spp spp, 1 bounce, each scene's default view: FLIP against the CPU's (seed 1)"
echo
echo "| scene | CPU seed 2 (noise floor) | GPU | CPU s | GPU s |"
echo "|---|---:|---:|---:|---:|"
scenes=("" assets/scenes/cornell-box/CornellBox-Original.gltf assets/scenes/chair-on-floor/MixedLightingExample.gltf
  assets/scenes/hotel-room/hotel-room.glb assets/scenes/japanese-garden/japanese-garden.glb)
for s in "${scenes[@]}"; do
  name="${s:-default Cornell box}"
  scene=()
  [ -n "$s" ] && scene=(--scene "$s")
  t() { local start=$SECONDS; "$bin" reference "${scene[@]}" --size "$size" --spp "$spp" --bounces 1 "$@" >/dev/null 2>&1; echo $((SECONDS - start)); }
  cpu_s=$(t --out "$out/cpu.exr")
  t --seed 2 --out "$out/cpu2.exr" >/dev/null
  gpu_s=$(t --gpu --out "$out/gpu.exr")
  flip() { "$bin" compare "$out/$1.exr" "$out/cpu.exr" 2>/dev/null | awk '/^FLIP/ { print $2 }'; }
  echo "| ${name#assets/scenes/} | $(flip cpu2) | $(flip gpu) | $cpu_s | $gpu_s |"
done
