#!/usr/bin/env bash
# Renders one image on a Slurm cluster: a job array whose tasks each render a share of the passes
# (render-part.sbatch) into a shared folder, and a merge job (merge.sbatch) that runs when every
# task has succeeded (--dependency=afterok) and writes the image, bit for bit the one
# `photonmap render --passes N` makes in one process.
#
#   scripts/slurm/submit.sh --dir /shared/job1 --tasks 64 --passes 1024 scene.toml -o final.exr \
#       [--photonmap /shared/bin/photonmap] [--sbatch-arg --partition=render ...] \
#       [--merge-arg --png --merge-arg final.png] [-- render flags (--width, --integrator ...)]
#
# The folder must be visible to every node at the same path; the scene (and its meshes and
# textures) too. Prints the array's and the merge's job IDs. A task that failed (a node lost, a
# time limit) is rendered again by resubmit.sh, which gives the same part: a task's passes
# depend only on the seed and the pass indices.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
usage() { sed -n '2,15p' "$0" >&2; exit 2; }

dir='' tasks='' passes='' scene='' output='' photonmap=${PHOTONMAP:-photonmap}
sbatch_args=() merge_args=() render_args=()
while (($#)); do
    case $1 in
        --dir) dir=$2; shift 2 ;;
        --tasks) tasks=$2; shift 2 ;;
        --passes) passes=$2; shift 2 ;;
        --photonmap) photonmap=$2; shift 2 ;;
        --sbatch-arg) sbatch_args+=("$2"); shift 2 ;;
        --merge-arg) merge_args+=("$2"); shift 2 ;;
        -o|--output) output=$2; shift 2 ;;
        --) shift; render_args=("$@"); break ;;
        -h|--help) usage ;;
        -*) echo "submit.sh: unknown option $1" >&2; usage ;;
        *) [ -z "$scene" ] || { echo "submit.sh: one scene only ($scene, $1)" >&2; exit 2; }; scene=$1; shift ;;
    esac
done
if [ -z "$dir" ] || [ -z "$tasks" ] || [ -z "$passes" ] || [ -z "$scene" ] || [ -z "$output" ]; then usage; fi
[[ $tasks =~ ^[1-9][0-9]*$ && $passes =~ ^[1-9][0-9]*$ ]] \
    || { echo "submit.sh: --tasks and --passes must be positive integers" >&2; exit 2; }
((tasks <= passes)) || { echo "submit.sh: $tasks tasks for $passes passes: use at most one task a pass" >&2; exit 2; }
photonmap=$(command -v "$photonmap") || { echo "submit.sh: no photonmap binary ($photonmap)" >&2; exit 2; }

# NAME=( 'quoted' 'values' ), read back by `.` as the same words (none for an empty list).
array() {
    local name=$1 a
    shift
    printf '%s=(' "$name"
    for a in "$@"; do printf ' %q' "$a"; done
    printf ' )\n'
}
abs() { case $1 in /*) printf '%s' "$1" ;; *) printf '%s/%s' "$PWD" "$1" ;; esac; }
mkdir -p "$dir/parts" "$dir/logs"
dir=$(cd "$dir" && pwd)
{
    printf 'PHOTONMAP=%q\nSCENE=%q\nOUTPUT=%q\nPASSES=%q\nTASKS=%q\n' \
        "$(abs "$photonmap")" "$(abs "$scene")" "$(abs "$output")" "$passes" "$tasks"
    array RENDER_ARGS "${render_args[@]}"
    array MERGE_ARGS "${merge_args[@]}"
    array SBATCH_ARGS "${sbatch_args[@]}"
} > "$dir/job.env"

# The array, then the merge, waiting on it.
exec "$here/resubmit.sh" "$dir" "0-$((tasks - 1))"
