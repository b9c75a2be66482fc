#!/usr/bin/env bash
# A figure of one scene side by side: the one-bounce path-traced truth, then each preset as a
# "before" binary and this checkout's binary render it (128² unless SIZE, paused, FRAMES
# frames), all tone-mapped alike (x/(1+x), sRGB), captioned with their FLIP against the truth;
# writes docs/screenshots/NAME.png and NAME.md (the commit, size, view and commands).
# Needs ImageMagick's montage (apt-get install imagemagick).
#
# Usage: scripts/side-by-side.sh NAME BEFORE_BIN "SCENE ARGS" PRESET[:FRAMES] ...
#   e.g. scripts/side-by-side.sh issue51-chair /tmp/gi-lab-old "--scene tests/data/chair-behind.glb" nguyen-hcb gautron-ic-splatting
#   BEFORE_BIN "-" leaves the before column out.
set -euo pipefail
cd "$(dirname "$0")/.."
name=$1; before=$2; args=$3; shift 3
SIZE="${SIZE:-128x128}"; SPP="${SPP:-2048}"; FRAMES="${FRAMES:-16}"
AFTER="${GI_LAB:-target/release/gi-lab}"
[ -x "$AFTER" ] || cargo build --release -p gi-lab
work=$(mktemp -d /tmp/gi-lab-side.XXXXXX)
# shellcheck disable=SC2086
"$AFTER" reference $args --size "$SIZE" --spp "$SPP" --bounces 1 --out "$work/truth.exr" > "$work/truth.log" 2>&1
view=$(grep -m1 '^view:' "$work/truth.log" | sed 's/^view: //' || true)
tiles=(-label "path-traced truth ($SPP spp)" "$work/truth.png")
for item in "$@"; do
  preset=${item%%:*}; frames=$FRAMES; [ "$item" != "$preset" ] && frames=${item#*:}
  for which in before after; do
    bin=$AFTER; [ "$which" = before ] && bin=$before
    [ "$bin" = "-" ] && continue
    out="$work/$preset-$which"
    # shellcheck disable=SC2086
    "$bin" render --preset "presets/$preset.ron" $args --size "$SIZE" --frames "$frames" --paused --buffer final.hdr --out "$out" > /dev/null 2>&1
    flip=$("$AFTER" compare "$out/final.hdr.exr" "$work/truth.exr" | grep -m1 -o 'FLIP *[0-9.]*' | awk '{print $2}')
    tiles+=(-label "$preset\n$which: FLIP $(printf %.3f "$flip")" "$out/final.hdr.png")
  done
done
mkdir -p docs/screenshots
montage "${tiles[@]}" -tile "$(( (${#tiles[@]} / 3) ))x1" -geometry 160x160+3+3 -pointsize 10 "$work/montage.png"
convert "$work/montage.png" -strip "docs/screenshots/$name.png"
{
  echo "# docs/screenshots/$name.png"
  echo
  echo "Made by \`scripts/side-by-side.sh $name BEFORE '$args' $*\` at commit $(git rev-parse --short HEAD) ($(date -u +%Y-%m-%d)), $SIZE, $FRAMES frames paused (or PRESET:FRAMES), truth $SPP spp one bounce. View: ${view:-as the scene opens}. Before: \`$before\`."
} > "docs/screenshots/$name.md"
echo "wrote docs/screenshots/$name.png"
