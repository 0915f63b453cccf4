# plot_cells_render.gp — chart of bench_cells_render's CSVs.
#   gnuplot -e 'dir="tests/bench/results"' tests/bench/plot_cells_render.gp
# Writes dir/cells_render.png. Left: first-hit draw time against the mean
# hit error vs the exact reference as the thesis's linear search step moves
# (R/16 .. R/512 tile-map voxels, fixed step and the angle rule; labels: the
# step in voxels), the exact traversal as one point per view (drawn at
# 1e-4 px when its error is below that). Right: time per frame (left axis)
# and the reference's mean colour change from order b to order 3 (right
# axis, log) against the number of bounces, reflection and refraction.
if (!exists("dir")) dir = "tests/bench/results"
st = dir."/cells_render_step.csv"
od = dir."/cells_render_order.csv"
cairo = strstrt(GPVAL_TERMINALS, "pngcairo") > 0
set datafile separator ","
rows(f, cond) = sprintf("< awk -F, 'NR > 1 && (%s)' '%s'", cond, f)
set grid
set key noenhanced top right
if (cairo) { set terminal pngcairo size 1500,640 enhanced font "sans,11" } else { set terminal png size 1500,640 }
set output dir."/cells_render.png"
set multiplot layout 1,2 title "cells on llvmpipe: the Figure 5.1 bunny (64^3 map x 128^3 tiles, Voronoi 8), 400x300, vs the exact reference" noenhanced
views = "full close"
set logscale xy
set xlabel "mean hit error against the exact reference (pixels)"
set ylabel "ms / frame (first hit)"
lowclip(x) = (x > 0.0001) ? x : 0.0001
set xrange [0.0001:0.2]
set key outside below maxrows 3
plot for [v=1:2] rows(st, sprintf("$1==\"%s\" && $2==\"linear_fixed\"", word(views,v))) using (lowclip($11)):5 \
       with linespoints lc v pt 7 title sprintf("%s: linear, fixed step", word(views,v)), \
     for [v=1:2] rows(st, sprintf("$1==\"%s\" && $2==\"linear_fixed\"", word(views,v))) using (lowclip($11)):5:(sprintf("%g", $3)) \
       with labels offset 1.5,0.5 font ",8" textcolor lt v notitle, \
     for [v=1:2] rows(st, sprintf("$1==\"%s\" && $2==\"linear_angle\"", word(views,v))) using (lowclip($11)):5 \
       with linespoints lc v dt 2 pt 5 title sprintf("%s: linear, angle rule", word(views,v)), \
     for [v=1:2] rows(st, sprintf("$1==\"%s\" && $2==\"exact\"", word(views,v))) using (lowclip($11)):5 \
       with points lc v pt 3 ps 3 lw 2 title sprintf("%s: exact traversal", word(views,v))
unset logscale
set xlabel "bounces (order)"
set xtics 1
set ylabel "ms / frame (exact traversal)"
set y2label "reference: mean colour change to order 3"
set logscale y2
set y2tics
set ytics nomirror
set key outside below maxrows 2
unset xrange
set xrange [-0.2:3.2]
modes = "reflect refract"
plot for [v=1:2] for [m=1:2] rows(od, sprintf("$1==\"%s\" && $2==\"%s\"", word(views,v), word(modes,m))) using 3:4 \
       with linespoints lc (2*v+m-2) pt 7 title sprintf("%s %s: ms", word(views,v), word(modes,m)), \
     for [v=1:2] for [m=1:2] rows(od, sprintf("$1==\"%s\" && $2==\"%s\" && $3 < 3", word(views,v), word(modes,m))) using 3:11 \
       axes x1y2 with linespoints lc (2*v+m-2) dt 2 pt 6 title sprintf("%s %s: change to order 3", word(views,v), word(modes,m))
unset multiplot
