#!/usr/bin/env bash
# Joins the N shards that run-shard.sh wrote below OUT into OUT/merged: the files the unsharded run writes (a
# campaign's results.json, results.csv, paths.svg; a mission campaign's <name>-campaign.json), byte for byte, plus
# the shards' timing. tetherbot refuses (exit 2, with the reason) missing or duplicate shards, shards of different
# campaigns and corrupt files, so run this after every shard has ended, whatever their exit status.
#
#   run-merge.sh KIND N OUT        (FORCE=1 replaces an earlier merge's files)
set -euo pipefail
[ $# -eq 3 ] || { echo "usage: $0 campaign|mission N OUT" >&2; exit 2; }
kind=$1 n=$2 out=$3
bin=${TETHERBOT:-tetherbot}
shopt -s nullglob
case "$kind" in
  campaign)
    files=("$out"/shard-*/results.json)
    [ ${#files[@]} -gt 0 ] || { echo "$0: no $out/shard-*/results.json: did the shards run?" >&2; exit 2; }
    exec "$bin" campaign merge ${FORCE:+--force} "$out/merged" "${files[@]}"
    ;;
  mission)
    files=("$out"/shards/*-campaign-shard-*-of-"$n".json)
    [ ${#files[@]} -gt 0 ] || { echo "$0: no $out/shards/*-campaign-shard-*-of-$n.json: did the shards run?" >&2; exit 2; }
    exec "$bin" mission merge ${FORCE:+--force} "$out/merged" "${files[@]}"
    ;;
  *) echo "usage: $0 campaign|mission N OUT" >&2; exit 2 ;;
esac
