#!/bin/sh
# examples/embed_minimal opens a real GLFW window under Xvfb and draws three
# frames of a baked frusta object (the saguaro) and of a shell; a missing
# file exits 2 and a missing argument 1.
# usage: embed_minimal_xvfb.sh EMBED_MINIMAL MESOBAKE TEST_DATA_DIR
set -eu
prog=$1 bake=$2 data=$3
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$bake" frusta -i "$data/saguaro.skel" -o "$out/saguaro.meso" >/dev/null 2>&1
"$bake" shell -i "$data/sphere.obj" --texture bricks:32 -j 2 -o "$out/sphere.meso" >/dev/null 2>&1
for f in saguaro sphere; do
  xvfb-run -a -s "-screen 0 640x480x24" "$prog" "$out/$f.meso" --frames 3 ||
    { echo "embed_minimal $f.meso --frames 3 exited $?"; exit 1; }
done
rc=0; xvfb-run -a -s "-screen 0 640x480x24" "$prog" "$out/none.meso" --frames 1 2>/dev/null || rc=$?
[ $rc = 2 ] || { echo "a missing file exited $rc, expected 2"; exit 1; }
rc=0; "$prog" 2>/dev/null || rc=$?
[ $rc = 1 ] || { echo "no argument exited $rc, expected 1"; exit 1; }
echo "embed_minimal: three frames of a frusta object and of a shell in a window"
