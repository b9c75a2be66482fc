#!/usr/bin/env bash
# Writes docs/frame-steps.md: for every shipped preset, stages 3–7 as the list of steps its
# stage choices compose (render/src/chain/, docs/architecture.md "The frame as a list"), as
# `gi-lab render` prints them after one frame of the default scene at 32×32. Run it again
# when a stage choice, a step or a preset changes.
set -euo pipefail
cd "$(dirname "$0")/.."
export WGPU_BACKEND="${WGPU_BACKEND:-vulkan}"
bin=target/debug/gi-lab
cargo build -q -p gi-lab
out=docs/frame-steps.md
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
{
  echo "# The frame's steps per shipped preset"
  echo
  echo "Written by \`scripts/frame-steps.sh\` at commit $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- render presets || echo ' (with uncommitted changes)'):"
  echo "\`gi-lab render --preset P --size 32x32 --frames 1\` on the default scene, its \`steps:\` line."
  echo "Each step is \"stage name\"; the near field's list, when there is one, comes last. The"
  echo "\`explain.*\` steps record only while a pixel is pinned."
  echo
  echo "| preset | steps |"
  echo "|---|---|"
  for f in presets/*.ron; do
    p=$(basename "$f" .ron)
    steps=$("$bin" render --preset "$f" --size 32x32 --frames 1 --out "$tmp/$p" | sed -n 's/^steps: //p')
    echo "| \`$p\` | ${steps//→/·} |"
  done
} >"$out"
echo "wrote $out"
