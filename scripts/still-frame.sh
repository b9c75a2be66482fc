#!/usr/bin/env bash
# Issue #53's "kept while nothing moves" table (docs/performance.md): the default preset on
# the embedded default scene, its animation playing and paused, each with the passes kept
# while their inputs do not change (the default) and with every pass redone every frame
# (`--no-reuse`, what the frame did before), all four from one binary in one run. Prints a
# Markdown table headed by the commit, the size and the view.
#
#   cargo build -p gi-lab && bash scripts/still-frame.sh [SIZE] [FRAMES]
#
# On lavapipe read the ratios between rows of one run, not the absolute times.
set -euo pipefail
cd "$(dirname "$0")/.."

BIN="${GI_LAB_BIN:-target/debug/gi-lab}"
SIZE="${1:-1280x720}"
FRAMES="${2:-10}"
if [ ! -x "$BIN" ]; then
  echo "scripts/still-frame.sh: $BIN is missing: cargo build -p gi-lab" >&2
  exit 1
fi
LOG="$(mktemp)"
trap 'rm -f "$LOG"' EXIT

run() {
  "$BIN" bench --preset presets/default.ron --size "$SIZE" --frames "$FRAMES" \
    --flicker-frames 0 --afterglow-frames 0 "$@" 2>&1
}

echo "Commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown), $SIZE, $FRAMES frames after 3 warm-up frames, the default preset on the embedded default scene from its camera, $(date -u +%Y-%m-%d)."
echo
echo "| animation | passes | frame wall ms | window frame ms | gbuffer ms | direct ms | light-space passes ms | kept / frame: light space, G-buffer + direct |"
echo "|---|---|---:|---:|---:|---:|---:|---|"
for anim in playing paused; do
  for reuse in kept redone; do
    args=()
    [ "$anim" = paused ] && args+=(--paused)
    [ "$reuse" = redone ] && args+=(--no-reuse)
    run "${args[@]}" >"$LOG"
    grep -q "^GI Lab bench" "$LOG" || { cat "$LOG" >&2; exit 1; }
    awk -v anim="$anim" -v reuse="$reuse" '
      /^pass / { table = 1; next }
      table && /^total / { table = 0; next }
      table && $1 == "gbuffer" { g = $2 }
      table && $1 == "direct" { d = $2 }
      table && ($1 == "direct.shadow" || $1 ~ /^vpl\.(light_gbuffer|importance|sample)/ || $1 ~ /^ism\./) { ls += $2 }
      /^frame wall/ { wall = $3 }
      /^window frame/ { window = $3 }
      /^kept while nothing moved/ { kept = $11 ", " $19 }
      END {
        if (g == "") g = "kept"
        if (d == "") d = "kept"
        printf "| %s | %s | %s | %s | %s | %s | %.1f | %s |\n", anim, (reuse == "kept" ? "kept while unchanged" : "all redone (--no-reuse)"), wall, window, g, d, ls, kept
      }
    ' "$LOG"
  done
done
