#!/usr/bin/env bash
# Fuzzes every parser for a bounded time each and prints executions per target (firmware/fuzz/README.md).
#
#   firmware/fuzz/run.sh [SECONDS_PER_TARGET] [TARGET...]     (default 15 s, every target)
#
# Builds the targets as `cargo fuzz build --sanitizer none` (cargo-fuzz 0.13) does, with plain cargo: the same
# libFuzzer (libfuzzer-sys, compiled from its C++ source by the crate's build script), the same SanitizerCoverage
# flags, release with debug assertions (overflow checks on), so a fresh machine needs neither cargo-fuzz nor a
# nightly toolchain. Seeds come from gen_corpus.sh; what a run finds is added to corpus/<target>/, a crash is
# written to artifacts/<target>/ and fails the script (after the table).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
secs="${1:-15}"
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    targets=(deframe_decode frame_decode fieldlog scenario geotiff asc npy obj ply pcd las movingai retained tile)
fi
if ! command -v c++ > /dev/null; then   # libFuzzer is C++
    SUDO=""; if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
    $SUDO apt-get update -qq && $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends g++
fi
triple="$(rustc -vV | sed -n 's/^host: //p')"
# cargo-fuzz's flags (src/project.rs of 0.13.2) for --sanitizer none in release mode
flags="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing -Cllvm-args=-sanitizer-coverage-stack-depth \
-Cdebug-assertions -Ccodegen-units=1"
target_dir="${FUZZ_TARGET_DIR:-$here/target}"
t0=$SECONDS
# FUZZ_SKIP_BUILD=1: run the binaries an earlier build left (e.g. `cargo fuzz build --sanitizer none`)
[ "${FUZZ_SKIP_BUILD:-0}" = 1 ] || RUSTFLAGS="$flags" cargo build -q --manifest-path "$here/Cargo.toml" --target "$triple" --release \
    --config 'profile.release.debug="line-tables-only"' --target-dir "$target_dir" --bins
build_s=$((SECONDS - t0))
"$here/gen_corpus.sh" > /dev/null
bin="$target_dir/$triple/release"
mkdir -p "$here/artifacts"
results=()
failed=0
for t in "${targets[@]}"; do
    mkdir -p "$here/corpus/$t" "$here/artifacts/$t"
    log="$here/artifacts/$t.log"
    status=ok
    # -timeout: an input running over 10 s is a hang and fails like a crash
    if ! "$bin/$t" "$here/corpus/$t" -max_total_time="$secs" -timeout=10 -print_final_stats=1 \
        -artifact_prefix="$here/artifacts/$t/" > "$log" 2>&1; then
        status=FAILED
        failed=1
        grep -E "^(==|SUMMARY|thread|.*panicked)|Test unit written|ERROR" "$log" | head -20 || true
    fi
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
    cov=$(grep -oE 'cov: [0-9]+' "$log" | tail -1 | cut -d' ' -f2)
    corpus=$(find "$here/corpus/$t" -type f | wc -l)
    results+=("$(printf '%-16s %12s %10s %8s %8s %s' "$t" "${execs:-?}" "${rate:-?}" "${cov:-?}" "$corpus" "$status")")
done
printf '%-16s %12s %10s %8s %8s %s\n' target executions per_s cov corpus status
printf '%s\n' "${results[@]}"
echo "fuzz: build ${build_s} s, ${#targets[@]} targets x ${secs} s"
exit $failed
