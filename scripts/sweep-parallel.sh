#!/usr/bin/env bash
# A refract sweep as N shards with GNU parallel on one machine (or `--sshloginfile` for
# several), then the merged report. Usage: scripts/sweep-parallel.sh SWEEP.toml [N]
set -euo pipefail
SWEEP=${1:?usage: sweep-parallel.sh SWEEP.toml [SHARDS]}
N=${2:-4}
REFRACT=${REFRACT:-target/release/refract}
seq 0 $((N - 1)) | parallel --halt never "$REFRACT" sweep "$SWEEP" --shard {}/"$N" \
    --out sweep-out/shard{} --cache sweep-cache
"$REFRACT" report sweep-out/shard* --out report
echo "open report/index.html"
