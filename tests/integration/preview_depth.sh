#!/bin/sh
# preview_depth.sh MESOBAKE MESOINSPECT DATA_DIR PNG_PROBE
#
# mesoinspect preview --depth standard|reversed (issue 18): every object
# kind baked from bundled data, previewed under standard depth and under
# reversed-Z (glClipControl 0..1, GL_GREATER, an infinite far plane). The
# two images must agree: the ray casters at all but 0.5 % of the pixels
# (float rounding of the unprojected rays at silhouettes), rasterised slices
# at all but 2 % (ties between coincident slice fragments follow the depth
# rounding; tests/gl/test_rt_conventions.c says the same per pixel), with
# either --slice-axis. A bad --depth or --slice-axis is a usage error
# (exit 1) that writes nothing.
set -u
bake=$1
inspect=$2
data=$3
probe=$4
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { # DESCRIPTION COMMAND...
  d=$1; shift
  if "$@"; then echo "ok   $d"; else echo "FAIL $d"; fail=1; fi
}

"$bake" mesh -i "$data/spot_low_resolution.obj" -o "$tmp/mesh.meso" >/dev/null 2>&1 &&
  "$bake" shell -i "$data/sphere.obj" -o "$tmp/shell.meso" --thickness-rel 0.05 --texture bricks:64 -j 2 \
    >/dev/null 2>&1 &&
  "$bake" frusta -i "$data/saguaro.skel" -o "$tmp/frusta.meso" --relief bricks:64 >/dev/null 2>&1 &&
  "$bake" cells -i "$data/spot_low_resolution.obj" -o "$tmp/cells.meso" -j 2 >/dev/null 2>&1
check "bakes succeed" test $? = 0

# name file allowed-per-mille [preview options]
for row in "mesh mesh 5" "shell shell 5" "curved shell 5 --technique curved" \
           "slices shell 20 --technique slices" "slices-levels shell 20 --technique slices --slice-axis levels" \
           "frusta frusta 5" "cells cells 5"; do
  set -- $row
  name=$1 file=$2 permille=$3
  shift 3
  "$inspect" preview "$tmp/$file.meso" -o "$tmp/$name-std.png" --size 128x128 "$@" >/dev/null 2>&1
  a=$?
  "$inspect" preview "$tmp/$file.meso" -o "$tmp/$name-rev.png" --size 128x128 --depth reversed "$@" >/dev/null 2>&1
  b=$?
  check "$name: both previews written" test $a = 0 -a $b = 0 -a -s "$tmp/$name-std.png" -a -s "$tmp/$name-rev.png"
  out=$("$probe" --diff "$tmp/$name-std.png" "$tmp/$name-rev.png")
  differing=${out% *}
  echo "     $name: $out (pixels differing by > 2, largest difference)"
  check "$name: reversed-Z agrees at all but $permille per mille of 128x128" \
    test "${differing:-99999}" -le $((128 * 128 * permille / 1000))
done

# The depth pass's picture (grey = eye depth) under both conventions.
"$inspect" preview "$tmp/shell.meso" -o "$tmp/zs.png" --size 128x128 --pass depth >/dev/null 2>&1 &&
  "$inspect" preview "$tmp/shell.meso" -o "$tmp/zr.png" --size 128x128 --pass depth --depth reversed >/dev/null 2>&1
check "--pass depth: written under both conventions" test $? = 0
out=$("$probe" --diff "$tmp/zs.png" "$tmp/zr.png")
echo "     depth pass: $out"
check "--pass depth --depth reversed: the same eye-depth picture (5 per mille)" \
  test "${out% *}" -le $((128 * 128 * 5 / 1000))

"$inspect" preview "$tmp/shell.meso" -o "$tmp/bad.png" --depth sideways >/dev/null 2>"$tmp/err"
check "--depth sideways: usage error (exit 1)" test $? = 1
check "--depth sideways: says what it expects" grep -q "standard or reversed" "$tmp/err"
check "--depth sideways: writes nothing" test ! -e "$tmp/bad.png"
"$inspect" preview "$tmp/shell.meso" -o "$tmp/bad.png" --technique slices --slice-axis diagonal >/dev/null 2>"$tmp/err"
check "--slice-axis diagonal: usage error (exit 1)" test $? = 1
check "--slice-axis diagonal: says what it expects" grep -q "view or levels" "$tmp/err"
check "--slice-axis diagonal: writes nothing" test ! -e "$tmp/bad.png"
exit $fail
