#!/usr/bin/env bash
# Issue #53's lavapipe table (docs/performance.md; each run's page under docs/runs/): the default preset on the embedded default
# scene from its camera, its animation playing and paused, each with the passes kept while
# their inputs do not change (the default) and with every pass redone every frame
# (`--no-reuse`), all from one binary in one run; and, when GI_LAB_BEFORE names an older
# build of gi-lab (e.g. one made at the commit before a change), that binary's frame first
# (it has no --paused or --no-reuse: its animation plays and every pass runs). Prints a
# Markdown table headed by the commits, the size and the view.
#
#   cargo build -p gi-lab && GI_LAB_BEFORE=/path/to/old/gi-lab bash scripts/still-frame.sh [SIZE] [FRAMES]
#
# On lavapipe read the ratios between rows of one run, not the absolute times.
set -euo pipefail
cd "$(dirname "$0")/.."

BIN="${GI_LAB_BIN:-target/debug/gi-lab}"
BEFORE="${GI_LAB_BEFORE:-}"
BEFORE_LABEL="${GI_LAB_BEFORE_LABEL:-before}"
SIZE="${1:-1280x720}"
FRAMES="${2:-10}"
if [ ! -x "$BIN" ]; then
  echo "scripts/still-frame.sh: $BIN is missing: cargo build -p gi-lab" >&2
  exit 1
fi
LOG="$(mktemp)"
trap 'rm -f "$LOG"' EXIT

bench() {
  local bin="$1"
  shift
  "$bin" bench --preset presets/default.ron --size "$SIZE" --frames "$FRAMES" \
    --flicker-frames 0 --afterglow-frames 0 "$@" 2>&1
}

# One row of the table from a bench's output in $LOG.
row() {
  awk -v label="$1" '
    /^pass / { table = 1; next }
    table && /^total / { table = 0; next }
    table && $1 == "gbuffer" { g = $2 " (" $3 ")" }
    table && $1 == "direct" { d = $2 " (" $3 ")" }
    table && $1 == "interleave.gather" { ga = $2 " (" $3 ")" }
    table && $1 == "interleave.filter" { fi = $2 " (" $3 ")"; fm += $2; fml += $3 }
    table && $1 == "temporal" { t = $2 " (" $3 ")"; fm += $2; fml += $3 }
    # The filter fused into the merge (issue #53): one pass for the last two columns.
    table && $1 == "temporal.filter_merge" { fi = "fused"; t = "fused"; fm += $2; fml += $3 }
    table && ($1 == "direct.shadow" || $1 ~ /^vpl\.(light_gbuffer|importance|sample)/ || $1 ~ /^ism\./) { ls += $2 }
    /^frame wall/ { wall = $3 }
    /^window frame/ { window = $3 }
    /^kept while nothing moved/ { kept = $11 ", " $19 }
    END {
      if (g == "") g = "kept"
      if (d == "") d = "kept"
      if (kept == "") kept = "–"
      printf "| %s | %s | %s | %s | %s | %s | %.3f (%.3f) | %.1f | %s | %s | %s |\n", label, g, d, ga, fi, t, fm, fml, ls, wall, window, kept
    }
  ' "$LOG"
}

echo "Commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown)${BEFORE:+ against $BEFORE_LABEL}, $SIZE, $FRAMES frames after 3 warm-up frames, the default preset on the embedded default scene from its camera, $(date -u +%Y-%m-%d). Times in ms: per pass the mean (and the least) over the frames; the light-space passes summed (means); frame wall and window frame are means."
echo
echo "| frames | gbuffer | direct | interleave.gather | interleave.filter | temporal | filter + merge | light-space passes | frame wall | window frame | kept / frame: light space, G-buffer + direct |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"
if [ -n "$BEFORE" ]; then
  bench "$BEFORE" >"$LOG"
  grep -q "^GI Lab bench" "$LOG" || { cat "$LOG" >&2; exit 1; }
  row "$BEFORE_LABEL, playing"
fi
for anim in playing paused; do
  for reuse in redone kept; do
    args=()
    [ "$anim" = paused ] && args+=(--paused)
    [ "$reuse" = redone ] && args+=(--no-reuse)
    bench "$BIN" "${args[@]}" >"$LOG"
    grep -q "^GI Lab bench" "$LOG" || { cat "$LOG" >&2; exit 1; }
    if [ "$reuse" = kept ]; then label="now, $anim, kept while unchanged"; else label="now, $anim, all redone"; fi
    row "$label"
  done
done
