#!/bin/sh
# run_benchmarks.sh — build with -Dbench=true into build-bench, run both
# benchmarks and draw the chart. Results: tests/bench/results/
#   format_throughput.csv, draco.csv, draco.png
# Usage (from anywhere): tests/bench/run_benchmarks.sh [BUILD_DIR]
# bench_format writes (and deletes) a ~1.07 GB file in the build directory.
set -eu
src=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$src/build-bench}
results=$src/tests/bench/results
mkdir -p "$results"
if [ ! -d "$build" ]; then
    meson setup "$build" "$src" -Dbench=true -Dtests=true
else
    meson configure "$build" -Dbench=true -Dtests=true
fi
ninja -C "$build" tests/bench/bench_format tests/bench/bench_draco
echo "== bench_format"
"$build/tests/bench/bench_format" "$build/tests/bench" "$results/format_throughput.csv"
echo "== bench_draco"
"$build/tests/bench/bench_draco" "$results/draco.csv"
echo "== plot"
gnuplot -e "csv='$results/draco.csv'; png='$results/draco.png'" "$src/tests/bench/plot_draco.gp"
echo "results in $results"
