#!/usr/bin/env bash
# A Slurm job array: one `vkbrdf eval --shard K/N` per array task, then one merge.
#   sbatch --array=1-16 examples/shards/slurm.sh            # the parts
#   sbatch --dependency=afterok:<JOBID> --wrap 'vkbrdf merge -o brdf.npy parts/part-*.npy'
#SBATCH --job-name=vkbrdf-eval
#SBATCH --cpus-per-task=4
#SBATCH --mem=2G
set -euo pipefail
N=${SLURM_ARRAY_TASK_MAX:?run as an array job}
K=${SLURM_ARRAY_TASK_ID:?run as an array job}
mkdir -p parts
vkbrdf eval -m materials.toml -i tuples.npy -o "parts/part-$K.npy" --shard "$K/$N" --max-memory 1GiB
