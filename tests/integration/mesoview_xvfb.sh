#!/bin/sh
# mesoview opens a real GLFW window under Xvfb, draws two frames and saves a
# screenshot whose size and clear colour are checked.
# usage: mesoview_xvfb.sh MESOVIEW PNG_PROBE
set -eu
view=$1 probe=$2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
xvfb-run -a -s "-screen 0 640x480x24" "$view" --size 320x200 --frames 2 --screenshot "$out/shot.png"
set -- $("$probe" "$out/shot.png" | head -n 2 | tr '\n' ' ')
[ "$1" = 320 ] && [ "$2" = 200 ] || { echo "screenshot is $1x$2, expected 320x200"; exit 1; }
# Clear colour (0.18, 0.20, 0.24) in 8 bits: 46 51 61 (rounding may differ by one).
r=$3 g=$4 b=$5
for pair in "$r 46" "$g 51" "$b 61"; do
  set -- $pair
  d=$(( $1 - $2 )); [ $d -lt 0 ] && d=$(( -d ))
  [ $d -le 1 ] || { echo "corner pixel $r $g $b, expected about 46 51 61"; exit 1; }
done
echo "mesoview: window opened, screenshot 320x200 with the clear colour"
