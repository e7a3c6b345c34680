#!/bin/bash
# One shard of a ringmesh sweep per Slurm array task: `sbatch --array=0-(N-1)
# array.sh COMMAND SCENE [ARGS…] -o DIR` runs `ringmesh COMMAND SCENE [ARGS…]
# -o DIR --shard I/N` with I = $SLURM_ARRAY_TASK_ID and N =
# $SLURM_ARRAY_TASK_COUNT (shards count from 0, as the array does). COMMAND is
# one that takes --shard: front, study or budget. Run from the repository
# root (the job's working directory is where sbatch was called).
#SBATCH --job-name=ringmesh-shard
#SBATCH --cpus-per-task=2
#SBATCH --time=01:00:00
set -euo pipefail
: "${SLURM_ARRAY_TASK_ID:?array.sh runs as a Slurm array task (sbatch --array=0-(N-1))}"
exec "${RINGMESH:-./target/release/ringmesh}" "$@" \
    --shard "${SLURM_ARRAY_TASK_ID}/${SLURM_ARRAY_TASK_COUNT}"
