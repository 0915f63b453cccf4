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

# Shell directors (issue #4): ~15-20 min on 2 cores. Results:
#   shell_size.csv, shell_accuracy.csv, shell_thickness.csv, shell_goals.csv
#   and shell_size.png, shell_accuracy.png, shell_thickness.png
# Skip with MESO_BENCH_SKIP_SHELL=1; sizes up to level 4 (423k triangles) by
# default, `bench_shell size DIR 5` adds 1.7M (much longer).
if [ "${MESO_BENCH_SKIP_SHELL:-0}" != 1 ]; then
    ninja -C "$build" tests/bench/bench_shell bake/mesobake
    echo "== bench_shell"
    nice "$build/tests/bench/bench_shell" all "$results" "$build/bake/mesobake"
    gnuplot -e "dir='$results'" "$src/tests/bench/plot_shell.gp"
    echo "shell results in $results"
fi

# Shell ray casting (issue #5): Table 1 on llvmpipe, error against the exact
# reference, cost-vs-error sweeps. Results: table1.csv, shell_render_sweep.csv,
# shell_render_cost_error.png, shell_render_table1.png. Skip with
# MESO_BENCH_SKIP_RENDER=1; `quick` as a 4th argument for a smoke run.
if [ "${MESO_BENCH_SKIP_RENDER:-0}" != 1 ]; then
    ninja -C "$build" tests/bench/bench_shell_render bake/mesobake
    echo "== bench_shell_render"
    MESA_SHADER_CACHE_DISABLE=true "$build/tests/bench/bench_shell_render" "$results" "$build/bake/mesobake" \
        "$src/tests/data"
    gnuplot -e "dir='$results'" "$src/tests/bench/plot_shell_render.gp"
    echo "render results in $results"
fi

# Frusta (issue #7): set_pose per 1000 frusta and draw times (bench_frusta),
# frusta against polygon tessellations at equal error, relief steps, and
# segments against fit error on ../shared/data/meshes/armadillo.obj
# (bench_frusta_render). ~1 min. Results: bench_frusta.csv,
# frusta_vs_tess.csv, frusta_relief_steps.csv, frusta_fit.csv,
# frusta_vs_tess.png. Skip with MESO_BENCH_SKIP_FRUSTA=1.
if [ "${MESO_BENCH_SKIP_FRUSTA:-0}" != 1 ]; then
    ninja -C "$build" tests/bench/bench_frusta tests/bench/bench_frusta_render bake/mesobake
    echo "== bench_frusta"
    MESA_SHADER_CACHE_DISABLE=true "$build/tests/bench/bench_frusta" "$results"
    echo "== bench_frusta_render"
    MESA_SHADER_CACHE_DISABLE=true "$build/tests/bench/bench_frusta_render" "$results" "$build/bake/mesobake" \
        "$src/tests/data" "$src/../shared/data/meshes/armadillo.obj"
    gnuplot -e "dir='$results'" "$src/tests/bench/plot_frusta.gp"
    echo "frusta results in $results"
fi
