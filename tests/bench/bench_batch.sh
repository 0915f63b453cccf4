#!/bin/sh
# bench_batch.sh — `mesobake batch` over a 34-job manifest of mixed kinds
# (mesh, mesh --draco, shell, cells, frusta from skeletons and meshes) made
# from the bundled data: wall time for -j 1, -j 2 and the Slurm engine on a
# private one-node cluster (tools/slurm/cluster.sh; needs root), each from an
# empty cache, and for the cached re-run. Medians over RUNS runs (default 5).
# Writes tests/bench/results/batch.csv.
# usage: bench_batch.sh [MESOBAKE] [RUNS]
set -eu
src=$(cd "$(dirname "$0")/../.." && pwd)
bake=${1:-$src/build/tools/mesobake}
runs=${2:-5}
out=$src/tests/bench/results/batch.csv
tmp=$(mktemp -d)
cluster=""
cleanup() {
    [ -n "$cluster" ] && sh "$src/tools/slurm/cluster.sh" stop "$cluster" >/dev/null 2>&1
    rm -rf "$tmp"
}
trap cleanup EXIT
mkdir -p "$tmp/data"
cp "$src"/tests/data/*.obj "$src"/tests/data/*.swc "$src"/tests/data/*.skel "$tmp/data/"

# The manifest: 8 meshes x (mesh, mesh --draco), 8 shells, 3 cells, 7 frusta.
{
    echo '{"jobs": ['
    sep=""
    for m in blub_fish_low_resolution cube_no_bottom saddle sphere spot_low_resolution spot_uv torus wingnut; do
        printf '%s{"command": "mesh", "input": "data/%s.obj", "output": "out/mesh_%s.meso"},\n' "$sep" "$m" "$m"
        printf '{"command": "mesh", "input": "data/%s.obj", "output": "out/draco_%s.meso", "args": ["--draco"]},\n' "$m" "$m"
        if [ "$m" = wingnut ]; then # intersects itself: no shell (E3114); a textured shell instead
            printf '{"command": "shell", "input": "data/spot_uv.obj", "output": "out/shell_bricks.meso", "args": ["--texture", "bricks:64", "--tiling", "4"]}'
        else
            printf '{"command": "shell", "input": "data/%s.obj", "output": "out/shell_%s.meso"}' "$m" "$m"
        fi
        sep=",
"
    done
    for m in torus sphere spot_low_resolution; do
        printf ',\n{"command": "cells", "input": "data/%s.obj", "output": "out/cells_%s.meso", "args": ["--tiles", "4", "--tile-res", "16"]}' "$m" "$m"
    done
    for s in morphio_soma_single_frustum morphio_three_point_soma neurom_Neuron neurom_fat_end neurom_simple; do
        printf ',\n{"command": "frusta", "input": "data/%s.swc", "output": "out/frusta_%s.meso"}' "$s" "$s"
    done
    printf ',\n{"command": "frusta", "input": "data/saguaro.skel", "output": "out/frusta_saguaro.meso", "args": ["--relief", "bricks:64"]}'
    printf ',\n{"command": "frusta", "input": "data/torus.obj", "output": "out/frusta_torus.meso"}\n]}\n'
} >"$tmp/manifest.json"
jobs=$(grep -c '"command"' "$tmp/manifest.json")

field() { # FILE NAME: a number from a batch report
    sed -n "s/^[[:space:]]*\"$2\":[[:space:]]*\\([0-9.e+-]*\\),*$/\\1/p" "$1" | head -n 1
}
median() { sort -g | awk '{v[NR]=$1} END {print (NR % 2) ? v[(NR+1)/2] : (v[NR/2] + v[NR/2+1]) / 2}'; }

# measure NAME ARGS...: RUNS cold runs (empty cache) each followed by a cached re-run.
measure() {
    name=$1
    shift
    : >"$tmp/cold" && : >"$tmp/warm" && : >"$tmp/busy"
    r=0
    while [ $r -lt "$runs" ]; do
        rm -rf "$tmp/cache" "$tmp/out"
        "$bake" batch "$tmp/manifest.json" --cache "$tmp/cache" --report "$tmp/cold.json" "$@" 2>/dev/null
        [ "$(field "$tmp/cold.json" jobs_failed)" = 0 ] || { echo "bench_batch: a job failed ($name)" >&2; exit 1; }
        field "$tmp/cold.json" seconds >>"$tmp/cold"
        field "$tmp/cold.json" cpu_busy >>"$tmp/busy"
        "$bake" batch "$tmp/manifest.json" --cache "$tmp/cache" --report "$tmp/warm.json" "$@" 2>/dev/null
        [ "$(field "$tmp/warm.json" jobs_cached)" = "$jobs" ] || { echo "bench_batch: re-run not all cached" >&2; exit 1; }
        field "$tmp/warm.json" seconds >>"$tmp/warm"
        r=$((r + 1))
    done
    cold=$(median <"$tmp/cold") warm=$(median <"$tmp/warm") busy=$(median <"$tmp/busy")
    echo "$name,$jobs,$runs,$cold,$busy,$warm" >>"$tmp/batch.csv"
    echo "$name: $jobs jobs, median of $runs: ${cold} s from an empty cache (cpu busy $busy), ${warm} s cached"
}

echo "config,jobs,runs,median_seconds,median_cpu_busy,median_cached_seconds" >"$tmp/batch.csv"
measure local_j1 -j 1
measure local_j2 -j 2
if [ "$(id -u)" -eq 0 ] && command -v sbatch >/dev/null 2>&1; then
    cluster=$tmp/slurm
    eval "$(sh "$src/tools/slurm/cluster.sh" start "$cluster")"
    export SLURM_CONF
    measure slurm --engine slurm
else
    echo "bench_batch: no Slurm row (needs root and slurm-client, slurmd, slurmctld, munge)" >&2
fi
mv "$tmp/batch.csv" "$out"
echo "results in $out"
