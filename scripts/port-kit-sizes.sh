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
: >"$tmp/several.md"
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
    row=$(python3 - "$tmp/$p/manifest.json" "$tmp/$p.several" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
steps = sum(len(p["steps"]) for p in m["passes"])
files = {o["file"] for f in m["golden"] for o in f["inputs"] + [x for p in f["passes"] for x in p["outputs"]]}
e = m.get("expressions") or {}
print(f'{len(m["passes"])} | {steps} | {len(m["resources"])} | {len(m["shaders"])} | {len(m["translations"])} | {len(files)}', end="\t")
print(f'{e.get("fitted", 0)} of W, H ({e.get("as_captured", 0)} as captured); {e.get("following_a_setting", 0)} follow a setting, {e.get("fitted_in_a_setting", 0)} fitted in it')
# The numbers that follow several settings, or a setting and the image: their expressions.
rows = []
def several(deps, exprs):
    return len(deps) > 1 or any(x and ("W" in x or "H" in x) for x in exprs)
for r in m["resources"]:
    if r.get("depends_on") and several(r["depends_on"], r["size_expr"]):
        rows.append((f'`{r["name"]}` size', r["depends_on"], r["size_expr"]))
for p in m["passes"]:
    for s in p["steps"]:
        if s.get("counts_depend_on") and several(s["counts_depend_on"], s["counts_expr"]):
            rows.append((f'`{p["name"]}` {s["kind"]} `{s.get("pipeline")}`', s["counts_depend_on"], s["counts_expr"]))
seen = set()
unrolled = set()
with open(sys.argv[2], "w") as f:
    for what, deps, exprs in rows:
        key = (what, tuple(deps), tuple(str(x) for x in exprs))
        if key in seen:
            continue
        seen.add(key)
        # One setting, an expression of the image without it: a step or resource of a loop
        # that setting unrolls (it exists at some of its values), counted, not listed.
        if len(deps) == 1 and all(x and not any(d in x for d in deps) for x in exprs):
            unrolled.add(what)
            continue
        shown = ", ".join(f"`{x}`" if x else "as captured" for x in exprs)
        f.write(f'| `{m["preset"]}` | {what} | {", ".join(deps)} | {shown} |\n')
    if unrolled:
        f.write(f'| `{m["preset"]}` | {len(unrolled)} more of the image that exist at some values of a setting (a loop unrolled) | | |\n')
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
    cat "$tmp/$p.several" >>"$tmp/several.md"
    rm -rf "${tmp:?}/$p-port"
    rm -rf "${tmp:?}/$p"
  done
  echo
  echo "## Sizes that follow several settings, or a setting and the image"
  echo
  echo "Each kit's numbers (once each, of its last frame's passes) that follow more than one setting, or a setting and the image, with the settings they follow and their expressions (docs/port-kit.md, \"Several settings at once, or a setting and the image\"); \"as captured\" where none was fitted: a loop a setting unrolls, or no expression that every capture and the range between them agree on."
  echo
  echo "| preset | number | follows | expressions |"
  echo "|---|---|---|---|"
  cat "$tmp/several.md"
} >"$out"
echo "wrote $out"
