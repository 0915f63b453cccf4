# plot_cells_bake.gp — the thesis's Table 5.1 against bench_cells_bake's CSV.
#   gnuplot -e 'dir="tests/bench/results"' tests/bench/plot_cells_bake.gp
# Reads dir/cells_table51.csv, writes dir/cells_table51.png:
#   left   bytes per map and setup (log scale), ours (solid) next to the
#          thesis's (hatched): tile map (TILE + SPLT; thesis: cell map), colour
#          (ours: R^3 RGBA8; thesis: a fixed 128^3 RGBA8 map), normal,
#          membership, total file (ours incl. MESH) / total texture memory
#   right  bake wall time (s, bars) and peak RSS of mesobake (MiB, points,
#          right axis) per setup
# Setups that did not finish (status != ok) have no bars of ours.
if (!exists("dir")) dir = "tests/bench/results"
csv = dir."/cells_table51.csv"
cairo = strstrt(GPVAL_TERMINALS, "pngcairo") > 0
set datafile separator ","
set datafile missing ""
set key autotitle columnheader
if (cairo) { set terminal pngcairo size 1600,620 enhanced font "sans,10" } else { set terminal png size 1600,620 }
set output dir."/cells_table51.png"
set multiplot layout 1,2 title "Table 5.1: mesobake cells on the bunny, 8192 voxels across, Voronoi 8 seeds, 2 threads — ours against the thesis" \
    noenhanced
set style data histograms
set style histogram clustered gap 2
set grid y
set logscale y
set ytics ("16 KiB" 2**14, "64 KiB" 2**16, "256 KiB" 2**18, "1 MiB" 2**20, "4 MiB" 2**22, "16 MiB" 2**24, \
           "64 MiB" 2**26, "256 MiB" 2**28, "1 GiB" 2**30)
set ylabel "bytes"
set xlabel "tile map resolution R^3 x tiles T^3"
set xtics noenhanced
set key below noenhanced maxrows 2 font ",9"
set yrange [2**14:2**30]
# Our bytes only for finished setups.
ours(c) = (strcol(4) eq "ok" ? column(c) : 1/0)
# Columns: 9 tile map, 10 colour, 11 normal, 12 membership, 8 file total;
# thesis 15 cell map, 16 colour, 17 normal, 18 membership, 19 total.
plot csv using (ours(9)):xtic(1)  title "tile map (TILE+SPLT)" fs solid 0.8 lc rgb "#1f77b4", \
     ''  using 15      title "thesis cell map" fs pattern 4 lc rgb "#1f77b4", \
     ''  using (ours(10)) title "colour (ours R^3 RGBA8)" fs solid 0.8 lc rgb "#ff7f0e", \
     ''  using 16      title "thesis colour (fixed 128^3 RGBA8)" fs pattern 4 lc rgb "#ff7f0e", \
     ''  using (ours(11)) title "normal (NRMM)" fs solid 0.8 lc rgb "#2ca02c", \
     ''  using 17      title "thesis normal" fs pattern 4 lc rgb "#2ca02c", \
     ''  using (ours(12)) title "membership (MEMB, sparse)" fs solid 0.8 lc rgb "#d62728", \
     ''  using 18      title "thesis membership" fs pattern 4 lc rgb "#d62728", \
     ''  using (ours(8)) title "file total (incl. MESH)" fs solid 0.8 lc rgb "#7f7f7f", \
     ''  using 19      title "thesis total" fs pattern 4 lc rgb "#7f7f7f"

unset logscale y
set ytics auto
set yrange [0:*]
set ylabel "seconds"
set y2label "peak RSS of mesobake (MiB)"
set y2tics
set y2range [0:*]
set ytics nomirror
set key below noenhanced font ",9"
set style histogram clustered gap 1
plot csv using (ours(5)):xtic(1) title "seconds_total (report)" fs solid 0.8 lc rgb "#1f77b4", \
     ''  using 6 title "wall seconds (our clock)" fs solid 0.5 lc rgb "#9ecae1", \
     ''  using ($0):7 axes x1y2 with linespoints pt 7 ps 1.5 lw 2 lc rgb "#d62728" title "peak RSS (MiB)"
unset multiplot
