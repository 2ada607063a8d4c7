#!/usr/bin/env bash
# A refract sweep as a Slurm job array: one shard per array task, all writing into one shared
# output directory (job results are written atomically, so shards never clash), references
# shared through a cache directory. Edit the sweep file, the paths and the array size, then:
#   sbatch scripts/sweep-slurm.sh
# and, when all tasks are done (or to look at partial results at any time):
#   refract report "$OUT" --out report
#SBATCH --job-name=refract-sweep
#SBATCH --array=0-15
#SBATCH --cpus-per-task=4
#SBATCH --time=02:00:00
set -euo pipefail
SWEEP=${SWEEP:-sweeps/nearby-ior.toml}
OUT=${OUT:-sweep-out}
CACHE=${CACHE:-sweep-cache}
REFRACT=${REFRACT:-target/release/refract}
export RAYON_NUM_THREADS=${SLURM_CPUS_PER_TASK:-4}
"$REFRACT" sweep "$SWEEP" --shard "$SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT" \
    --out "$OUT" --cache "$CACHE"
