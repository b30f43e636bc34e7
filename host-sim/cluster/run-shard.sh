#!/usr/bin/env bash
# One shard of a tetherbot campaign. The scheduler decides where and when this runs (Slurm job array task,
# Kubernetes Indexed Job pod); this script only turns its index into tetherbot's arguments.
#
#   run-shard.sh KIND K N OUT [SCENARIO] [-- EXTRA...]
#
#   KIND      campaign (tetherbot campaign: Table I planning trials) or mission (tetherbot mission --seeds)
#   K         this shard's 0-based index: $SLURM_ARRAY_TASK_ID or $JOB_COMPLETION_INDEX
#   N         the number of shards (the array's size, the Job's completions)
#   OUT       a directory every node sees (the shards write below it, the merge reads there)
#   SCENARIO  campaign: a name from host-sim/scenarios/ or a .toml path (required);
#             mission: a .toml path, or empty for the embedded default
#   EXTRA     more options, the same for every shard, e.g. --trials 100 (campaign) or --seeds 20 --seed 101 (mission)
#
# Trial (mission) i goes to shard i mod N and keeps its seed; run-merge.sh joins the N shards into the file the
# unsharded run writes, byte for byte. TETHERBOT names the binary (default: tetherbot on PATH); THREADS the worker
# threads (default: SLURM_CPUS_PER_TASK, else the machine's cores).
set -euo pipefail
usage() { echo "usage: $0 campaign|mission K N OUT [SCENARIO] [-- EXTRA...]" >&2; exit 2; }
[ $# -ge 4 ] || usage
kind=$1 k=$2 n=$3 out=$4
shift 4
scenario=""
if [ $# -gt 0 ] && [ "$1" != "--" ]; then scenario=$1; shift; fi
if [ $# -gt 0 ] && [ "$1" = "--" ]; then shift; fi
bin=${TETHERBOT:-tetherbot}
threads=()
if [ -n "${THREADS:-${SLURM_CPUS_PER_TASK:-}}" ]; then threads=(--threads "${THREADS:-${SLURM_CPUS_PER_TASK:-}}"); fi
case "$kind" in
  campaign)
    [ -n "$scenario" ] || { echo "$0: a campaign needs a SCENARIO" >&2; exit 2; }
    exec "$bin" campaign "$scenario" --shard "$k/$n" "${threads[@]}" --out "$out/shard-$k" "$@"
    ;;
  mission)
    mkdir -p "$out/shards"
    exec "$bin" mission ${scenario:+"$scenario"} --shard "$k/$n" "${threads[@]}" --out "$out/shards" --quiet "$@"
    ;;
  *) usage ;;
esac
