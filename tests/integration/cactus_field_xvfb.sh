#!/bin/sh
# The cactus field (examples/cactus_field.c) under Xvfb: bakes the saguaro
# (frusta, ribs relief) and a rock (shell, cobble) with mesobake, draws 12
# frames of 144 swaying cacti and 40 rocks in a real GLFW window, and checks
# the screenshot: its size, sky in the top corners, sand in the bottom ones,
# and cactus-green pixels in between.
# usage: cactus_field_xvfb.sh CACTUS_FIELD MESOBAKE PNG_PROBE DATA_DIR
set -eu
field=$1 bake=$2 probe=$3 data=$4
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$bake" frusta -i "$data/saguaro.skel" --relief ribs:64 --relief-repeat 14 -o "$out/cactus.meso" >/dev/null 2>&1
"$bake" shell -i "$data/sphere.obj" --texture cobble:32 --tiling 2 -j 2 -o "$out/rock.meso" >/dev/null 2>&1
xvfb-run -a -s "-screen 0 640x480x24" "$field" "$out/cactus.meso" "$out/rock.meso" --size 320x180 --frames 12 \
  --screenshot "$out/shot.png"
set -- $("$probe" "$out/shot.png" | tr '\n' ' ')
[ "$1" = 320 ] && [ "$2" = 180 ] || { echo "screenshot is $1x$2, expected 320x180"; exit 1; }
# Rows: png_probe's corners are (0,0) (w-1,0) (0,h-1) (w-1,h-1) of the PNG, top row first.
[ "$5" -gt "$3" ] || { echo "top-left corner $3 $4 $5 is not sky"; exit 1; }
[ "${11}" -gt "${13}" ] || { echo "bottom-left corner ${11} ${12} ${13} is not sand"; exit 1; }
green=$("$probe" "$out/shot.png" --dominant g)
[ "$green" -gt 1500 ] || { echo "only $green cactus-green pixels"; exit 1; }
echo "cactus_field: 320x180 screenshot with sky, sand and $green cactus-green pixels"
