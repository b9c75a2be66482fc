#!/usr/bin/env bash
# Issue #53's bytes-per-pixel tables (docs/performance.md; each run's page under docs/runs/): the traffic counter of
# `gi-lab bench --json` (what each pass binds, from the formats and sizes; the same on every
# device) divided by the pixels, at SIZE (default 1920x1080) on the embedded default scene from
# its camera, animation playing.
#
# 1. The default preset pass by pass, for GI_LAB_BEFORE (an older build of gi-lab, when given)
#    and this binary, side by side (a pass one of them does not run shows "–").
# 2. Every shipped preset's frame (presets/*.ron), the same two binaries.
#
#   cargo build -p gi-lab && GI_LAB_BEFORE=/path/to/old/gi-lab bash scripts/bytes-per-pixel.sh [SIZE]
set -euo pipefail
cd "$(dirname "$0")/.."

BIN="${GI_LAB_BIN:-target/debug/gi-lab}"
BEFORE="${GI_LAB_BEFORE:-}"
BEFORE_LABEL="${GI_LAB_BEFORE_LABEL:-before}"
SIZE="${1:-1920x1080}"
if [ ! -x "$BIN" ]; then
  echo "scripts/bytes-per-pixel.sh: $BIN is missing: cargo build -p gi-lab" >&2
  exit 1
fi
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT

# bench BIN OUT [ARGS…]: the JSON of two measured frames.
bench() {
  local bin="$1" out="$2"
  shift 2
  "$bin" bench --size "$SIZE" --frames 2 --flicker-frames 0 --afterglow-frames 0 --json "$@" >"$out" 2>"$TMP/err" ||
    { cat "$TMP/err" >&2; exit 1; }
}

commit="$(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
echo "Commit $commit${BEFORE:+ against $BEFORE_LABEL}, $SIZE, the embedded default scene from its camera, animation playing, $(date -u +%Y-%m-%d): \`gi-lab bench --json\`'s traffic counter (bytes bound by each pass) ÷ pixels."
echo
[ -n "$BEFORE" ] && bench "$BEFORE" "$TMP/before.json"
bench "$BIN" "$TMP/now.json"
python3 - "$TMP/before.json" "$TMP/now.json" "$BEFORE_LABEL" "$commit" <<'EOF'
import json, os, sys
before_path, now_path, label, commit = sys.argv[1:5]
def load(p):
    if not os.path.exists(p):
        return None
    d = json.load(open(p))
    px = d["width"] * d["height"]
    return [(p["pass"], p["traffic_bytes"] / px) for p in d["passes"]], d["traffic_bytes_per_frame"] / px
now = load(now_path)
before = load(before_path)
names = []
for table in ([before[0]] if before else []) + [now[0]]:
    for n, _ in table:
        if n not in names:
            names.append(n)
cols = ([f"{label}"] if before else []) + [f"now ({commit})"]
print("| pass | " + " | ".join(cols) + " |")
print("|---|" + "---:|" * len(cols))
for n in names:
    cells = []
    for t in ([before] if before else []) + [now]:
        v = dict(t[0]).get(n)
        cells.append("–" if v is None else f"{v:.1f}")
    print(f"| {n} | " + " | ".join(cells) + " |")
print("| **frame** | " + " | ".join(f"**{t[1]:.1f}**" for t in ([before] if before else []) + [now]) + " |")
EOF
echo
echo "Every shipped preset's frame (B/px), the same way:"
echo
if [ -n "$BEFORE" ]; then
  echo "| preset | $BEFORE_LABEL | now ($commit) |"
  echo "|---|---:|---:|"
else
  echo "| preset | now ($commit) |"
  echo "|---|---:|"
fi
for preset in presets/*.ron; do
  name="$(basename "$preset" .ron)"
  # The exact reference gathers every VPL against cube maps: not a real-time preset.
  [ "$name" = exact-vpl-reference ] && continue
  row="| \`$name\` |"
  for bin in $BEFORE "$BIN"; do
    file="$preset"
    if [ "$bin" = "$BEFORE" ] && grep -q "temporal: HcbSampleCache" "$preset" && [ "$name" = gautron-at-hcb-samples ]; then
      # A build from before session 11 refuses the mix with the HCB's sample cache: the
      # preset as it was then (every sample a hemisphere every frame).
      sed 's/temporal: HcbSampleCache/temporal: r#None/' "$preset" >"$TMP/as-it-was.ron"
      file="$TMP/as-it-was.ron"
    fi
    # A build that fails on a preset at this size (the HCB's lists before a05a57a exceeded
    # lavapipe's storage bindings at 1920x1080) gets "fails" and its first error line.
    if "$bin" bench --size "$SIZE" --frames 2 --flicker-frames 0 --afterglow-frames 0 --json --preset "$file" \
      >"$TMP/p.json" 2>"$TMP/err"; then
      row="$row $(python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); print("%.1f" % (d["traffic_bytes_per_frame"]/(d["width"]*d["height"])))' "$TMP/p.json") |"
    else
      why="$(grep -m1 -E 'exceeds|error' "$TMP/err" | sed 's/^ *//; s/|/\\|/g' | cut -c1-90)"
      row="$row fails (${why:-exit $?}) |"
    fi
  done
  echo "$row"
done
