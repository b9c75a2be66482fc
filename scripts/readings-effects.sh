#!/usr/bin/env bash
# Measures what the readings of the papers that have a setting change (docs/readings.md): for
# each one, `gi-lab sweep` renders the embedded default scene with the paper's preset at both
# values of the setting (256×256, 3 warm-up frames and 4 timed ones, the scene paused) and
# measures FLIP against the path-traced truth; the script then prints, per reading, the
# measured-effect cell of its row in docs/readings.md.
#
# Usage: scripts/readings-effects.sh [ID ...]
#   ID      readings to measure (e.g. soler.vote-sigmas); all of the list below when none
#   GI_LAB  the binary (default target/debug/gi-lab; it is not rebuilt)
#   OUT     the output folder (default a new folder under /tmp); OUT/<id>/sweep.csv per reading
#
# Each preset's truth is path-traced once (by the first sweep that uses the preset) and
# passed to the later sweeps with --reference. A reading whose setting the binary does not
# know is reported as "pending". Times from a software renderer (lavapipe) are only
# comparable within a run, so the cell gives the ratio of the frame times, B/A.
set -euo pipefail
cd "$(dirname "$0")/.."

BIN="${GI_LAB:-target/debug/gi-lab}"
OUT="${OUT:-$(mktemp -d /tmp/gi-lab-readings.XXXXXX)}"
mkdir -p "$OUT"

# id, preset (presets/<preset>.ron), setting, value A (GI Lab's default), value B, and optionally
# overrides of the preset the setting needs to act (--set; comma-separated).
READINGS="
nguyen.thresholds            nguyen-hcb                     hcb.theta_max_deg           20              10
nguyen.d-max                 nguyen-hcb                     hcb.d_max_m                 0               0.26
nguyen.footprint-clamp       nguyen-hcb                     hcb.footprint_min_cos       0.01            0.0001
nguyen.cache-thresholds      nguyen-hcb-cached              hcb.incomplete_weight       0.1             0.5
nguyen.glossy-receiver       nguyen-hcb                     hcb.receiver                Glossy          DiffuseOnly
knecht.demodulated-filter    knecht-cornell-256             interleave.demodulate       true            false
knecht.albedo-mip            knecht-cornell-256             vpl.albedo_mip              4               0
knecht.distance-clamp        knecht-cornell-256             vpl.min_distance_m          0.1             1
knecht.budget-split          knecht-cornell-256             vpl.split_by_power          true            false
knecht.ism-depth-bias        knecht-cornell-256             ism.depth_bias              0.05            0.01
knecht.ism-normal-offset     knecht-cornell-256             ism.normal_offset           3               0
knecht.ism-eye-offset        knecht-cornell-256             ism.eye_offset              0.005           0
knecht.push-inside-surfaces  knecht-cornell-256             ism.push_behind             InsideSurfaces  Everywhere
knecht.splat-tangent-plane   knecht-cornell-256             ism.splat_depth             TangentPlane    PointDistance
knecht.bounce-shadow-test    knecht-multibounce             ism.bounce_test             PulledMaps      RawSplats
knecht.w-pos                 knecht-cornell-256             temporal.w_pos              300             30
knecht.merge-order           knecht-cornell-256             temporal.order              FilterThenMerge MergeThenFilter
gautron.border-cosine        gautron-ic-splatting           gautron.border_compensation CosineWeighted  Paper
gautron.weight-clamp         gautron-ic-splatting           gautron.weight_clamp        100             1000000
gautron.glossy-receiver      gautron-ic-splatting           gautron.receiver            Glossy          DiffuseOnly
ddgi.glossy-receiver         ddgi-probes                    ddgi.receiver               Glossy          DiffuseOnly     ddgi.infinite_bounces=false
ddgi.cold-start              ddgi-probes                    ddgi.running_mean_start     true            false           ddgi.infinite_bounces=false
ddgi.idle-probes             ddgi-probes                    ddgi.skip_inactive          true            false           ddgi.infinite_bounces=false
gautron.r-clamps             gautron-ic-splatting           gautron.r_clamps            true            false
gautron.in-front-tolerance   gautron-ic-splatting           gautron.in_front_tolerance  0.05            0
gautron.neighbour-clamping   gautron-ic-splatting           gautron.neighbour_clamping  true            false
gautron.creation-per-tile    gautron-ic-splatting           gautron.creation_tile_px    8               16
gautron.invalidation         gautron-ic-splatting           gautron.invalidation        Refresh         Drop
soler.vote-sigmas            soler-quarter-4-64             soler.vote_sigma_depth      0.05            10
soler.vote-radiance-power    soler-quarter-4-64             soler.vote_power            true            false
soler.vote-consistent        soler-quarter-4-64             soler.vote_consistent       true            false
soler.min-cos-beta           soler-quarter-4-64             soler.min_cos_beta          0.1             0.001
soler.upsample-weights       soler-quarter-4-64             soler.upsample_sigma_depth  0.1             10
soler.sender-diffuse         soler-quarter-4-64             soler.sender                Diffuse         ViewDependent
soler.glossy-variance        soler-quarter-4-64             soler.glossy_sharpness      0.25            1               soler.glossy_reflection=true
soler.glossy-min-power       soler-quarter-4-64             soler.glossy_min_power      16              0               soler.glossy_reflection=true
soler.temporal-a             soler-quarter-4-64             soler.temporal_a            0.85            0.5
soler.temporal-motion        soler-quarter-4-64             soler.temporal_motion_px    4               1000
soler.temporal-gloss         soler-quarter-4-64             soler.temporal_gloss        0.05            0
soler.temporal-reject        soler-quarter-4-64             soler.reject_depth          0.05            0.5
soler.temporal-history       soler-quarter-4-64             soler.temporal_history      Filtered        Raw
soler.temporal-order         soler-quarter-4-64             soler.temporal_quantity     Irradiance      Radiance
soler.voxel-slope-bias       soler-quarter-4-64-visibility  soler.voxel_slope_bias      0.5             0
soler.march-bias             soler-quarter-4-64-visibility  soler.march_bias_px         1.5             0.5
"

wanted=("$@")
known_ids=$(awk 'NF { print $1 }' <<<"$READINGS")
for id in "${wanted[@]}"; do
  grep -qx -- "$id" <<<"$known_ids" || { echo "readings-effects.sh: no reading '$id' with a setting; known: $(tr '\n' ' ' <<<"$known_ids")" >&2; exit 2; }
done

# The measured-effect cell from OUT/<id>/sweep.csv: FLIP and frame ms of both points, B/A.
cell() {
  local csv="$1" path="$2" a="$3" b="$4"
  awk -F, -v path="$path" -v a="$a" -v b="$b" '
    NR == 1 { for (i = 1; i <= NF; i++) { if ($i == path) p = i; if ($i == "flip") f = i; if ($i == "total_ms") t = i } next }
    { n++; flip[n] = $f; ms[n] = $t }
    END {
      if (n != 2 || !p || !f || !t) { print "measurement failed (see sweep.csv)"; exit }
      printf "`%s`: FLIP %.4f; `%s`: FLIP %.4f; frame time B/A %.2f\n", a, flip[1], b, flip[2], ms[2] / ms[1]
    }' "$csv"
}

printf '| id | preset | setting | measured effect |\n|---|---|---|---|\n' >"$OUT/effects.md"
while read -r id preset path a b extra; do
  [ -n "$id" ] || continue
  if [ ${#wanted[@]} -gt 0 ] && ! printf '%s\n' "${wanted[@]}" | grep -qx -- "$id"; then
    continue
  fi
  ref=()
  [ -f "$OUT/truth-$preset.exr" ] && ref=(--reference "$OUT/truth-$preset.exr")
  sets=() with=""
  if [ -n "$extra" ]; then
    IFS=, read -r -a overrides <<<"$extra"
    for o in "${overrides[@]}"; do sets+=(--set "$o"); with+=" with \`$o\`"; done
  fi
  echo "== $id: $preset, $path = $a / $b${extra:+ ($extra)}" >&2
  if nice -n 19 "$BIN" sweep --preset "presets/$preset.ron" "${sets[@]}" --param "$path=$a,$b" --size 256x256 \
      --frames 4 --flicker-frames 0 "${ref[@]}" --out "$OUT/$id" >"$OUT/$id.log" 2>&1; then
    [ -f "$OUT/truth-$preset.exr" ] || cp "$OUT/$id/reference.exr" "$OUT/truth-$preset.exr" 2>/dev/null || true
    effect=$(cell "$OUT/$id/sweep.csv" "$path" "$a" "$b")
  elif grep -q "no setting named" "$OUT/$id.log"; then
    effect="pending ($path is not in this binary)"
  else
    effect="measurement failed (see $OUT/$id.log)"
  fi
  printf '| `%s` | %s | `%s`: `%s` / `%s`%s | %s |\n' "$id" "$preset" "$path" "$a" "$b" "$with" "$effect" | tee -a "$OUT/effects.md"
done <<<"$READINGS"
echo "wrote $OUT/effects.md" >&2
