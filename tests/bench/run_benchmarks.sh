#!/bin/sh
# run_benchmarks.sh — build with -Dbench=true into build-bench, run both
# benchmarks and draw the chart. Results: tests/bench/results/
#   format_throughput.csv, draco.csv, draco.png
# Usage (from anywhere): tests/bench/run_benchmarks.sh [BUILD_DIR]
# bench_format writes (and deletes) a ~1.07 GB file in the build directory.
# Everything reads only the repository. The thesis's setups used the Stanford
# bunny and armadillo, which cannot be bundled (their terms forbid
# commercial use); the bundled spot stands in for both. To measure on a copy
# of your own, set MESO_BENCH_MESH (cells) and MESO_BENCH_FIT_MESH (frusta
# fit) to its path; the checked-in results were measured that way.
set -eu
src=$(cd "$(dirname "$0")/../.." && pwd)
bench_mesh=${MESO_BENCH_MESH:-$src/tests/data/spot_low_resolution.obj}
fit_mesh=${MESO_BENCH_FIT_MESH:-$src/tests/data/spot_low_resolution.obj}
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
#   shell_size.csv, shell_accuracy.csv, shell_thickness.csv, shell_goals.csv,
#   shell_kept.csv, shell_kept_dist.csv
#   and shell_size.png, shell_accuracy.png, shell_thickness.png, shell_kept.png
# (goals and kept read tests/data, or the folder $MESO_BENCH_MESHES names;
# the checked-in ones are of the shared closed meshes.)
# Skip with MESO_BENCH_SKIP_SHELL=1; sizes up to level 4 (423k triangles) by
# default, `bench_shell size DIR 5` adds 1.7M (much longer).
if [ "${MESO_BENCH_SKIP_SHELL:-0}" != 1 ]; then
    ninja -C "$build" tests/bench/bench_shell tools/mesobake
    echo "== bench_shell"
    nice "$build/tests/bench/bench_shell" all "$results" "$build/tools/mesobake"
    gnuplot -e "dir='$results'" "$src/tests/bench/plot_shell.gp"
    echo "shell results in $results"
fi

# Incremental shell re-bakes (mesobake shell --update) against full re-bakes:
# shell_update.csv. The checked-in one is of the shared armadillo and the
# bundled spot_uv ($MESO_BENCH_MESHES/armadillo.obj when set). ~3-5 min.
if [ "${MESO_BENCH_SKIP_SHELL:-0}" != 1 ]; then
    ninja -C "$build" tests/bench/bench_shell_update
    echo "== bench_shell_update"
    if [ -n "${MESO_BENCH_MESHES:-}" ] && [ -f "$MESO_BENCH_MESHES/armadillo.obj" ]; then
        nice "$build/tests/bench/bench_shell_update" "$results" "$MESO_BENCH_MESHES/armadillo.obj" \
            "$src/tests/data/spot_uv.obj"
    else
        nice "$build/tests/bench/bench_shell_update" "$results"
    fi
fi

# Shell ray casting (issue #5): Table 1 on llvmpipe, error against the exact
# reference, cost-vs-error sweeps. Results: table1.csv, shell_render_sweep.csv,
# shell_render_cost_error.png, shell_render_table1.png. Skip with
# MESO_BENCH_SKIP_RENDER=1; `quick` as a 4th argument for a smoke run.
if [ "${MESO_BENCH_SKIP_RENDER:-0}" != 1 ]; then
    ninja -C "$build" tests/bench/bench_shell_render tools/mesobake
    echo "== bench_shell_render"
    MESA_SHADER_CACHE_DISABLE=true "$build/tests/bench/bench_shell_render" "$results" "$build/tools/mesobake" \
        "$src/tests/data"
    gnuplot -e "dir='$results'" "$src/tests/bench/plot_shell_render.gp"
    echo "render results in $results"
fi

# Slice-based shell rendering (issue #19): Figure 12 recreated. Results:
# slices.csv, slices_angle.csv, slices_fig12.png, slices_error_time.png.
# Skip with MESO_BENCH_SKIP_SLICES=1.
if [ "${MESO_BENCH_SKIP_SLICES:-0}" != 1 ]; then
    ninja -C "$build" tests/bench/bench_slices
    echo "== bench_slices"
    MESA_SHADER_CACHE_DISABLE=true "$build/tests/bench/bench_slices" "$results"
    gnuplot -e "dir='$results'" "$src/tests/bench/plot_slices.gp"
fi

# Frusta (issue #7): set_pose per 1000 frusta and draw times (bench_frusta),
# frusta against polygon tessellations at equal error, relief steps, and
# segments against fit error on $fit_mesh (bench_frusta_render). ~1 min. Results: bench_frusta.csv,
# frusta_vs_tess.csv, frusta_relief_steps.csv, frusta_fit.csv,
# frusta_vs_tess.png. Skip with MESO_BENCH_SKIP_FRUSTA=1.
if [ "${MESO_BENCH_SKIP_FRUSTA:-0}" != 1 ]; then
    ninja -C "$build" tests/bench/bench_frusta tests/bench/bench_frusta_render tools/mesobake
    echo "== bench_frusta"
    MESA_SHADER_CACHE_DISABLE=true "$build/tests/bench/bench_frusta" "$results"
    echo "== bench_frusta_render"
    MESA_SHADER_CACHE_DISABLE=true "$build/tests/bench/bench_frusta_render" "$results" "$build/tools/mesobake" \
        "$src/tests/data" "$fit_mesh"
    gnuplot -e "dir='$results'" "$src/tests/bench/plot_frusta.gp"
    echo "frusta results in $results"
fi

# Cells objects: the thesis's Table 5.1 setups on $bench_mesh
# (mesobake cells at 8192 voxels across: tile map 256^3 x 32^3 tiles ..
# 32^3 x 256^3, Voronoi 8 seeds), wall time, peak RSS and bytes per map next
# to the thesis's. ~1 min. Results: cells_table51.csv, cells_table51.png.
# Skip with MESO_BENCH_SKIP_CELLS=1; a setup is killed after
# MESO_BENCH_CELLS_TIMEOUT seconds (default 900).
if [ "${MESO_BENCH_SKIP_CELLS:-0}" != 1 ]; then
    ninja -C "$build" tests/bench/bench_cells_bake tools/mesobake
    echo "== bench_cells_bake"
    nice "$build/tests/bench/bench_cells_bake" "$build/tools/mesobake" "$bench_mesh" "$results"
    gnuplot -e "dir='$results'" "$src/tests/bench/plot_cells_bake.gp"
    echo "cells results in $results"
fi

# Cells rendering: the Figure 5.1 (top) setup on $bench_mesh (64^3 map x 128^3 tiles,
# Voronoi 8) ray traced by libmeso against the exact reference at 400x300:
# the thesis's linear search step (R/16 .. R/512 voxels, fixed and angle
# rule) against the exact traversal, reflection / refraction orders 0..3,
# and the README pictures. ~8 min on 2 cores. Results: cells_render_step.csv,
# cells_render_order.csv, cells_render.png, cells_first.png,
# cells_reflect.png, cells_refract.png. Skip with
# MESO_BENCH_SKIP_CELLS_RENDER=1; `quick` as a 4th argument for a smoke run.
if [ "${MESO_BENCH_SKIP_CELLS_RENDER:-0}" != 1 ]; then
    ninja -C "$build" tests/bench/bench_cells_render tools/mesobake
    echo "== bench_cells_render"
    MESA_SHADER_CACHE_DISABLE=true nice "$build/tests/bench/bench_cells_render" "$results" "$build/tools/mesobake" \
        "$bench_mesh"
    gnuplot -e "dir='$results'" "$src/tests/bench/plot_cells_render.gp"
    echo "cells render results in $results"
fi

# mesobake batch (issue 17): a 34-job manifest, -j 1, -j 2 and the Slurm
# engine on a private one-node cluster (root only), cold and cached, medians
# of 5. Result: batch.csv. Skip with MESO_BENCH_SKIP_BATCH=1.
if [ "${MESO_BENCH_SKIP_BATCH:-0}" != 1 ]; then
    ninja -C "$build" tools/mesobake
    sh "$src/tests/bench/bench_batch.sh" "$build/tools/mesobake" 5
fi

# Many objects (issue 18 items 3, 10): CPU us per instance (instanced,
# separate, list), the Goal's GPU-time ratio (1000 instanced saguaros
# against one object of 1000 saguaros) and the cactus field at 1, 10, 100,
# 1000 objects, at 320x240. ~15 min on 2 cores. Result: instances.csv. Skip
# with MESO_BENCH_SKIP_INSTANCES=1.
if [ "${MESO_BENCH_SKIP_INSTANCES:-0}" != 1 ]; then
    ninja -C "$build" tests/bench/bench_instances tools/mesobake
    echo "== bench_instances"
    "$build/tests/bench/bench_instances" "$results/instances.csv" "$build/tools/mesobake" "$src/tests/data"
fi

# Levels of detail (issue 14): the 64-object scene at pixel errors 0.5..16
# and the finest level everywhere (lod_scene.csv, lod_scene.png, the chart
# lod_scene_chart.png; ~10 min), and a ~105 MB mesh file streamed at
# 10 MB/s (stream.csv; ~3 min, most of it the 2.2M-triangle bake), and the
# frusta stand-in's cost against the native level's (frusta_standin_cost.csv).
# Skip with MESO_BENCH_SKIP_LOD=1.
if [ "${MESO_BENCH_SKIP_LOD:-0}" != 1 ]; then
    ninja -C "$build" tests/bench/bench_lod_scene tests/bench/bench_stream tools/mesobake
    echo "== bench_lod_scene"
    "$build/tests/bench/bench_lod_scene" "$results/lod_scene.csv" "$build/tools/mesobake" "$src/tests/data" \
        "$build/tests/bench" "$results/lod_scene.png"
    gnuplot -e "dir='$results'" "$src/tests/bench/plot_lod_scene.gp"
    echo "== bench_stream"
    "$build/tests/bench/bench_stream" "$results/stream.csv" "$build/tools/mesobake" "$build/tests/bench"
    # A frusta object's tessellated stand-in against its native level where
    # libmeso switches to it, per bundled skeleton (~30 s; the checked-in
    # frusta_standin_cost.csv is the median of 3 runs).
    ninja -C "$build" tests/bench/bench_frusta_standin_cost
    echo "== bench_frusta_standin_cost"
    MESA_SHADER_CACHE_DISABLE=true "$build/tests/bench/bench_frusta_standin_cost" "$results/frusta_standin_cost.csv" \
        "$build/tools/mesobake" "$src/tests/data" "$build/tests/bench"
fi
