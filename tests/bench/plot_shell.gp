# plot_shell.gp — charts of bench_shell's CSVs (tests/bench/results/shell_*.csv).
#   gnuplot -e 'dir="tests/bench/results"' tests/bench/plot_shell.gp
# Writes into dir:
#   shell_size.png       bake time (and peak RSS) vs triangles, log-log, per mode,
#                        with the issue #4 goals (2 s @ 100k, 30 s @ 1M, 2 GB)
#   shell_accuracy.png   max director error vs time for the θ × angle-tolerance sweep,
#                        one line per tolerance (points: θ), one panel per mesh
#   shell_thickness.png  inverted prisms + offset intersections vs thickness,
#                        one panel per mesh and side, one line per method
if (!exists("dir")) dir = "tests/bench/results"
size_csv = dir."/shell_size.csv"
acc_csv = dir."/shell_accuracy.csv"
thk_csv = dir."/shell_thickness.csv"
cairo = strstrt(GPVAL_TERMINALS, "pngcairo") > 0
set datafile separator ","
set grid
set key noenhanced

# (a) ------------------------------------------------------------------------
if (cairo) { set terminal pngcairo size 1400,600 enhanced font "sans,11" } else { set terminal png size 1400,600 }
set output dir."/shell_size.png"
set multiplot layout 1,2 title "mesobake shell on spot subdivided 1:4 — exterior, 5 % of the diagonal, 2 threads, θ 0.5, 5°, repair"
set logscale xy
set format x "10^{%L}"
set xlabel "triangles"
set ylabel "seconds"
set key top left
set label 1 "goal 2 s @ 100k" at 1.1e5, 2 left offset 1,0
set label 2 "goal 30 s @ 1M" at 1.1e6, 30 left offset 1,0
plot size_csv using (strcol(3) eq "hybrid" ? $1 : 1/0):11 with linespoints lw 2 pt 7 lc rgb "#1f77b4" title "hybrid: total", \
     size_csv using (strcol(3) eq "hybrid" ? $1 : 1/0):8 with linespoints dt 2 pt 6 lc rgb "#1f77b4" title "hybrid: directors (incl. checks of each round)", \
     size_csv using (strcol(3) eq "hybrid" ? $1 : 1/0):($10 + $9) with linespoints dt 3 pt 4 lc rgb "#1f77b4" title "hybrid: repair + validation", \
     size_csv using (strcol(3) eq "hybrid" ? $1 : 1/0):($7 + $6) with linespoints dt 4 pt 8 lc rgb "#1f77b4" title "hybrid: normals + field build", \
     size_csv using (strcol(3) eq "lp" ? $1 : 1/0):11 with linespoints lw 2 pt 5 lc rgb "#d62728" title "lp (all vertices): total", \
     size_csv using (strcol(3) eq "lp" ? $1 : 1/0):8 with linespoints dt 2 pt 4 lc rgb "#d62728" title "lp: directors", \
     '+' using (1e5):(2) every ::0::0 with points pt 3 ps 3 lw 2 lc rgb "black" notitle, \
     '+' using (1e6):(30) every ::0::0 with points pt 3 ps 3 lw 2 lc rgb "black" notitle
unset label 1
unset label 2
set ylabel "peak RSS, MB (own process)"
set label 3 "goal 2 GB" at graph 0.02, first 2300 left
plot size_csv using (strcol(3) eq "hybrid" ? $1 : 1/0):13 with linespoints lw 2 pt 7 lc rgb "#1f77b4" title "hybrid", \
     size_csv using (strcol(3) eq "lp" ? $1 : 1/0):13 with linespoints lw 2 pt 5 lc rgb "#d62728" title "lp", \
     2048 with lines dt 2 lc rgb "black" title "2 GB"
unset label 3
unset multiplot

# (b) ------------------------------------------------------------------------
meshes = system("tail -n +2 '".acc_csv."' | cut -d, -f1 | uniq | tr '\\n' ' '")
nm = words(meshes)
if (cairo) { set terminal pngcairo size 700*nm,560 enhanced font "sans,11" } else { set terminal png size 700*nm,560 }
set output dir."/shell_accuracy.png"
set multiplot layout 1,nm title "Director error vs time: all-Lp exterior directors at 10 %; reference θ = 0 (exact), 0.5°; points left to right: θ = 1, 0.7, 0.5, 0.35, 0.2, 0 (exact)"
set logscale xy
set format x "10^{%L}"
set format y "10^{%L}"
set xlabel "seconds (directors only, 2 threads)"
set ylabel "max |d − d_{ref}| / h"
set key bottom left
tols = "1 2 5 10 20"
do for [m in meshes] {
    set title m noenhanced
    plot for [t in tols] acc_csv using (strcol(1) eq m && $6 == real(t) ? $7 : 1/0):9 with linespoints lw 2 title "tolerance ".t."°", \
         acc_csv using (strcol(1) eq m && $6 == 5 ? $7 : 1/0):9:(sprintf("θ %.2g", $5)) with labels offset 0,-1 font ",8" notitle
}
unset title
unset multiplot

# (c) ------------------------------------------------------------------------
meshes = system("tail -n +2 '".thk_csv."' | cut -d, -f1 | uniq | tr '\\n' ' '")
nm = words(meshes)
if (cairo) { set terminal pngcairo size 460*nm,900 enhanced font "sans,10" } else { set terminal png size 460*nm,900 }
set output dir."/shell_thickness.png"
set multiplot layout 2,nm title "Where each method fails: inverted prisms + offset self- and offset/base intersections vs thickness (0 drawn at the bottom)"
unset logscale
set logscale y
set format x "%g"
set format y "%g"
set xlabel "thickness, % of the bbox diagonal"
set ylabel "failing prisms + intersecting pairs"
set xrange [0:42]
set yrange [0.5:*]
set ytics ("0" 0.5, "1" 1, "10" 10, "100" 100, "10^3" 1000, "10^4" 10000, "10^5" 100000)
set key top left font ",8"
fail(a,b,c) = (a + b + c) > 0 ? a + b + c : 0.5
methods = "normal lp hybrid"
colors = "#2ca02c #d62728 #1f77b4"
do for [side in "exterior interior"] {
    do for [m in meshes] {
        set title m." — ".side noenhanced
        plot for [i=1:3] thk_csv using (strcol(1) eq m && strcol(3) eq side && strcol(5) eq word(methods,i) && $6 == 0 ? 100*$4 : 1/0):(fail($7,$9,$10)) \
                 with linespoints lw 2 pt 7 ps 0.8 lc rgb word(colors,i) title word(methods,i), \
             for [i=1:3] thk_csv using (strcol(1) eq m && strcol(3) eq side && strcol(5) eq word(methods,i) && $6 == 1 ? 100*$4 : 1/0):(fail($7,$9,$10)) \
                 with linespoints lw 1 dt 2 pt 6 ps 0.8 lc rgb word(colors,i) title word(methods,i)." + repair"
    }
}
unset multiplot
