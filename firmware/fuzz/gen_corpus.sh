#!/usr/bin/env bash
# Writes the seed corpora, one directory per fuzz target, into firmware/fuzz/corpus/<target>/ by running the
# ignored test that generates them (tests/tests/fuzz_corpus.rs: protocol frames of every kind, hand-built and
# recorded; small valid files of every reader's format).
set -euo pipefail
cd "$(dirname "$0")/../.."
# --workspace: the features the README's test command builds with, so CI reuses its build (-p tests alone rebuilt both
# crates under it)
FUZZ_CORPUS_DIR="$PWD/firmware/fuzz/corpus" cargo test -q --workspace --test fuzz_corpus -- --ignored --nocapture
