#!/usr/bin/env bash
# Slurm array job: analyse a study in N shards, one per array task, then merge.
#
#   sbatch --array=1-8 scripts/slurm/study-array.sh /data/footage out/study
#   # when every task has finished:
#   eulerdisk merge out/study/shard-* -o out/study
#
# Each task analyses every N-th clip (deterministic: clips sorted by path), writes
# out/study/shard-K/ atomically, and reuses unchanged results on a rerun
# (--resume), so a task that hit its time limit can simply be resubmitted. A task
# whose shard has failed clips exits with status 2 (Slurm shows it as failed); its
# report lists them, and merge still combines it (and also exits 2).
#SBATCH --job-name=eulerdisk-study
#SBATCH --cpus-per-task=4
#SBATCH --mem=4G
#SBATCH --time=01:00:00
#SBATCH --output=eulerdisk-%A_%a.log
set -euo pipefail

root=${1:?usage: study-array.sh FOOTAGE_ROOT OUT}
out=${2:?usage: study-array.sh FOOTAGE_ROOT OUT}
k=${SLURM_ARRAY_TASK_ID:?run with sbatch --array=1-N}
n=${SLURM_ARRAY_TASK_COUNT:?run with sbatch --array=1-N}

# Plain log lines (no progress bar) go to the Slurm log.
RAYON_NUM_THREADS=${SLURM_CPUS_PER_TASK:-1} \
  eulerdisk study "$root" -o "$out/shard-$k" --shard "$k/$n" --resume
