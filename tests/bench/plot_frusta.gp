# plot_frusta.gp — charts of bench_frusta_render's CSVs.
#   gnuplot -e 'dir="tests/bench/results"' tests/bench/plot_frusta.gp
# Writes dir/frusta_vs_tess.png: draw time (left) and memory (middle) against
# the mean hit error vs the exact reference, for the ray caster (the relief
# step count swept) and for polygon tessellations of the same relief surface
# (the grid swept); right: segments and fit error against --tolerance for a
# skeleton extracted from the armadillo (when frusta_fit.csv exists).
if (!exists("dir")) dir = "tests/bench/results"
vt = dir."/frusta_vs_tess.csv"
rs = dir."/frusta_relief_steps.csv"
fit = dir."/frusta_fit.csv"
cairo = strstrt(GPVAL_TERMINALS, "pngcairo") > 0
set datafile separator ","
rows(f, cond) = sprintf("< awk -F, 'NR > 1 && (%s)' '%s'", cond, f)
set grid
set key noenhanced top right
if (cairo) { set terminal pngcairo size 1650,520 enhanced font "sans,11" } else { set terminal png size 1650,520 }
set output dir."/frusta_vs_tess.png"
set multiplot layout 1,3 title "relief-mapped frusta vs polygon tessellations on llvmpipe (saguaro + ribs, 400x300; error vs the exact reference)"
set logscale xy
set xlabel "mean hit error (pixels)"
set ylabel "ms / frame"
plot rows(rs, "1") using 4:2 with linespoints pt 7 lc 1 title "frusta (relief steps 4..256)", \
     rows(rs, "1") using 4:2:(sprintf("%d", $1)) with labels offset 1.2,0.6 font ",9" textcolor lt 1 notitle, \
     rows(vt, "$1==\"tessellation\"") using 9:6 with linespoints pt 5 lc 2 title "tessellation (grid 8..512)", \
     rows(vt, "$1==\"tessellation\"") using 9:6:(sprintf("%dk", $3/1000)) with labels offset 1.2,-0.6 font ",9" textcolor lt 2 notitle
set ylabel "bytes"
set format y "10^{%T}"
plot rows(vt, "$1==\"frusta\"") using 9:4 with points pt 7 ps 2 lc 1 title "frusta object (records + relief map)", \
     rows(vt, "$1==\"tessellation\"") using 9:4 with linespoints pt 5 lc 2 title "tessellation (MESH chunk)"
unset format
unset logscale
if (system(sprintf("test -s '%s' && echo 1 || echo 0", fit)) + 0) {
  set logscale x
  set xlabel "--tolerance (fraction of the bounding-box diagonal)"
  set ylabel "segments"
  set y2label "fit error / diagonal (%)"
  set y2tics
  set ytics nomirror
  plot rows(fit, "1") using 1:2 with linespoints pt 7 lc 3 title "segments", \
       rows(fit, "1") using 1:($3*100) axes x1y2 with linespoints pt 5 lc 4 title "max (two-sided)", \
       rows(fit, "1") using 1:($4*100) axes x1y2 with linespoints pt 9 lc 6 title "mean", \
       2 axes x1y2 with lines dt 2 lc 0 title "goal 2 %"
}
unset multiplot
