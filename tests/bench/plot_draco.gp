# plot_draco.gp — Draco vs raw MESH chunks from bench_draco's CSV.
#   gnuplot -e 'csv="tests/bench/results/draco.csv"; png="tests/bench/results/draco.png"' tests/bench/plot_draco.gp
# Left: stored bytes relative to the raw chunk vs max position error (relative
# to the bounding-box diagonal). Right: decode time (read_chunk, ms) vs the
# same error. One line per mesh; points are position bits 8..16.
if (!exists("csv")) csv = "tests/bench/results/draco.csv"
if (!exists("png")) png = "tests/bench/results/draco.png"

if (strstrt(GPVAL_TERMINALS, "pngcairo") > 0) {
    set terminal pngcairo size 1400,560 enhanced font "sans,10"
} else {
    set terminal png size 1400,560
}
set output png
set datafile separator ","
meshes = system("tail -n +2 '".csv."' | cut -d, -f1 | uniq | tr '\\n' ' '")

set multiplot layout 1,2 title "Draco MESH chunks: position bits 8, 10, 12, 14, 16 (normals 10, uvs 12)"
set logscale x
set format x "10^{%L}"
set grid
set key top right
set xlabel "max vertex position error / bbox diagonal"

set ylabel "stored bytes / raw chunk bytes"
set yrange [0:*]
plot for [m in meshes] csv using (strcol(1) eq m && strcol(4) eq "draco" ? $12 : 1/0):9 \
    with linespoints title m noenhanced

set ylabel "decode time, ms (meso\\_file\\_read\\_chunk incl. CRC)"
set logscale y
set yrange [*:*]
plot for [m in meshes] csv using (strcol(1) eq m && strcol(4) eq "draco" ? $12 : 1/0):11 \
    with linespoints title m noenhanced
unset multiplot
