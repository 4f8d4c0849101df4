#!/usr/bin/env bash
# Renders the before/after frames of a refactor with binary $1 into $2 (reusing the bakes in
# $3 when given, else baking the Modern Hall and the Cornell box first): the built-in room
# (regular, CK, progressive), the Hall, the Cornell box on CPU and GPU, adaptive shading and
# `lustre demo`. Compare two output folders with `cmp` and, where EXR bytes differ, with
# `lustre render ... --compare-reference` (EXR bytes differ between runs; pixels do not).
set -u
B=$(realpath "$1"); O=$2; BAKES=${3:+$(realpath "$3")}
REPO=$(cd "$(dirname "$0")/.." && pwd)
S=$(realpath "${LUSTRE_SHARED:-$REPO/../shared/data}")
mkdir -p "$O"; cd "$O"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp/xdg-$(id -u)}; mkdir -p -m700 "$XDG_RUNTIME_DIR"
run() { name=$1; shift; /usr/bin/time -f "$name %e s" "$B" "$@" > "$name.log" 2>&1 || echo "FAIL $name"; }
if [ -z "$BAKES" ]; then
  run bake_hall bake $REPO/scenes/modern_hall.toml --out hall --texels-per-metre 4 --spp 8
  run bake_cornell bake $S/scenes/cornell_box/cornell_box.obj --out cornell --spp 8 --texels-per-metre 0.1
  BAKES=$O
fi
for dev in cpu gpu; do
  run room_${dev}_regular render --device $dev --size 128x96 --out room_${dev}_regular
  run room_${dev}_ck render --device $dev --size 128x96 --method ck --spp 4 --out room_${dev}_ck
  run room_${dev}_prog render --device $dev --size 128x96 --method progressive --frames 3 --out room_${dev}_prog
  run hall_${dev} render $BAKES/hall/scene.toml --device $dev --size 128x72 --out hall_${dev}
  run cornell_${dev} render $BAKES/cornell/scene.toml --device $dev --size 96x96 --out cornell_${dev}
done
run adaptive_cpu render --method adaptive --device cpu --size 96x72 --samples 8 --out adaptive_cpu
run adaptive_gpu render --method adaptive --device gpu --size 96x72 --samples 8 --out adaptive_gpu
run demo_cpu demo --cpu --size 96x72 --reference-spp 4 --out demo_cpu.png
run demo_gpu demo --size 96x72 --reference-spp 4 --out demo_gpu.png
