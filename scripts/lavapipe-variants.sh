#!/usr/bin/env bash
# Lavapipe's shader variants (docs/performance.md, "Shader variants on lavapipe"): Knecht on the
# default box open to a sky of 64 directions that rotate every frame, 3 frames at 96², each run
# with a cold Mesa shader cache, so that every LLVM compile a frame triggers is paid. Prints the
# commit, the view and the per-pass table's light-space rows and total, then how many shader
# variants the cache holds after one frame and after three (a pass whose uniforms lavapipe
# inlines adds variants every frame). Run from the repository root after `cargo build`.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/debug/gi-lab
[ -x "$bin" ] || { echo "scripts/lavapipe-variants.sh: build first (cargo build)" >&2; exit 1; }
export WGPU_BACKEND="${WGPU_BACKEND:-vulkan}"
cache="$(mktemp -d /tmp/gi-lab-variants.XXXXXX)"
trap 'rm -rf "$cache"' EXIT
args=(--preset presets/knecht-cornell-256.ron --sky 0.6,0.75,1 --set sky.directions=64
  --set direct.shadow_map_size=256 --size 96x96)
echo "commit $(git rev-parse --short HEAD)$(git diff --quiet || echo ' (with local changes)'), $(date -u +%F)"
echo "view: the default box (embedded), its camera; ${args[*]}"
MESA_SHADER_CACHE_DIR="$cache/bench" "$bin" bench "${args[@]}" --frames 3 2>&1 | grep -E '^(pass |vpl\.|direct\.shadow|total|GI Lab bench)'
out="$(mktemp -d /tmp/gi-lab-variants-out.XXXXXX)"
MESA_SHADER_CACHE_DIR="$cache/one" "$bin" render "${args[@]}" --frames 1 --out "$out" >/dev/null 2>&1
one=$(find "$cache/one" -type f | wc -l)
MESA_SHADER_CACHE_DIR="$cache/one" "$bin" render "${args[@]}" --frames 3 --out "$out" >/dev/null 2>&1
three=$(find "$cache/one" -type f | wc -l)
rm -rf "$out"
echo "shader cache entries: $one after 1 frame, $three after a second run of 3 frames (+$((three - one)))"
