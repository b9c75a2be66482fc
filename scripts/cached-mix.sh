#!/usr/bin/env bash
# Issue #53's lavapipe tables for this work (docs/performance.md; each run's page under docs/runs/), from one binary in one run:
#
# 1. `gautron-at-hcb-samples` (Gautron's hemispheres at the HCB's samples) on the embedded
#    default scene from its camera at SIZE (default 320x180), its animation playing: without
#    the HCB's sample cache (`pipeline.temporal = None`, every sample a hemisphere every frame),
#    with it (the preset's choice: only the due and the new samples), and paused with the
#    passes kept; when GI_LAB_BEFORE names an older build of gi-lab, its frame first (with
#    `pipeline.temporal = None`, the preset as it was before the cache). Then the cache's counts per frame (`gi-lab hcb-stats
#    --play`): how many samples got a hemisphere.
# 2. The traffic counter per pass (bytes bound ÷ pixels) of the default preset at 1920x1080,
#    from `gi-lab bench --json`, for GI_LAB_BEFORE (when given) and this binary.
#
#   cargo build -p gi-lab && GI_LAB_BEFORE=/path/to/old/gi-lab bash scripts/cached-mix.sh [SIZE] [FRAMES]
#
# On lavapipe read the ratios between rows of one run, not the absolute times.
set -euo pipefail
cd "$(dirname "$0")/.."

BIN="${GI_LAB_BIN:-target/debug/gi-lab}"
BEFORE="${GI_LAB_BEFORE:-}"
BEFORE_LABEL="${GI_LAB_BEFORE_LABEL:-before}"
SIZE="${1:-320x180}"
FRAMES="${2:-6}"
PRESET=presets/gautron-at-hcb-samples.ron
if [ ! -x "$BIN" ]; then
  echo "scripts/cached-mix.sh: $BIN is missing: cargo build -p gi-lab" >&2
  exit 1
fi
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
LOG="$TMP/log"

bench() {
  local bin="$1" preset="${PRESET_FILE:-$PRESET}"
  shift
  "$bin" bench --preset "$preset" --size "$SIZE" --frames "$FRAMES" --flicker-frames 0 --afterglow-frames 0 "$@" >"$LOG" 2>&1
  grep -q "^GI Lab bench" "$LOG" || { cat "$LOG" >&2; exit 1; }
}

# One row from the bench in $LOG: the HCB's passes summed, the hemispheres' two scopes, the
# splat, the frame.
row() {
  awk -v label="$1" '
    /^pass / { table = 1; next }
    table && /^total / { table = 0; next }
    table && $1 ~ /^hcb\.(cache\.update|cache\.splat|build)$/ { hcb += $2 }
    table && $1 == "gautron.create" { c = $2 " (" $3 ")" }
    table && $1 == "gautron.hemispheres" { h = $2 " (" $3 ")" }
    table && $1 == "hcb.splat" { s = $2 }
    /^frame wall/ { wall = $3 }
    /^window frame/ { window = $3 }
    END {
      if (c == "") c = "kept"
      if (h == "") h = "kept"
      printf "| %s | %.1f | %s | %s | %s | %s | %s |\n", label, hcb, c, h, s, wall, window
    }
  ' "$LOG"
}

commit="$(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
echo "Commit $commit${BEFORE:+ against $BEFORE_LABEL}, $SIZE, $FRAMES frames after 3 warm-up frames, \`$PRESET\` on the embedded default scene from its camera, $(date -u +%Y-%m-%d). Times in ms: the mean (and the least) over the frames; the HCB's selection passes (hcb.cache.update, hcb.cache.splat, hcb.build) summed; frame wall and window frame are means."
echo
echo "| frames | HCB selection | gautron.create | gautron.hemispheres | hcb.splat | frame wall | window frame |"
echo "|---|---:|---:|---:|---:|---:|---:|"
if [ -n "$BEFORE" ]; then
  # A build from before the cache refuses the preset's HcbSampleCache: give it a copy without.
  sed 's/temporal: HcbSampleCache/temporal: r#None/' "$PRESET" >"$TMP/uncached.ron"
  PRESET_FILE="$TMP/uncached.ron" bench "$BEFORE"
  row "$BEFORE_LABEL, playing (no sample cache)"
fi
bench "$BIN" --set pipeline.temporal=None
row "now, playing, no sample cache (temporal None)"
bench "$BIN"
row "now, playing, the HCB's sample cache (the preset)"
bench "$BIN" --paused
row "now, paused, kept while unchanged"
echo
echo "The cache's counts per frame, \`gi-lab hcb-stats --preset $PRESET --size $SIZE --frames $FRAMES --play\` (a hemisphere for each new and each recomputed sample):"
echo
echo '```'
"$BIN" hcb-stats --preset "$PRESET" --size "$SIZE" --frames "$FRAMES" --play 2>/dev/null | grep '^frame'
echo '```'

# Table 2: bytes bound per pixel, default preset, 1920x1080.
traffic() {
  "$1" bench --size 1920x1080 --frames 2 --flicker-frames 0 --afterglow-frames 0 --json >"$2" 2>/dev/null
}
echo
echo "Bytes bound per pixel (the traffic counter ÷ pixels), the default preset at 1920x1080 on the embedded default scene from its camera, animation playing, \`gi-lab bench --json\`:"
echo
files=()
labels=()
if [ -n "$BEFORE" ]; then
  traffic "$BEFORE" "$TMP/before.json"
  files+=("$TMP/before.json")
  labels+=("$BEFORE_LABEL")
fi
traffic "$BIN" "$TMP/now.json"
files+=("$TMP/now.json")
labels+=("now ($commit)")
python3 - "${#files[@]}" "${files[@]}" "${labels[@]}" <<'PY'
import json, sys
n = int(sys.argv[1])
runs = [json.load(open(f)) for f in sys.argv[2:2 + n]]
labels = sys.argv[2 + n:]
px = runs[-1]["width"] * runs[-1]["height"]
names = []
for r in runs:
    for p in r["passes"]:
        if p["pass"] not in names:
            names.append(p["pass"])
print("| pass | " + " | ".join(labels) + " |")
print("|---|" + "---:|" * n)
for name in names:
    cells = []
    for r in runs:
        b = next((p["traffic_bytes"] for p in r["passes"] if p["pass"] == name), None)
        cells.append("–" if b is None else f"{b / px:.1f}")
    print(f"| {name} | " + " | ".join(cells) + " |")
print("| **frame** | " + " | ".join(f"**{r['traffic_bytes_per_frame'] / px:.1f}**" for r in runs) + " |")
PY
