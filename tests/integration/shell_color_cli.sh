#!/bin/sh
# mesobake shell --color from the command line (FORMAT.md §7.2 "Shell
# colour", issue 16): the COLR + CMAP chunks each kind of SPEC writes (dims,
# mapping, scale), COLR bytes equal to the source texels (a PNG's rows
# flipped so that the bottom row is t = 0; a raw volume as is), META's
# "color", byte-identical output for -j 1 and -j 2, default bakes (no
# --color) unchanged by the option's existence (no COLR, no CMAP, no
# "color"), and bad inputs: a coded error, the documented exit code and no
# output file.
# usage: shell_color_cli.sh MESOBAKE MESOINSPECT TEST_DATA_DIR
set -u
bake=$1 inspect=$2 data=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { # DESCRIPTION COMMAND...
  d=$1; shift
  if "$@"; then echo "ok   $d"; else echo "FAIL $d"; fail=1; fi
}
col="$data/color"
quad="$tmp/quad.obj"
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n' >"$quad"
chunk_row() { "$inspect" info "$1" | awk -v t="$2" '$2 == t'; }
# hexdump of a chunk's payload, one byte a line
payload() { "$inspect" dump "$1" "$2" -o "$tmp/payload" >/dev/null 2>&1 && od -An -v -tu1 "$tmp/payload" | tr -s ' \n' '\n\n' | grep -v '^$'; }

# 1. A PNG, tiled: COLR 8x8x1 U8x4 = the PNG's texels, bottom row first; CMAP TILED, scale 1, 1.
"$bake" shell -i "$quad" -o "$tmp/png.meso" --thickness 0.1 --texture bricks:32 --tiling 2,3 \
  --color "$col/color8.png" -j 1 >/dev/null 2>&1
"$bake" shell -i "$quad" -o "$tmp/png2.meso" --thickness 0.1 --texture bricks:32 --tiling 2,3 \
  --color "$col/color8.png" -j 2 >/dev/null 2>&1
check "png: bake succeeds" test -s "$tmp/png.meso"
check "png: -j 1 and -j 2 give byte-identical files" cmp -s "$tmp/png.meso" "$tmp/png2.meso"
check "png: validates fully" sh -c "'$inspect' validate --full '$tmp/png.meso' >/dev/null"
check "png: COLR u8 x 4, 8x8x1 on object 1" sh -c "'$inspect' info '$tmp/png.meso' | awk '\$2 == \"COLR\" && \$4 == 1 && \$7 == \"u8\" && \$8 == 4 && \$9 == \"8x8x1\"' | grep -q ."
check "png: one CMAP record on object 1" sh -c "'$inspect' info '$tmp/png.meso' | awk '\$2 == \"CMAP\" && \$4 == 1 && \$11 == 32' | grep -q ."
# texel (x, y) of the PNG (y from the top) is r = 16 + 28x, g = 16 + 28y, b = 200 - 12(x + y):
# COLR row 0 is the PNG's bottom row (y = 7)
expect=$(awk 'BEGIN { for (r = 0; r < 8; r++) { y = 7 - r; for (x = 0; x < 8; x++) printf "%d\n%d\n%d\n255\n", 16 + 28 * x, 16 + 28 * y, 200 - 12 * (x + y) } }')
check "png: COLR holds the PNG's texels, bottom row first" test "$(payload "$tmp/png.meso" COLR)" = "$expect"
# mapping 0, flags 0, scale (1.0f, 1.0f) = 00 00 80 3f, 16 reserved zeros
cmap_tiled=$(printf '0\n0\n0\n0\n0\n0\n0\n0\n0\n0\n128\n63\n0\n0\n128\n63\n'; i=0; while [ $i -lt 16 ]; do echo 0; i=$((i + 1)); done)
check "png: CMAP is TILED with scale 1, 1" test "$(payload "$tmp/png.meso" CMAP)" = "$cmap_tiled"
check "png: META records the colour" sh -c "'$inspect' info '$tmp/png.meso' --format json | tr -d ' \t\n' | grep -q '\"color\":{\"spec\":\"[^\"]*color8.png\",\"source\":\"png\",\"res\":\[8,8\],\"mapping\":\"tiled\"}'"

# 2. from-mesh: the glTF box's 4x4 base colour x factor (1, 0.8, 0.6), mapping BASE, scale 1/tiling.
"$bake" shell -i "$data/gltf/box.gltf" -o "$tmp/mesh.meso" --texture bricks:32 --tiling 4,2 --color from-mesh \
  >/dev/null 2>&1
check "from-mesh: validates fully" sh -c "'$inspect' validate --full '$tmp/mesh.meso' >/dev/null"
check "from-mesh: COLR 4x4x1" sh -c "'$inspect' info '$tmp/mesh.meso' | awk '\$2 == \"COLR\" && \$9 == \"4x4x1\"' | grep -q ."
# mapping 1, flags 0, scale (0.25f, 0.5f) = 00 00 80 3e, 00 00 00 3f
cmap_base=$(printf '1\n0\n0\n0\n0\n0\n0\n0\n0\n0\n128\n62\n0\n0\n0\n63\n'; i=0; while [ $i -lt 16 ]; do echo 0; i=$((i + 1)); done)
check "from-mesh: CMAP is BASE with scale 1/4, 1/2" test "$(payload "$tmp/mesh.meso" CMAP)" = "$cmap_base"
# The glTF image's top-left quadrant (200, 40, 40) is COLR's top rows (t = 1): texel (0, 3),
# times the factor (1, 0.8, 0.6) in linear light, re-encoded to sRGB and rounded.
red=$(awk 'function lin(x) { return x <= 0.04045 ? x / 12.92 : exp(2.4 * log((x + 0.055) / 1.055)) }
           function enc(x) { return x <= 0.0031308 ? 12.92 * x : 1.055 * exp(log(x) / 2.4) - 0.055 }
           function r8(x) { return int(255 * enc(x) + 0.5) }
           BEGIN { printf "%d %d %d 255 ", r8(lin(200 / 255)), r8(lin(40 / 255) * 0.8), r8(lin(40 / 255) * 0.6) }')
check "from-mesh: COLR texel (0, 3) is red x factor ($red)" test "$(payload "$tmp/mesh.meso" COLR | sed -n '49,52p' | tr '\n' ' ')" = "$red"

# 3. A raw RGBA8 volume over a volume texture: COLR 4x4x2, the file's bytes.
printf '\377%.0s' $(seq 1 512) >"$tmp/ones.raw"
"$bake" shell -i "$quad" -o "$tmp/vol.meso" --thickness 0.1 --texture "volume:$tmp/ones.raw:8x8x8" \
  --color "volume:$col/volume4.raw:4x4x2" >/dev/null 2>&1
check "volume: validates fully" sh -c "'$inspect' validate --full '$tmp/vol.meso' >/dev/null"
check "volume: COLR 4x4x2" sh -c "'$inspect' info '$tmp/vol.meso' | awk '\$2 == \"COLR\" && \$9 == \"4x4x2\"' | grep -q ."
"$inspect" dump "$tmp/vol.meso" COLR -o "$tmp/vol.colr" >/dev/null 2>&1
check "volume: COLR holds the file's bytes" cmp -s "$tmp/vol.colr" "$col/volume4.raw"

# 4. Without --color nothing about colour is written.
"$bake" shell -i "$quad" -o "$tmp/plain.meso" --thickness 0.1 --texture bricks:32 >/dev/null 2>&1
check "plain: no COLR" sh -c "! '$inspect' info '$tmp/plain.meso' | awk '\$2 == \"COLR\" || \$2 == \"CMAP\"' | grep -q ."
check "plain: no META color" sh -c "! '$inspect' info '$tmp/plain.meso' --format json | grep -q '\"color\"'"

# 5. Bad inputs: coded error, exit code, no output.
refuse() { # DESCRIPTION EXPECTED_EXIT EXPECTED_TEXT MESH ARGS...
  what=$1 code=$2 text=$3 mesh=$4; shift 4
  rm -f "$tmp/out.meso"
  "$bake" shell -i "$mesh" -o "$tmp/out.meso" "$@" >"$tmp/stdout" 2>"$tmp/stderr"
  rc=$?
  check "$what: exit $code (got $rc)" test "$rc" = "$code"
  check "$what: says '$text'" grep -q -- "$text" "$tmp/stderr"
  check "$what: writes no output" test ! -e "$tmp/out.meso"
}
printf 'not a png' >"$tmp/bad.png"
head -c 100 "$col/color8.png" >"$tmp/cut.png"
refuse "missing PNG (I/O, as --texture's)" 2 "E3131.*nope.png" "$quad" --texture bricks:32 --color "$tmp/nope.png"
refuse "not a PNG" 3 "E3132.*not a PNG" "$quad" --texture bricks:32 --color "$tmp/bad.png"
refuse "truncated PNG" 3 "E3132" "$quad" --texture bricks:32 --color "$tmp/cut.png"
refuse "from-mesh on an OBJ" 3 "E3133.*no material" "$quad" --texture bricks:32 --color from-mesh
refuse "from-mesh on a glTF without material" 3 "E3133.*no material" "$data/gltf/cube8.gltf" --texture bricks:32 \
  --color from-mesh
refuse "volume spec without size" 1 "E3130" "$quad" --texture weave:16 --color "volume:$col/volume4.raw"
refuse "volume of the wrong size" 3 "E3132.*128 bytes" "$quad" --texture weave:16 --color "volume:$col/volume4.raw:4x4x4"
refuse "3D colour over a height field" 1 "E3130.*volume texture" "$quad" --texture bricks:32 \
  --color "volume:$col/volume4.raw:4x4x2"
refuse "--color without --texture" 1 "needs --texture" "$quad" --color "$col/color8.png"
check "help documents --color" sh -c "'$bake' shell --help | grep -q -- '--color SPEC'"
exit $fail
