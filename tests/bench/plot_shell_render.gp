# plot_shell_render.gp — charts of bench_shell_render's CSVs.
#   gnuplot -e 'dir="tests/bench/results"' tests/bench/plot_shell_render.gp
# Writes into dir:
#   shell_render_cost_error.png  ms/frame (left) and ray steps per pixel (right)
#       against the mean hit error (pixels) against the exact reference, one
#       colour per technique, one point type per knob swept
#   shell_render_table1.png      the paper's Table 1 on llvmpipe: ms/frame per
#       test and technique
if (!exists("dir")) dir = "tests/bench/results"
sw = dir."/shell_render_sweep.csv"
t1 = dir."/table1.csv"
cairo = strstrt(GPVAL_TERMINALS, "pngcairo") > 0
set datafile separator ","
rows(f, cond) = sprintf("< awk -F, 'NR > 1 && (%s)' '%s'", cond, f)
set grid
set key noenhanced outside right
if (cairo) { set terminal pngcairo size 1500,600 enhanced font "sans,11" } else { set terminal png size 1500,600 }
set output dir."/shell_render_cost_error.png"
set multiplot layout 1,2 title "shell ray casting on llvmpipe (spot + bricks, 400x300): cost against error vs the exact reference"
set logscale xy
set xlabel "mean hit error against the exact reference (pixels)"
set xrange [0.005:20]
set ylabel "ms / frame"
knobs = "error_px max_steps fixed_step dist_cells"
techs = "smooth curved tetra"
plot for [t=1:3] for [k=1:4] rows(sw, sprintf("$1==\"%s\" && $2==\"%s\" && $8>0", word(techs,t), word(knobs,k))) \
       using 8:4 with linespoints lc t pt (2*k+3) title sprintf("%s: %s", word(techs,t), word(knobs,k)), \
     for [t=1:3] rows(sw, sprintf("$1==\"%s\" && $2==\"defaults\"", word(techs,t))) using (($8>0)?$8:0.005):4 \
       with points lc t pt 3 ps 3 title sprintf("%s: defaults", word(techs,t))
set ylabel "ray steps per covered pixel"
plot for [t=1:3] for [k=1:4] rows(sw, sprintf("$1==\"%s\" && $2==\"%s\" && $8>0", word(techs,t), word(knobs,k))) \
       using 8:5 with linespoints lc t pt (2*k+3) title sprintf("%s: %s", word(techs,t), word(knobs,k)), \
     for [t=1:3] rows(sw, sprintf("$1==\"%s\" && $2==\"defaults\"", word(techs,t))) using (($8>0)?$8:0.005):5 \
       with points lc t pt 3 ps 3 title sprintf("%s: defaults", word(techs,t))
unset multiplot

reset
set datafile separator ","
set grid y
if (cairo) { set terminal pngcairo size 1100,500 enhanced font "sans,11" } else { set terminal png size 1100,500 }
set output dir."/shell_render_table1.png"
set title "Table 1 on llvmpipe (2 cores): spot + bricks"
set style data histograms
set style histogram clustered gap 1
set style fill solid 0.8 border -1
set logscale y
set ylabel "ms / frame"
set xtics rotate by -20 noenhanced
set key top left noenhanced
plot for [t in "segment smooth curved tetra"] sprintf("< awk -F, 'NR>1 && $2==\"%s\" {print $1\",\"$5}' '%s'", t, t1) \
     using 2:xtic(1) title t
