#!/usr/bin/env bash
# GI Lab's GPU benchmark: every shipped preset on the embedded default scene at 1920x1080
# (also summed up as one Markdown table, gpu-bench.md: GPU and wall time, the per-frame
# counters of issue #38 and the heaviest pass), the papers' blended splats beside the default
# (binned on a GPU), the default preset at 960x540 and 3840x2160 (how the passes scale),
# the default paused with and without the passes kept while nothing moves (issue #53),
# the suites (knecht and nguyen at 1920x1080, soler at 1280x720 as its Fig. 9, gautron at
# 64x64 for its per-pixel brute force, scenes at 1920x1080 over assets/, rays at 512x512:
# the GPU ray caster and path tracer against the CPU's), written as text
# into one folder. Run it from the project root with a release build:
#
#   cargo build --release -p gi-lab && bash scripts/gpu-bench.sh [OUT_DIR]
#
# Each run has its own time limit so that one slow row cannot eat the whole budget; a row
# that times out says so in the log. Absolute times are only meaningful on a real GPU
# (docs/performance.md; each run's page under docs/runs/); on lavapipe compare ratios within one run.
set -uo pipefail
cd "$(dirname "$0")/.."

BIN="${GI_LAB_BIN:-target/release/gi-lab}"
SIZE="${GI_LAB_BENCH_SIZE:-1920x1080}"
FRAMES="${GI_LAB_BENCH_FRAMES:-60}"
LIMIT="${GI_LAB_BENCH_LIMIT:-90}"
OUT="${1:-out/gpu-bench}"
mkdir -p "$OUT"
LOG="$OUT/gpu-bench.txt"
: >"$LOG"

if [ ! -x "$BIN" ]; then
  echo "scripts/gpu-bench.sh: $BIN is missing: cargo build --release -p gi-lab" >&2
  exit 1
fi

# One row: its command line, then its output (or why it stopped).
row() {
  local name="$1"
  shift
  echo "=== $name: gi-lab $*" | tee -a "$LOG"
  local start=$SECONDS
  timeout "$LIMIT" "$BIN" "$@" >>"$LOG" 2>&1
  local rc=$?
  if [ $rc -eq 124 ]; then
    echo "(stopped after ${LIMIT} s)" | tee -a "$LOG"
  elif [ $rc -ne 0 ]; then
    echo "(exit status $rc)" | tee -a "$LOG"
  fi
  echo "--- $name: $((SECONDS - start)) s" | tee -a "$LOG"
}

{
  echo "GI Lab GPU bench, $(date -u +%Y-%m-%dT%H:%MZ), commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
  command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
  uname -srm
} | tee -a "$LOG"

TABLE="$OUT/gpu-bench.md"
{
  echo "| preset ($SIZE) | GPU ms | wall ms | window frame ms | blocking waits / frame | submits / frame | objects created / frame | MB bound / frame | kept / frame: light space, G-buffer + direct | heaviest pass (ms) |"
  echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"
} >"$TABLE"
# One preset (or a variant of it: NAME+VARIANT with extra --set arguments), as a table row.
preset_row() {
  local name="$1" preset="$2"
  shift 2
  row "preset $name" bench --preset "$preset" --size "$SIZE" --frames "$FRAMES" "$@"
  # One Markdown row from the bench's table: its total, wall clock, counters and heaviest pass.
  awk -v name="$name" '
    /^=== preset / { mine = ($3 == name ":") }
    mine && /^GI Lab bench/ { table = 1; next }
    mine && table && /^pass / { next }
    mine && table && /^total / { gpu = $2; mb = $3; table = 0; next }
    mine && table && NF >= 5 { if ($2 + 0 > top_ms) { top_ms = $2 + 0; top = $1 } }
    mine && /^frame wall/ { wall = $3 }
    mine && /^window frame/ { window = $3 }
    mine && /^per frame:/ { waits = $3; submits = $6; objects = $8 }
    mine && /^kept while nothing moved/ { kept = $11 ", " $19 }
    END { if (gpu != "") printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s %.2f |\n", name, gpu, wall, window, waits, submits, objects, mb, kept, top, top_ms }
  ' "$LOG" >>"$TABLE"
}
for p in presets/*.ron; do
  preset_row "$(basename "$p" .ron)" "$p"
done
# The splats as the papers' blended quads, against the default above (`Auto`: binned in
# compute on a GPU, issue #38).
preset_row gautron-ic-splatting+blend presets/gautron-ic-splatting.ron --set gautron.splat=Blend
preset_row nguyen-hcb+blend presets/nguyen-hcb.ron --set hcb.splat=Blend
preset_row nguyen-hcb-cached+blend presets/nguyen-hcb-cached.ron --set hcb.splat=Blend
# The Gautron mix without the HCB's sample cache (issue #53: the preset caches its samples'
# hemispheres; every sample a hemisphere every frame, as before).
preset_row gautron-at-hcb-samples+no-cache presets/gautron-at-hcb-samples.ron --set pipeline.temporal=None
# DDGI at the production grid of issue #56's goal (probe update plus sampling ≤ 1 ms at
# 1080p with 16×8×16 probes and 256 rays a probe): the passes ddgi.trace, ddgi.update and
# ddgi.apply of the table.
preset_row ddgi-probes+16x8x16x256 presets/ddgi-probes.ron --set ddgi.probes_x=16 --set ddgi.probes_y=8 \
  --set ddgi.probes_z=16 --set ddgi.rays_per_probe=256
# The default preset with its animation paused (issue #53: the still view a lighting artist
# tunes keeps its shadow maps, light G-buffer, G-buffer and direct light), and the same
# redoing every pass every frame (before #53), so that the saving is read in one run.
preset_row default+paused presets/default.ron --paused
preset_row default+paused+no-reuse presets/default.ron --paused --no-reuse
# The default preset at a quarter and four times the pixels: how each pass scales with the
# image (on the H100/H200 the G-buffer is linear in the pixels: their raster is the limit).
row "scaling 960x540" bench --preset presets/default.ron --size 960x540 --frames 30 --flicker-frames 0 --afterglow-frames 0
row "scaling 3840x2160" bench --preset presets/default.ron --size 3840x2160 --frames 30 --flicker-frames 0 --afterglow-frames 0
row "suite knecht" bench --suite knecht --size "$SIZE" --frames 20
row "suite nguyen" bench --suite nguyen --size "$SIZE" --frames 20
row "suite soler" bench --suite soler --size 1280x720 --frames 20
row "suite scenes" bench --suite scenes --size "$SIZE" --frames 20
row "suite gautron" bench --suite gautron --size 64x64
# The GPU ray caster and path tracer against the CPU's (issue #56): rays and paths per second.
row "suite rays" bench --suite rays --size 512x512 --spp 16
echo "done: $LOG and $TABLE"
