#!/usr/bin/env bash
# Writes docs/port-kit-sizes.md: for the four papers' presets and a mix, the port kit that
# `gi-lab export --port-kit` writes on the embedded default scene from its camera (passes,
# steps, resources, shader modules, translations, golden files, size on disk, sizes fitted as
# expressions), at SIZE and FRAMES (320x180 and 4, the command's defaults, unless given), and
# what examples/port-kit-host and `gi-lab verify` make of it. Run it again when the kit's
# contents change.
#
#   bash scripts/port-kit-sizes.sh [SIZE] [FRAMES]
set -euo pipefail
cd "$(dirname "$0")/.."
export WGPU_BACKEND="${WGPU_BACKEND:-vulkan}"
SIZE="${1:-320x180}"
FRAMES="${2:-4}"
bin=target/debug/gi-lab
cargo build -q -p gi-lab -p port-kit-host
host=target/debug/port-kit-host
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
  echo "Expressions: the sizes and counts fitted as expressions of W and H (and those left as captured); those that change with a setting, and how many of them got an expression of it (docs/port-kit.md)."
  echo "Host: \`port-kit-host\` ran the kit, \`gi-lab verify\` compared every output of every pass of every frame (tolerance 0.01)."
  echo
  echo "| preset | passes | steps | resources | shader modules | entry points translated | golden files | size on disk | expressions | host: outputs, worst | verify |"
  echo "|---|---:|---:|---:|---:|---:|---:|---:|---|---|---|"
  for p in knecht-cornell-256 nguyen-hcb gautron-ic-splatting soler-quarter-4-64 soler-near-knecht-far; do
    "$bin" export --preset "presets/$p.ron" --port-kit "$tmp/$p" --size "$SIZE" --frames "$FRAMES" >/dev/null 2>&1
    row=$(python3 - "$tmp/$p/manifest.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
steps = sum(len(p["steps"]) for p in m["passes"])
files = {o["file"] for f in m["golden"] for o in f["inputs"] + [x for p in f["passes"] for x in p["outputs"]]}
e = m.get("expressions") or {}
print(f'{len(m["passes"])} | {steps} | {len(m["resources"])} | {len(m["shaders"])} | {len(m["translations"])} | {len(files)}', end="\t")
print(f'{e.get("fitted", 0)} of W, H ({e.get("as_captured", 0)} as captured); {e.get("following_a_setting", 0)} follow a setting, {e.get("fitted_in_a_setting", 0)} fitted in it')
PY
)
    size=$(du -sh "$tmp/$p" | cut -f1)
    "$host" "$tmp/$p" "$tmp/$p-port" >/dev/null
    verdict=pass
    "$bin" verify --port-kit "$tmp/$p" --outputs "$tmp/$p-port" >"$tmp/verify.txt" 2>&1 || verdict="**fail**"
    worst=$(python3 - "$tmp/verify.txt" <<'PY'
import sys
rows = [l.split("|") for l in open(sys.argv[1]) if l.startswith("| ") and not l.startswith("| frame")]
n = sum(int(r[3]) for r in rows)
w = max(rows, key=lambda r: float(r[4].split()[0]))
print(f"{n}, {w[4].strip()}")
PY
)
    echo "| \`$p\` | ${row%%$'\t'*} | $size | ${row#*$'\t'} | $worst | $verdict |"
    rm -rf "${tmp:?}/$p-port"
    rm -rf "${tmp:?}/$p"
  done
} >"$out"
echo "wrote $out"
