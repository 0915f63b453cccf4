#!/bin/sh
# mesoview_keys.sh MESOVIEW MESOBAKE MESOINSPECT DATA_DIR
#
# mesoview's levels of detail live (issue 14, Deliver 4): under Xvfb, with
# keys pressed through its keyboard handler (--keys, one a frame) and its
# window titles printed (--print-title), P and O double and halve the pixel
# error from libmeso's default 1 px (0.125 .. 64, below that the finest
# levels), and each title names the pixel error, the level drawn, the
# bytes resident and the frame time. The level it names at each pixel
# error is the one `mesoinspect preview --pixel-error` draws for the same
# view and image size (both frame the bounds alike: yaw 30, pitch 20,
# 35 degrees; preview's pixel error counts pixels of its PNG). An unknown
# key is refused.
set -u
MV=$1
MB=$2
MI=$3
DATA=$4
. "$(dirname "$0")/check_lib.sh"

run "$MB" mesh -i "$DATA/spot_uv.obj" -o "$T/spot.meso"
if [ "$rc" -eq 5 ]; then
    echo "SKIP: mesobake has no mesh import in this build" >&2
    exit 77
fi
expect_rc 0 "bake spot_uv"

keys=PPPOOOOOOO
run xvfb-run -a -s "-screen 0 640x480x24" "$MV" "$T/spot.meso" --size 320x200 --frames 11 --keys "$keys" --print-title
expect_rc 0 "mesoview --keys $keys"
cp "$T/out" "$T/titles"
expect_eq "$(wc -l <"$T/titles" | tr -d ' ')" 11 "one title for the first frame and one per key"

# The pixel error each title should show, from the keys: 1 2 4 8 4 2 1 0.5 0.25 0.125 finest.
want="1 2 4 8 4 2 1 0.5 0.25 0.125 finest"
i=0
for tau in $want; do
    i=$((i + 1))
    line=$(sed -n "${i}p" "$T/titles")
    lod=$(printf '%s\n' "$line" | sed -n 's/.*  lod \([0-9]*\)\/[0-9]* at .*/\1/p')
    if [ "$tau" = finest ]; then
        shown=$(printf '%s\n' "$line" | sed -n 's/.* at finest \([0-9.]*\) px, .*/finest/p')
        expect_eq "$shown" finest "title $i names the finest levels: $line"
        expect_eq "$lod" 0 "title $i: the finest levels draw lod 0"
        continue
    fi
    shown=$(printf '%s\n' "$line" | sed -n 's/.* at \([0-9.]*\) px, [0-9]* KiB.*/\1/p')
    expect_eq "$shown" "$tau" "title $i shows pixel error $tau: $line"
    printf '%s\n' "$line" | grep -Eq '  [0-9]+\.[0-9] ms/frame' && ok || fail "title $i has no frame time: $line"
    printf '%s\n' "$line" | grep -Eq ' [1-9][0-9]* KiB' && ok || fail "title $i has no bytes resident: $line"
    run "$MI" preview "$T/spot.meso" -o "$T/p.png" --size 320x200 --pixel-error "$tau" --stats "$T/s.json"
    expect_rc 0 "preview at $tau px"
    ref=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["objects"][0]["levels_drawn"])' "$T/s.json")
    expect_eq "$lod" "$ref" "at $tau px mesoview draws the level preview draws"
done
# The levels follow the pixel error: coarser at 8 px than at 1 px.
l1=$(sed -n 1p "$T/titles" | sed -n 's/.*  lod \([0-9]*\)\/.*/\1/p')
l8=$(sed -n 4p "$T/titles" | sed -n 's/.*  lod \([0-9]*\)\/.*/\1/p')
[ "${l8:-0}" -gt "${l1:-0}" ] && ok || fail "lod at 8 px ($l8) is not coarser than at 1 px ($l1)"

run xvfb-run -a -s "-screen 0 640x480x24" "$MV" "$T/spot.meso" --frames 1 --keys PQ
expect_rc 1 "an unknown key is refused"
expect_err "--keys: 'Q' is not one of" "the refusal names the key"

echo "mesoview_keys: $checks checks, $failures failures"
[ "$failures" -eq 0 ]
