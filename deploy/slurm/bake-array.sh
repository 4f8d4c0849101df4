#!/bin/bash
# `lustre bake` of one scene in N shards on SLURM: an array job bakes the tiles (array task K
# runs shard K/N), and a job that depends on the whole array assembles them. Submit from a login
# node:
#
#   deploy/slurm/bake-array.sh SCENE OUT_DIR SHARDS [BAKE OPTION...]
#   e.g. LUSTRE_CPUS=16 LUSTRE_MEM=16G deploy/slurm/bake-array.sh /scratch/hall/scene.xml \
#          /scratch/hall/bake 16 --spp 1024
#
# Prints the array's job id, then the merge's. OUT_DIR must be on a file system every node sees.
# Resources per task come from the environment (every one optional; see common.sh):
#   LUSTRE_CPUS (default 1), LUSTRE_MEM (default 2G), LUSTRE_TIME (default: the partition's),
#   LUSTRE_PARTITION, LUSTRE_SBATCH_ARGS (more sbatch options), LUSTRE (the executable,
#   default `lustre`), LUSTRE_TASKS (array indices to submit, default all: `0-(SHARDS-1)`).
# A request no node can satisfy, or more shards than the atlas has tiles, is refused before
# anything is submitted. A lost or cancelled task: resubmit just it (`LUSTRE_TASKS=3
# deploy/slurm/bake-array.sh …` with the same arguments); it resumes from its tiles, and the new
# merge job waits for it (the first merge job is cancelled by SLURM, its dependency being
# unsatisfiable).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
. "$here/common.sh"
if [ $# -lt 3 ]; then
  echo "usage: $0 SCENE OUT_DIR SHARDS [BAKE OPTION...]" >&2
  exit 2
fi
scene=$1 out=$2 shards=$3
shift 3
lustre_check_shards "$shards"
lustre_resources
# The scene, the options and the shard count checked here first (`lustre bake --plan` loads the
# scene and builds its atlas, writing nothing).
if command -v "$lustre" >/dev/null 2>&1; then
  if ! "$lustre" bake "$scene" --out "$out" "$@" --shard "0/$shards" --plan >&2; then
    echo "$0: nothing was submitted" >&2
    exit 1
  fi
else
  echo "$0: note: $lustre is not on this node's PATH; the scene and shard count are checked by the tasks" >&2
fi
mkdir -p "$out"
opts=$(lustre_quote "$@")
bake="RAYON_NUM_THREADS=$cpus $(lustre_quote "$lustre") bake $(lustre_quote "$scene") --out $(lustre_quote "$out") $opts"
array=$(lustre_submit --job-name=lustre-bake --array="$tasks" --output="$out/slurm-%A_%a.log" <<EOF
#!/bin/bash
set -euo pipefail
$bake --shard "\$SLURM_ARRAY_TASK_ID/$shards"
EOF
)
echo "$array"
lustre_submit --job-name=lustre-bake-merge --dependency="afterok:$array" --kill-on-invalid-dep=yes \
  --output="$out/slurm-merge-%j.log" <<EOF
#!/bin/bash
set -euo pipefail
$bake --merge
EOF
