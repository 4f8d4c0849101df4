#!/bin/bash
# `lustre fit` over a measurement database in N shards on SLURM: an array job runs the shards
# (each task's SLURM_ARRAY_TASK_ID minus SLURM_ARRAY_TASK_MIN is its shard), and a job that
# depends on the whole array merges them. Submit from a login node:
#
#   deploy/slurm/fit-array.sh OUT_DIR MODEL SHARDS INPUT...
#   e.g. deploy/slurm/fit-array.sh /scratch/fits/sgd sgd 8 /scratch/merl/*.binary
#
# OUT_DIR must be on a file system every node sees. A shard whose inputs fail still exits 0
# (the failure is a row of the merged summary), so `afterok` holds; a resubmitted shard resumes
# from the fits already in OUT_DIR.
set -euo pipefail
if [ $# -lt 4 ]; then
  echo "usage: $0 OUT_DIR MODEL SHARDS INPUT..." >&2
  exit 2
fi
out=$1 model=$2 shards=$3
shift 3
mkdir -p "$out"
array=$(sbatch --parsable --job-name=lustre-fit --array="0-$((shards - 1))" \
  --cpus-per-task=4 --mem=4G --output="$out/slurm-%A_%a.log" \
  --wrap="lustre fit --model $model --shard-count $shards --jobs 4 --out '$out' $(printf "'%s' " "$@")")
sbatch --parsable --job-name=lustre-fit-merge --dependency="afterok:$array" \
  --output="$out/slurm-merge-%j.log" --wrap="lustre fit --merge --out '$out'"
