#!/usr/bin/env bash
# The automatic real-time set-up against converged references, before and after: the Modern
# Hall from its XML (no hints) and with the hand-written hints, the built-in room with its hints
# and with the automatic set-up, the Cornell box, the sunroom (scripts/sunroom.py) and the
# sunroom on a vast site (sunroom.py --site), on the CPU frame. Every log and frame lands in
# OUT (default /tmp/setup-study).
#
#   scripts/setup_study.sh [LUSTRE] [OUT] [SPP]
set -euo pipefail
BIN=${1:-target/release/lustre}
OUT=${2:-/tmp/setup-study}
SPP=${3:-4096}
DATA=../shared/data/scenes
mkdir -p "$OUT"
ref() { # NAME SCENE SIZE
  [ -f "$OUT/ref-$1.exr" ] || "$BIN" reference ${2:+"$2"} --size "$3" --spp "$SPP" --out "$OUT/ref-$1.exr" 2>&1 | tee "$OUT/ref-$1.log"
}
frame() { # NAME SIZE SCENE... (the rest is passed to render)
  local name=$1 size=$2; shift 2
  /usr/bin/time -f "wall %e s" "$BIN" render "$@" --size "$size" --device cpu --samples 16 \
    --out "$OUT/$name" --compare-reference "$OUT/ref-${name%%-*}.exr" 2>&1 | tee "$OUT/$name.log"
}
ref hall "$DATA/modern_hall/mitsuba/scene.xml" 192x108
ref room "" 192x108
ref cornell "$DATA/cornell_box/cornell_box.obj" 160x160
ref sunroom scenes/sunroom/scene.xml 192x144
ref site scenes/sunroom/site.xml 192x144
# The Hall: bakes of the XML (automatic set-up, and none: what happened before) and of the
# hand-written hints (alone, and with the automatic set-up around them).
for v in auto manual; do
  [ -f "$OUT/bake-hall-xml-$v/scene.toml" ] || /usr/bin/time -f "wall %e s" "$BIN" bake \
    "$DATA/modern_hall/mitsuba/scene.xml" --out "$OUT/bake-hall-xml-$v" --transport full \
    --spp 64 --bounces 16 --texels-per-metre 8 --setup "$v" 2>&1 | tee "$OUT/bake-hall-xml-$v.log"
  [ -f "$OUT/bake-hall-hints-$v/scene.toml" ] || /usr/bin/time -f "wall %e s" "$BIN" bake \
    scenes/modern_hall.toml --out "$OUT/bake-hall-hints-$v" --transport full \
    --spp 64 --bounces 16 --texels-per-metre 8 --setup "$v" 2>&1 | tee "$OUT/bake-hall-hints-$v.log"
done
frame hall-xml-none 192x108 "$OUT/bake-hall-xml-manual/scene.toml"
frame hall-xml-auto 192x108 "$OUT/bake-hall-xml-auto/scene.toml"
frame hall-hints 192x108 "$OUT/bake-hall-hints-manual/scene.toml"
frame hall-hints+auto 192x108 "$OUT/bake-hall-hints-auto/scene.toml"
# The built-in room: its hand-written hints, then the automatic set-up in their place.
frame room-hints 192x108
frame room-auto 192x108 --auto-setup
# The Cornell box and the sunroom, baked on first use (the automatic set-up), and the sunroom
# without a set-up (the environment only: what happened before).
frame cornell-auto 160x160 "$DATA/cornell_box/cornell_box.obj"
frame sunroom-auto 192x144 scenes/sunroom/scene.xml
# The sunroom on a 2 km ground plane (scripts/sunroom.py --site): no free-space cell fits the
# room, so its room probe stands at the camera.
frame site-auto 192x144 scenes/sunroom/site.xml
[ -f "$OUT/bake-sunroom-manual/scene.toml" ] || "$BIN" bake scenes/sunroom/scene.xml \
  --out "$OUT/bake-sunroom-manual" --transport full --spp 64 --texels-per-metre 16 \
  --bounces 8 --setup manual 2>&1 | tee "$OUT/bake-sunroom-manual.log"
frame sunroom-none 192x144 "$OUT/bake-sunroom-manual/scene.toml"
grep -H "against" "$OUT"/*.log
