#!/usr/bin/env bash
# Submits tasks of a job made by submit.sh, and a new merge job that waits for them:
#
#   scripts/slurm/resubmit.sh DIR            # every task whose part is missing (failed, killed)
#   scripts/slurm/resubmit.sh DIR 3,7-9      # these tasks (Slurm's --array syntax)
#
# A task renders the same passes whatever attempt it is, so its part is the same bit for bit. The
# merge job left waiting on a failed array (its dependency can no longer be met) is cancelled.
# Prints the array's and the merge's job IDs.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
dir=${1:?usage: resubmit.sh DIR [TASKS]}
dir=$(cd "$dir" && pwd)
# shellcheck disable=SC1091
. "$dir/job.env"
indices=${2:-}
if [ -z "$indices" ]; then
    missing=()
    for ((i = 0; i < TASKS; i++)); do
        [ -f "$(printf '%s/parts/part-%05d.exr' "$dir" "$i")" ] || missing+=("$i")
    done
    ((${#missing[@]})) || { echo "resubmit.sh: every part is there; nothing to do" >&2; exit 0; }
    indices=$(IFS=,; echo "${missing[*]}")
fi
if [ -f "$dir/merge.jobid" ]; then
    scancel "$(cat "$dir/merge.jobid")" 2>/dev/null || true
fi
array=$(sbatch --parsable "${SBATCH_ARGS[@]}" --array="$indices" \
    --output="$dir/logs/part-%a.out" --export=ALL,PHOTONMAP_JOB_DIR="$dir" \
    "$here/render-part.sbatch")
array=${array%%;*}
merge=$(sbatch --parsable "${SBATCH_ARGS[@]}" --dependency=afterok:"$array" \
    --output="$dir/logs/merge.out" --export=ALL,PHOTONMAP_JOB_DIR="$dir" \
    "$here/merge.sbatch")
merge=${merge%%;*}
echo "$array" > "$dir/array.jobid"
echo "$merge" > "$dir/merge.jobid"
echo "array $array ($indices) merge $merge"
