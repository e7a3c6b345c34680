#!/bin/bash
# Submits a sharded ringmesh sweep to Slurm: N array tasks (array.sh), then
# `ringmesh merge DIR` as a job that starts only once every shard succeeded.
#
#   scripts/slurm/submit.sh N DIR COMMAND SCENE [ARGS…]
#
# e.g. scripts/slurm/submit.sh 8 runs/realistic-26m budget problems/realistic-26m.toml --samples 1000
# Prints the merge job's id (wait on it with `scontrol show job ID`). The
# tasks' logs go to $LOGS (default runs/slurm-logs), extra sbatch options
# (partition, account, time) in $SBATCH_OPTIONS.
set -euo pipefail
if [ $# -lt 4 ]; then
    echo "usage: $0 N DIR COMMAND SCENE [ARGS…]" >&2
    exit 2
fi
shards=$1 dir=$2
shift 2
case $shards in
    '' | *[!0-9]* | 0) echo "$0: N = '$shards' is not a positive number of shards" >&2; exit 2 ;;
esac
here=$(dirname "$0")
ringmesh=${RINGMESH:-./target/release/ringmesh}
logs=${LOGS:-runs/slurm-logs}
mkdir -p "$logs"
# shellcheck disable=SC2086 # SBATCH_OPTIONS is a list of options
array=$(sbatch --parsable ${SBATCH_OPTIONS:-} --array=0-$((shards - 1)) \
    --output="$logs/shard-%A_%a.out" \
    --export=ALL,RINGMESH="$ringmesh" \
    "$here/array.sh" "$@" -o "$dir")
# shellcheck disable=SC2086
sbatch --parsable ${SBATCH_OPTIONS:-} --job-name=ringmesh-merge \
    --dependency=afterok:"${array%%;*}" --kill-on-invalid-dep=yes \
    --output="$logs/merge-%j.out" \
    --wrap "exec '$ringmesh' merge '$dir' -o '$dir'"
