#!/bin/sh
# run_session.sh FUZZER CORPUS_DIR DICT SECONDS
#
# A bounded libFuzzer session for `meson test --suite fuzz-session`:
#   1. replay every checked-in corpus file (fails on any crash);
#   2. when SECONDS > 0, fuzz for SECONDS on a scratch copy of the corpus
#      (libFuzzer adds new inputs to its first corpus directory: the checked-in
#      corpus is never modified), with the dictionary, artifacts written into
#      the scratch directory.
# Fails when the fuzzer exits non-zero or leaves any crash-/leak-/timeout-/oom-
# artifact; those are copied to ./fuzz-artifacts/ (the test's working
# directory, build-fuzz/tests/fuzz) so they can be reproduced with
#   ./fuzz_meso_file fuzz-artifacts/crash-<sha1>
set -u
if [ $# -ne 4 ]; then
    echo "usage: $0 FUZZER CORPUS_DIR DICT SECONDS" >&2
    exit 2
fi
fuzzer=$1 corpus=$2 dict=$3 secs=$4
case $fuzzer in */*) ;; *) fuzzer=./$fuzzer ;; esac # meson passes it relative to workdir

work=$(mktemp -d "${TMPDIR:-/tmp}/meso-fuzz.XXXXXX") || exit 1
trap 'rm -rf "$work"' EXIT INT TERM
mkdir "$work/corpus" "$work/artifacts" || exit 1
cp "$corpus"/* "$work/corpus/" || exit 1

export ASAN_OPTIONS="${ASAN_OPTIONS:-abort_on_error=1:detect_leaks=1:allocator_may_return_null=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"

collect() {
    found=$(ls "$work/artifacts" 2>/dev/null | grep -E '^(crash|leak|timeout|oom)-' || true)
    if [ -n "$found" ]; then
        mkdir -p fuzz-artifacts
        cp "$work/artifacts"/* fuzz-artifacts/ 2>/dev/null
        echo "FAIL: fuzzer artifacts (copied to $(pwd)/fuzz-artifacts):" >&2
        echo "$found" >&2
        return 1
    fi
    return 0
}

# 1. Replay: with file arguments libFuzzer runs each input once and exits.
echo "== replaying $(ls "$work/corpus" | wc -l) corpus files"
"$fuzzer" -artifact_prefix="$work/artifacts/" -rss_limit_mb=2048 -timeout=10 "$work/corpus"/*
rc=$?
collect || exit 1
if [ $rc -ne 0 ]; then
    echo "FAIL: replay exited with $rc" >&2
    exit 1
fi
[ "$secs" -gt 0 ] || exit 0

# 2. Bounded fuzzing session.
echo "== fuzzing for $secs s"
"$fuzzer" "$work/corpus" -dict="$dict" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 \
    -max_len=65536 -print_final_stats=1 -artifact_prefix="$work/artifacts/"
rc=$?
echo "== corpus grew from $(ls "$corpus" | wc -l) to $(ls "$work/corpus" | wc -l) inputs"
collect || exit 1
if [ $rc -ne 0 ]; then
    echo "FAIL: fuzzer exited with $rc" >&2
    exit 1
fi
echo "== fuzz session clean"
