#!/bin/bash
# `lustre fit` over a measurement database in N shards on SLURM: an array job runs the shards
# (array task K runs shard K/N), and a job that depends on the whole array merges them. Submit
# from a login node:
#
#   deploy/slurm/fit-array.sh OUT_DIR MODEL SHARDS INPUT...
#   e.g. LUSTRE_CPUS=4 deploy/slurm/fit-array.sh /scratch/fits/sgd sgd 8 /scratch/merl/*.binary
#
# Prints the array's job id, then the merge's. OUT_DIR must be on a file system every node sees.
# Resources per task come from the environment (see common.sh): LUSTRE_CPUS (default 1: the
# fits run in parallel on that many threads), LUSTRE_MEM (default 2G), LUSTRE_TIME,
# LUSTRE_PARTITION, LUSTRE_SBATCH_ARGS, LUSTRE, LUSTRE_TASKS. A request no node can satisfy, or
# more shards than inputs, is refused before anything is submitted. A shard whose inputs fail
# still exits 0 (the failure is a row of the merged summary), so `afterok` holds; a lost or
# cancelled task is resubmitted alone (`LUSTRE_TASKS=K`, same arguments) and resumes from the
# fits already in OUT_DIR.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
. "$here/common.sh"
if [ $# -lt 4 ]; then
  echo "usage: $0 OUT_DIR MODEL SHARDS INPUT..." >&2
  exit 2
fi
out=$1 model=$2 shards=$3
shift 3
lustre_check_shards "$shards"
lustre_resources
# More shards than inputs is refused before submitting (an input such as nbrdf:FILE#* expands to
# several; then the tasks check).
case "$*" in
*'#*'*) ;;
*)
  if [ "$shards" -gt $# ]; then
    echo "$0: $shards shards for $# inputs: shards $# to $((shards - 1)) would fit nothing; use at most $# shards; nothing was submitted" >&2
    exit 1
  fi
  ;;
esac
mkdir -p "$out"
exe=$(lustre_quote "$lustre")
array=$(lustre_submit --job-name=lustre-fit --array="$tasks" --output="$out/slurm-%A_%a.log" <<EOF
#!/bin/bash
set -euo pipefail
$exe fit --model $(lustre_quote "$model") --jobs $cpus --out $(lustre_quote "$out") \
  --shard "\$SLURM_ARRAY_TASK_ID/$shards" -- $(lustre_quote "$@")
EOF
)
echo "$array"
lustre_submit --job-name=lustre-fit-merge --dependency="afterok:$array" --kill-on-invalid-dep=yes \
  --output="$out/slurm-merge-%j.log" <<EOF
#!/bin/bash
set -euo pipefail
$exe fit --merge --out $(lustre_quote "$out")
EOF
