#!/usr/bin/env bash
# Writes the seed corpus (one valid frame of every message kind, plus a few damaged ones) into
# firmware/fuzz/corpus/deframe_decode/ by running the ignored test that generates it.
set -euo pipefail
cd "$(dirname "$0")/../.."
FUZZ_CORPUS_DIR="$PWD/firmware/fuzz/corpus/deframe_decode" cargo test -p tests --test fuzz_corpus -- --ignored --nocapture
