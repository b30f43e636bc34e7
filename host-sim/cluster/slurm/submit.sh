#!/usr/bin/env bash
# Submits a tetherbot campaign to Slurm as a job array of N shards plus a merge job that waits for them:
#
#   host-sim/cluster/slurm/submit.sh KIND N OUT [SCENARIO] [-- EXTRA...]
#   host-sim/cluster/slurm/submit.sh campaign 4 "$PWD/runs/t3" ledge_test3 -- --trials 100
#   host-sim/cluster/slurm/submit.sh mission 4 "$PWD/runs/crater" host-sim/scenarios/mission_crater_rocks.toml -- --seeds 20 --seed 101
#
# OUT must be on a file system every node sees. The binary is TETHERBOT (default: target/release/tetherbot of this
# checkout; build it first: cargo build --release -p host-sim --bin tetherbot). Slurm does the scheduling: the
# array runs the shards (SLURM_ARRAY_TASK_ID = K), --dependency=afterany starts the merge when all have ended.
# Extra sbatch options (partition, account) go in SBATCH_* environment variables, which sbatch reads itself.
set -euo pipefail
[ $# -ge 3 ] || { sed -n '2,11p' "$0" >&2; exit 2; }
kind=$1 n=$2 out=$3
shift 3
case "$n" in ''|*[!0-9]*|0) echo "$0: N must be a whole number >= 1, got '$n'" >&2; exit 2 ;; esac
here=$(cd "$(dirname "$0")" && pwd)
export TETHERBOT_CLUSTER=${TETHERBOT_CLUSTER:-$(dirname "$here")}
export TETHERBOT=${TETHERBOT:-$(cd "$here/../../.." && pwd)/target/release/tetherbot}
[ -x "$TETHERBOT" ] || { echo "$0: no binary at $TETHERBOT: build it (cargo build --release -p host-sim --bin tetherbot) or set TETHERBOT" >&2; exit 2; }
mkdir -p "$out"
shards=$(sbatch --parsable --array=0-$((n - 1)) --export=ALL "$here/shard.sbatch" "$kind" "$n" "$out" "$@")
shards=${shards%%;*}
merge=$(sbatch --parsable --dependency=afterany:"$shards" --export=ALL "$here/merge.sbatch" "$kind" "$n" "$out")
echo "submitted shards as job array $shards (0-$((n - 1))) and the merge as job ${merge%%;*}: results in $out/merged"
