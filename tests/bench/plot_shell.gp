# plot_shell.gp — charts of bench_shell's CSVs (tests/bench/results/shell_*.csv).
#   gnuplot -e 'dir="tests/bench/results"' tests/bench/plot_shell.gp
# Writes into dir:
#   shell_size.png       bake time (and peak RSS) vs triangles, log-log, per mode,
#                        with the stage split, OpenVDB's level set as a reference
#                        and the goals (2 s @ 100k, 30 s @ 1M, 2 GB)
#   shell_accuracy.png   max director error vs time for the θ × angle-tolerance sweep,
#                        one line per tolerance (points: θ), one panel per mesh
#   shell_thickness.png  inverted prisms + offset intersections vs thickness,
#                        one panel per mesh and side, one line per method; bottom
#                        row: thickness kept by repair (mean and min ratio)
#   shell_kept.png       achieved / allowed thickness per vertex on every closed
#                        mesh (distribution per mesh and side, mean per mesh)
if (!exists("dir")) dir = "tests/bench/results"
size_csv = dir."/shell_size.csv"
acc_csv = dir."/shell_accuracy.csv"
thk_csv = dir."/shell_thickness.csv"
cairo = strstrt(GPVAL_TERMINALS, "pngcairo") > 0
set datafile separator ","
# rows of a CSV whose awk condition holds (keeps line segments unbroken)
rows(f, cond) = sprintf("< awk -F, 'NR > 1 && (%s)' '%s'", cond, f)
set grid
set key noenhanced

# (a) ------------------------------------------------------------------------
if (cairo) { set terminal pngcairo size 1400,600 enhanced font "sans,11" } else { set terminal png size 1400,600 }
set output dir."/shell_size.png"
set multiplot layout 1,2 title "mesobake shell (the whole bake, mesh in memory) on spot subdivided 1:4 — exterior, 5 % of the diagonal, 2 threads, CLI defaults (θ 0.5, no smoothing, repair, stand-in levels)"
set logscale xy
set xrange [1000:3e6]
set format x "10^{%L}"
set xlabel "triangles"
set ylabel "seconds"
set key top left
set label 1 "goal 2 s @ 100k" at 1.1e5, 2 left offset 1,0
set label 2 "goal 30 s @ 1M" at 1.1e6, 30 left offset 1,0
H = rows(size_csv, '$3 == "hybrid"')
L = rows(size_csv, '$3 == "lp"')
V = rows(size_csv, '$3 == "vdb"')
set key bottom right
plot H using 1:11 with linespoints lw 2 pt 7 lc rgb "#1f77b4" title "hybrid: total", \
     H using 1:8 with linespoints dt 2 pt 6 lc rgb "#1f77b4" title "hybrid: directors (incl. checks of each round)", \
     H using 1:($10 + $9) with linespoints dt 3 pt 4 lc rgb "#1f77b4" title "hybrid: repair + regrow + validation", \
     H using 1:($22 + $7 + $5 + $4) with linespoints dt 4 pt 8 lc rgb "#1f77b4" title "hybrid: mesh checks + topology + base check + normals + field", \
     H using 1:($23 + $24) with linespoints dt 5 pt 12 lc rgb "#1f77b4" title "hybrid: allowed thickness + stand-in levels + bytes", \
     L using 1:11 with linespoints lw 2 pt 5 lc rgb "#d62728" title "lp (all vertices): total", \
     V using 1:11 with linespoints lw 2 dt 2 pt 9 lc rgb "#2ca02c" title "OpenVDB narrow-band level set, 512 across (reference)", \
     '+' using (1e5):(2) every ::0::0 with points pt 3 ps 3 lw 2 lc rgb "black" notitle, \
     '+' using (1e6):(30) every ::0::0 with points pt 3 ps 3 lw 2 lc rgb "black" notitle
unset label 1
unset label 2
set ylabel "peak RSS, MB (own process)"
set key top left
# lp wide underneath: both modes hold the same arrays, so the lines coincide
plot L using 1:13 with linespoints lw 5 pt 5 ps 1.4 lc rgb "#d62728" title "lp", \
     H using 1:13 with linespoints lw 2 pt 7 lc rgb "#1f77b4" title "hybrid", \
     V using 1:13 with linespoints lw 2 dt 2 pt 9 lc rgb "#2ca02c" title "OpenVDB level set, 512 across", \
     2048 with lines dt 2 lc rgb "black" title "goal: 2 GB"
unset multiplot

# (b) ------------------------------------------------------------------------
meshes = system("tail -n +2 '".acc_csv."' | cut -d, -f1 | uniq | tr '\\n' ' '")
nm = words(meshes)
width = nm < 2 ? 1200 : 700*nm
if (cairo) { set terminal pngcairo size width,560 enhanced font "sans,11" } else { set terminal png size width,560 }
set output dir."/shell_accuracy.png"
unset xrange
set multiplot layout 1,nm title "Director error vs time: all-Lp exterior directors at 10 % (raw traces), reference θ = 0 (exact) at 0.5°\nalong each line left to right: θ = 1, 0.7, 0.5, 0.35, 0.2, 0 (exact); labels on the 5° line"
set logscale xy
set format x "10^{%L}"
set format y "10^{%L}"
set xlabel "seconds (directors only, 2 threads)"
set ylabel "max |d − d_{ref}| / h"
set key bottom left
tols = "1 2 5 10 20"
do for [m in meshes] {
    set title m noenhanced
    plot for [t in tols] rows(acc_csv, sprintf('$1 == "%s" && $6 == %s', m, t)) using 7:9 with linespoints lw 2 title "tolerance ".t."°", \
         rows(acc_csv, sprintf('$1 == "%s" && $6 == 5', m)) using 7:9:(sprintf("θ %.2g", $5)) with labels offset 0,-1 font ",8" notitle
}
unset title
unset multiplot

# (c) ------------------------------------------------------------------------
meshes = system("tail -n +2 '".thk_csv."' | cut -d, -f1 | uniq | tr '\\n' ' '")
nm = words(meshes)
if (cairo) { set terminal pngcairo size 460*nm,1300 enhanced font "sans,10" } else { set terminal png size 460*nm,1300 }
set output dir."/shell_thickness.png"
set multiplot layout 3,nm title "Where each method fails: inverted prisms + offset self- and offset/base intersections vs thickness (0 drawn at the bottom)"
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
# lp is drawn wide under hybrid: the two coincide wherever hybrid's Lp region is everything
widths = "2 5 1.5"
do for [side in "exterior interior"] {
    do for [m in meshes] {
        set title m." — ".side noenhanced
        if (m eq word(meshes,1)) { set key top left font ",8" } else { unset key }
        plot for [i=1:3] rows(thk_csv, sprintf('$1 == "%s" && $3 == "%s" && $5 == "%s" && $6 == 0', m, side, word(methods,i))) \
                 using (100*$4):(fail($7,$9,$10)) with linespoints lw word(widths,i) pt 7 ps 0.8 lc rgb word(colors,i) title word(methods,i), \
             for [i=1:3] rows(thk_csv, sprintf('$1 == "%s" && $3 == "%s" && $5 == "%s" && $6 == 1', m, side, word(methods,i))) \
                 using (100*$4):(fail($7,$9,$10)) with linespoints lw 1 dt 2 pt 6 ps 0.8 lc rgb word(colors,i) title word(methods,i)." + repair"
    }
}
# Bottom row: with repair every run above is valid; what it costs is thickness.
unset logscale y
set yrange [0:1.05]
set ytics auto
set ylabel "thickness kept: |d| / h after repair"
set key bottom left font ",8"
do for [m in meshes] {
    set title m." — with repair: mean ratio (lines), min (+)" noenhanced
    if (m eq word(meshes,1)) { set key bottom left font ",8" } else { unset key }
    plot for [i=1:3] rows(thk_csv, sprintf('$1 == "%s" && $3 == "exterior" && $5 == "%s" && $6 == 1', m, word(methods,i))) \
             using (100*$4):12 with linespoints lw word(widths,i) pt 7 ps 0.8 lc rgb word(colors,i) title word(methods,i)." exterior", \
         for [i=1:3] rows(thk_csv, sprintf('$1 == "%s" && $3 == "interior" && $5 == "%s" && $6 == 1', m, word(methods,i))) \
             using (100*$4):12 with linespoints lw word(widths,i) dt 2 pt 6 ps 0.8 lc rgb word(colors,i) title word(methods,i)." interior", \
         for [i=1:3] rows(thk_csv, sprintf('$1 == "%s" && $5 == "%s" && $6 == 1', m, word(methods,i))) \
             using (100*$4):11 with points pt 1 ps 0.6 lc rgb word(colors,i) notitle
}
unset title
unset multiplot

# (d) ------------------------------------------------------------------------
# shell_kept.png: achieved / allowed thickness per vertex (bake/shell_allowed.h)
# on every closed mesh, hybrid + repair at 10 % exterior / 5 % interior:
# the fraction of vertices below x (log; meshes that keep everything have
# none and draw no line), and the mean per mesh against the goal 0.95.
kept_csv = dir."/shell_kept.csv"
dist_csv = dir."/shell_kept_dist.csv"
if (system("test -s '".dist_csv."' && echo 1") eq "1") {
    meshes = system("tail -n +2 '".kept_csv."' | cut -d, -f1 | uniq | tr '\\n' ' '")
    nm = words(meshes)
    kept_colors = "#1f77b4 #ff7f0e #2ca02c #d62728 #9467bd #8c564b #e377c2 #7f7f7f #bcbd22 #17becf #000000 #aec7e8 #ffbb78 #98df8a #ff9896 #c5b0d5"
    if (cairo) { set terminal pngcairo size 1500,560 enhanced font "sans,10" } else { set terminal png size 1500,560 }
    set output dir."/shell_kept.png"
    set multiplot layout 1,3 title "Thickness kept against what the geometry allows (min(h, half the gap along the normal)): hybrid + repair + regrow + bend, CLI defaults\n(wingnut: the CLI refuses it, its surface intersects itself; the bench bakes it anyway and its shells are not valid)"
    unset logscale
    unset xrange
    unset yrange
    set logscale y
    set xrange [0:1]
    set yrange [1e-4:1]
    set format x "%g"
    set format y "10^{%L}"
    set ytics auto
    set xlabel "achieved / allowed (per vertex, capped at 1)"
    set ylabel "fraction of vertices below"
    set arrow 1 from 0.5, graph 0 to 0.5, graph 1 nohead dt 2 lc rgb "black"
    set label 3 "goal: none below 0.5" at 0.51, 2e-4 left
    set key top left font ",8"
    do for [side in "exterior interior"] {
        set title side.(side eq "exterior" ? " — 10 % of the diagonal" : " — 5 % of the diagonal")
        plot for [i=1:nm] rows(dist_csv, sprintf('$1 == "%s" && $2 == "%s" && $5 > 0', word(meshes,i), side)) \
             using 3:5 with lines lw 2 lc rgb word(kept_colors, 1 + (i - 1) % 16) title word(meshes,i)
    }
    unset arrow 1
    unset label 3
    unset logscale y
    set format y "%g"
    set yrange [0.7:1.01]
    set xrange [-0.5:nm - 0.5]
    set xtics rotate by -40 font ",8" noenhanced
    set xtics ("" 0)
    do for [i=1:nm] { set xtics add (word(meshes,i) i - 1) }
    set xlabel ""
    set ylabel "mean achieved / allowed"
    set title "mean per mesh (goal >= 0.95)"
    set key bottom left
    plot rows(kept_csv, '$3 == "exterior"') using ($0 - 0.15):8 with points pt 7 ps 1.2 lc rgb "#1f77b4" title "exterior 10 %", \
         rows(kept_csv, '$3 == "interior"') using ($0 + 0.15):8 with points pt 5 ps 1.2 lc rgb "#d62728" title "interior 5 %", \
         0.95 with lines dt 2 lc rgb "black" title "goal 0.95"
    unset title
    unset multiplot
    set xtics norotate
}
