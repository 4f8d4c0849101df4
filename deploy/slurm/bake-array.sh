#!/bin/bash
# `lustre bake` of one scene in N shards on SLURM: an array job bakes the tiles (each task's
# SLURM_ARRAY_TASK_ID minus SLURM_ARRAY_TASK_MIN is its shard), and a job that depends on the
# whole array assembles them. Submit from a login node:
#
#   deploy/slurm/bake-array.sh SCENE OUT_DIR SHARDS [BAKE OPTION...]
#   e.g. deploy/slurm/bake-array.sh /scratch/hall/scene.xml /scratch/hall/bake 16 --spp 1024
#
# OUT_DIR must be on a file system every node sees. A resubmitted shard resumes from its tiles.
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: $0 SCENE OUT_DIR SHARDS [BAKE OPTION...]" >&2
  exit 2
fi
scene=$1 out=$2 shards=$3
shift 3
mkdir -p "$out"
opts=$(printf "'%s' " "$@")
array=$(sbatch --parsable --job-name=lustre-bake --array="0-$((shards - 1))" \
  --cpus-per-task=8 --mem=8G --output="$out/slurm-%A_%a.log" \
  --wrap="lustre bake '$scene' --out '$out' $opts --shard-count $shards")
sbatch --parsable --job-name=lustre-bake-merge --dependency="afterok:$array" \
  --cpus-per-task=8 --mem=8G --output="$out/slurm-merge-%j.log" \
  --wrap="lustre bake '$scene' --out '$out' $opts --merge"
