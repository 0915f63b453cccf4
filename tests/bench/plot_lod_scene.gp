# plot_lod_scene.gp — levels of detail in bench_lod_scene's 64-object scene.
#   gnuplot -e "dir='tests/bench/results'" tests/bench/plot_lod_scene.gp
# Left: frame time (the whole frame, and its draws timed alone and summed:
# the frame's own time moves between builds, README), bytes held on the
# GPU and read from the file, and shader steps per covered pixel at each
# pixel error tau, as a share of drawing the finest level everywhere (the
# dashed goal lines are the issue's: a third of the time, a fifth of the
# bytes). Right: mean error against the supersampled finest render (0..255
# per channel), the finest render's own error as the dashed line.
if (!exists("dir")) dir = "tests/bench/results"
csv = dir."/lod_scene.csv"
if (strstrt(GPVAL_TERMINALS, "pngcairo") > 0) {
    set terminal pngcairo size 1200,460 enhanced font "sans,10"
} else {
    set terminal png size 1200,460
}
set output dir."/lod_scene_chart.png"
set datafile separator ","

# The finest setting's value of a metric.
finest(m) = system("awk -F, '$1==\"scene\" && $2==\"finest\" && $3==\"".m."\" {print $4}' '".csv."'") + 0
fms = finest("ms"); falone = finest("ms_alone"); fres = finest("resident"); fgpu = finest("gpu_resident"); fsteps = finest("steps_px"); fmae = finest("mae")
# One metric's rows over tau, as "tau,value" lines (a filter in `using`
# would leave gaps that break the lines).
sel(m) = "< awk -F, '$1==\"scene\" && $2!=\"finest\" && $3==\"".m."\" {print $2\",\"$4}' '".csv."'"

set multiplot layout 1,2 title "64 objects of every kind, 1x to 100x their size away (320 x 240, llvmpipe)"
set logscale x 2
set xrange [0.4:20]
set xtics ("0.5" 0.5, "1" 1, "2" 2, "4" 4, "8" 8, "16" 16)
set xlabel "pixel error tau (px)"
set grid
set key top right
set ylabel "share of the finest level everywhere"
set yrange [0:1.1]
plot sel("ms") using 1:($2 / fms) with linespoints lw 2 title "frame time", \
     sel("ms_alone") using 1:($2 / falone) with linespoints lw 2 title "draws timed alone, summed", \
     sel("gpu_resident") using 1:($2 / fgpu) with linespoints lw 2 title "bytes held on the GPU", \
     sel("resident") using 1:($2 / fres) with linespoints lw 2 title "bytes read from the file", \
     sel("steps_px") using 1:($2 / fsteps) with linespoints lw 2 title "steps per covered pixel", \
     1.0 / 3 with lines dt 2 lc rgb "#444444" title "goal: time at 1 px", \
     0.2 with lines dt 3 lc rgb "#444444" title "goal: bytes at 1 px"
set ylabel "mean error against the supersampled finest render (/255)"
set yrange [0:*]
set key top left
plot sel("mae") using 1:2 with linespoints lw 2 title "levels at tau", \
     fmae with lines dt 2 lc rgb "#444444" title "finest level everywhere"
unset multiplot
