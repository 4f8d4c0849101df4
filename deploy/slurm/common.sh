# Shared by bake-array.sh and fit-array.sh (sourced, not run): the resources of a task from the
# environment, checked against the cluster before anything is submitted.
#
#   LUSTRE_CPUS       CPUs per task (default 1): lustre's threads (RAYON_NUM_THREADS, fit --jobs)
#   LUSTRE_MEM        memory per task, as sbatch's --mem takes it (default 2G)
#   LUSTRE_TIME       time limit per task, as sbatch's --time takes it (default: the partition's)
#   LUSTRE_PARTITION  the partition (default: the cluster's default partition)
#   LUSTRE_SBATCH_ARGS  more sbatch options, split at spaces (e.g. "--account=lab --qos=long")
#   LUSTRE            the lustre executable on the nodes (default: lustre)
#   LUSTRE_TASKS      the array indices to submit (default: all, 0-(SHARDS-1)); e.g. "3" or
#                     "1,4" to resubmit lost shards

# Checks SHARDS: a whole number ≥ 1.
lustre_check_shards() {
  case "$1" in
  '' | *[!0-9]* | 0 | 0*)
    echo "$0: SHARDS must be a whole number ≥ 1 (got '$1')" >&2
    exit 2
    ;;
  esac
}

# Words quoted for bash, separated by spaces.
lustre_quote() {
  local out="" w
  for w in "$@"; do out+=$(printf '%q ' "$w"); done
  printf '%s' "${out% }"
}

# Sets cpus, lustre, tasks and res (the sbatch resource options) from the environment, and asks
# SLURM (sbatch --test-only) whether a node can run such a task; refuses with its reason if not.
lustre_resources() {
  cpus=${LUSTRE_CPUS:-1}
  case "$cpus" in
  '' | *[!0-9]* | 0)
    echo "$0: LUSTRE_CPUS must be a whole number ≥ 1 (got '$cpus')" >&2
    exit 2
    ;;
  esac
  lustre=${LUSTRE:-lustre}
  tasks=${LUSTRE_TASKS:-0-$((shards - 1))}
  local i
  for i in $(echo "${tasks%%%*}" | tr ',-' '  ' | sed 's/:[0-9]*//g'); do
    case "$i" in
    *[!0-9]*)
      echo "$0: LUSTRE_TASKS '$tasks' is not a list of array indices (e.g. 3 or 1,4 or 0-7)" >&2
      exit 2
      ;;
    esac
    if [ "$i" -ge "$shards" ]; then
      echo "$0: LUSTRE_TASKS '$tasks' names shard $i, but there are $shards shards (0 to $((shards - 1)))" >&2
      exit 2
    fi
  done
  res=(--cpus-per-task="$cpus" --mem="${LUSTRE_MEM:-2G}")
  [ -z "${LUSTRE_TIME:-}" ] || res+=(--time="$LUSTRE_TIME")
  [ -z "${LUSTRE_PARTITION:-}" ] || res+=(--partition="$LUSTRE_PARTITION")
  # shellcheck disable=SC2206 # split at spaces on purpose
  [ -z "${LUSTRE_SBATCH_ARGS:-}" ] || res+=($LUSTRE_SBATCH_ARGS)
  local why
  if ! why=$(sbatch --test-only "${res[@]}" --wrap=true 2>&1); then
    local nodes
    nodes=$(sinfo -h ${LUSTRE_PARTITION:+-p "$LUSTRE_PARTITION"} -o '%c CPUs, %m MB memory, time limit %l' 2>/dev/null | sort -u | paste -sd ';' -)
    echo "$0: no node can run a task with ${res[*]}: ${why##*error: }" >&2
    echo "  the partition's nodes: ${nodes:-unknown}" >&2
    echo "  set LUSTRE_CPUS, LUSTRE_MEM, LUSTRE_TIME or LUSTRE_PARTITION to fit them; nothing was submitted" >&2
    exit 1
  fi
  lustre_check_time
}

# Seconds in a SLURM time ("minutes", "minutes:seconds", "hours:minutes:seconds", "days-hours",
# "days-hours:minutes", "days-hours:minutes:seconds"); -1 for no limit; empty if unreadable.
lustre_seconds() {
  local t=$1 d=0 h=0 m=0 sec=0
  case "$t" in
  infinite | UNLIMITED | INFINITE) echo -1; return ;;
  *[!0-9:-]* | '') return ;;
  esac
  local IFS=:
  if [[ $t == *-* ]]; then
    d=${t%%-*}
    read -r -a p <<<"${t#*-}"
    case ${#p[@]} in
    1) h=${p[0]} ;;
    2) h=${p[0]} m=${p[1]} ;;
    3) h=${p[0]} m=${p[1]} sec=${p[2]} ;;
    *) return ;;
    esac
  else
    read -r -a p <<<"$t"
    case ${#p[@]} in
    1) m=${p[0]} ;;
    2) m=${p[0]} sec=${p[1]} ;;
    3) h=${p[0]} m=${p[1]} sec=${p[2]} ;;
    *) return ;;
    esac
  fi
  echo $(((10#$d * 24 + 10#$h) * 3600 + 10#$m * 60 + 10#$sec))
}

# Refuses LUSTRE_TIME above the partition's time limit (sbatch --test-only accepts it, and the
# job would wait forever with reason PartitionConfig).
lustre_check_time() {
  [ -n "${LUSTRE_TIME:-}" ] || return 0
  local want limit part
  want=$(lustre_seconds "$LUSTRE_TIME")
  if [ -n "${LUSTRE_PARTITION:-}" ]; then
    part=$LUSTRE_PARTITION
    limit=$(sinfo -h -p "$part" -o %l 2>/dev/null | head -1)
  else
    read -r part limit < <(sinfo -h -o '%P %l' 2>/dev/null | grep '^[^ ]*\* ' | head -1)
    part=${part%\*}
  fi
  limit=$(lustre_seconds "${limit:-}")
  if [ -n "$want" ] && [ -n "$limit" ] && [ "$limit" -ge 0 ] && [ "$want" -gt "$limit" ]; then
    echo "$0: LUSTRE_TIME=$LUSTRE_TIME is longer than partition $part allows ($(sinfo -h -p "$part" -o %l | head -1)); nothing was submitted" >&2
    exit 1
  fi
}

# sbatch with the resources, the job script on standard input; prints the job id.
lustre_submit() {
  sbatch --parsable "${res[@]}" "$@"
}
