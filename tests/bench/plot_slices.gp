# plot_slices.gp — the chart of bench_slices' CSVs (issue #19: Figure 12 of
# papers/volume-textures-lp-averaged-shells.md recreated).
#   gnuplot -e 'dir="tests/bench/results"' tests/bench/plot_slices.gp
# Writes dir/slices_error_time.png: normal error (median left, mean right,
# degrees, against the exact reference) against ms/frame on llvmpipe, one
# line per slice variant as the slice count runs 4..64 (labelled), and
# smooth ray casting as its error bound runs 0.25..16 px and its step limit
# 4..64 (labelled).
if (!exists("dir")) dir = "tests/bench/results"
f = dir."/slices.csv"
cairo = strstrt(GPVAL_TERMINALS, "pngcairo") > 0
set datafile separator ","
rows(cond) = sprintf("< awk -F, 'NR > 1 && (%s)' '%s'", cond, f)
set grid
set key noenhanced bottom left
if (cairo) { set terminal pngcairo size 1400,560 enhanced font "sans,11" } else { set terminal png size 1400,560 }
set output dir."/slices_error_time.png"
set multiplot layout 1,2 title "Figure 12 on llvmpipe (icospheres in a unit-cube shell, 400x400): normal error against time"
set logscale xy
set xlabel "ms / frame (median of 11, glFinish)"
conds = "$1==\"none\" $1==\"normal\" $1==\"texcoord\" $2==\"error_px\" $2==\"max_steps\""
titles = "'slices, no interpolation' 'slices, normal interpolation' 'slices, texture-coordinate interpolation' 'smooth ray casting, error bound 0.25..16 px' 'smooth ray casting, step limit 4..64'"
do for [col in "9 8"] {
    set ylabel (col eq "9" ? "median" : "mean")." normal error (degrees)"
    plot for [i=1:5] rows(word(conds,i)) using 4:(column(int(col))) \
           with linespoints lw 2 pt (4+i) title word(titles,i), \
         rows("$2!=\"error_px\"") using 4:(column(int(col))):3 with labels offset 0.8,0.6 font ",8" notitle
}
unset multiplot
