#!/bin/sh
# mesoinspect export (issue 16, glTF out): every object kind baked from the
# bundled data, packed into one multi-object file too, exported and checked
# by test_export_glb (tinygltf's parser with no warnings, the glTF rules,
# the geometry against the .meso); a height-field shell on a plane, from a
# 16-bit PNG and from a density volume of the same surface, whose normal
# maps must match the analytic normals; --object by id and name;
# determinism; bad input and bad options (coded errors, exit codes, nothing
# written).
# usage: export_cli.sh MESOBAKE MESOINSPECT TEST_EXPORT_GLB TEST_DATA_DIR
set -u
bake=$1 inspect=$2 checker=$3 data=$4
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { # DESCRIPTION COMMAND...
  d=$1; shift
  if "$@"; then echo "ok   $d"; else echo "FAIL $d"; fail=1; fi
}
# exits CODE COMMAND...: the command exits with CODE
exits() { c=$1; shift; "$@" >/dev/null 2>"$tmp/err"; test $? -eq "$c"; }

# 1. One file per kind, from the bundled data.
"$bake" mesh -i "$data/spot_uv.obj" -o "$tmp/mesh.meso" >/dev/null 2>&1
"$bake" shell -i "$data/spot_uv.obj" -o "$tmp/shell.meso" --texture bricks:64 -j 2 >/dev/null 2>&1
"$bake" shell -i "$data/sphere.obj" -o "$tmp/shellvol.meso" --texture weave:32 -j 2 >/dev/null 2>&1
"$bake" cells -i "$data/sphere.obj" -o "$tmp/cells.meso" --tiles 4 --tile-res 8 -j 2 >/dev/null 2>&1
"$bake" frusta -i "$data/saguaro.skel" -o "$tmp/frusta.meso" --relief ribs:64 >/dev/null 2>&1
"$bake" frusta -i "$data/neurom_simple.swc" -o "$tmp/swc.meso" >/dev/null 2>&1
for k in mesh shell shellvol cells frusta swc; do
  check "$k: bake" test -s "$tmp/$k.meso"
  check "$k: export exits 0" "$inspect" export "$tmp/$k.meso" -o "$tmp/$k.glb"
  check "$k: the glb passes every check" "$checker" check "$tmp/$k.meso" "$tmp/$k.glb"
done

# 2. Several objects in one file: one node each, in order; --object.
"$bake" pack "$tmp/mesh.meso" "$tmp/shell.meso" "$tmp/cells.meso" "$tmp/frusta.meso" -o "$tmp/scene.meso" \
  >/dev/null 2>&1
check "scene: pack" test -s "$tmp/scene.meso"
check "scene: export" "$inspect" export "$tmp/scene.meso" -o "$tmp/scene.glb" --frusta-grid 16
check "scene: four nodes, each checked" "$checker" check "$tmp/scene.meso" "$tmp/scene.glb"
check "scene: --object 3" "$inspect" export "$tmp/scene.meso" -o "$tmp/one.glb" --object 3
check "scene: --object 3 is object 3 alone" "$checker" check "$tmp/scene.meso" "$tmp/one.glb" 3
name=$("$inspect" info "$tmp/scene.meso" --format json | sed -n 's/.*"name":[[:space:]]*"\([^"]*\)".*/\1/p' | sed -n 2p)
check "scene: --object NAME ($name)" "$inspect" export "$tmp/scene.meso" -o "$tmp/named.glb" --object "$name"
check "scene: --object NAME is object 2 alone" "$checker" check "$tmp/scene.meso" "$tmp/named.glb" 2
"$inspect" export "$tmp/scene.meso" -o "$tmp/scene2.glb" --frusta-grid 16
check "scene: byte-identical on a second run" cmp -s "$tmp/scene.glb" "$tmp/scene2.glb"

# 3. The analytic test: a plane with uv = (x, y), thickness 0.5, so the
#    normal map must show the normals of z = 0.5 h(x, y) (K = 0.5).
"$checker" gen "$tmp"
# Tolerances: 8-bit texels are 0.5 degree steps; the height field is a
# 16-bit 128^2 PNG, the volume u8 densities on 32 levels over 64^2 columns.
for c in "hf height:$tmp/sine.png 1.5 0.5" "vol volume:$tmp/sine.raw:64x64x32 4 1.5"; do
  set -- $c
  "$bake" shell -i "$tmp/plane.obj" -o "$tmp/$1.meso" --thickness 0.5 --directors normal --texture "$2" \
    >/dev/null 2>"$tmp/$1.err"
  check "$1: bake" test -s "$tmp/$1.meso"
  check "$1: export" "$inspect" export "$tmp/$1.meso" -o "$tmp/$1.glb"
  check "$1: the glb passes every check" "$checker" check "$tmp/$1.meso" "$tmp/$1.glb"
  check "$1: normal map = analytic normals, colour = albedo x occlusion" "$checker" analytic "$tmp/$1.glb" 0.5 $3 $4
done

# 3b. Colour (FORMAT.md §7.2): a shell's COLR tiled (a PNG) and on the base
#     mesh's uv (from-mesh, CMAP BASE, exported on TEXCOORD_1), and a frusta
#     object's COLR (per-vertex COLOR_0): the checker's part 4 compares the
#     exported colour with the .meso's at every vertex.
"$bake" shell -i "$data/spot_uv.obj" -o "$tmp/coltiled.meso" --texture bricks:32 --tiling 4,2 \
  --color "$data/color/color8.png" -j 2 >/dev/null 2>&1
"$bake" shell -i "$data/gltf/box.gltf" -o "$tmp/colmesh.meso" --texture bricks:32 --tiling 4,2 \
  --color from-mesh >/dev/null 2>&1
"$bake" frusta -i "$data/saguaro.skel" -o "$tmp/colfrusta.meso" --relief ribs:64 \
  --relief-color "$data/color/bricks_color.png" >/dev/null 2>&1
for k in coltiled colmesh colfrusta; do
  check "$k: bake" test -s "$tmp/$k.meso"
  check "$k: export" "$inspect" export "$tmp/$k.meso" -o "$tmp/$k.glb" --frusta-grid 32
  # the glTF box's welded corners fit no one tangent frame: reported, not asserted
  mode=check; [ $k = colmesh ] && mode=check-hard-corners
  check "$k: the glb passes every check, colour included" "$checker" $mode "$tmp/$k.meso" "$tmp/$k.glb"
done
# A 3D colour (4x4x2) over a volume solid below w = 1/2 (4x4x8: four full
# slices, four empty; alpha crosses 1/2 half-way between texel centres 7/16
# and 9/16): every column tops out at w = 1/2, between the colour slices'
# centres 1/4 and 3/4, so each tile texel is the two slices' mean in linear light.
{ printf '\377%.0s' $(seq 1 64); printf '\000%.0s' $(seq 1 64); } >"$tmp/half.raw"
"$bake" shell -i "$data/spot_uv.obj" -o "$tmp/col3d.meso" --texture "volume:$tmp/half.raw:4x4x8" \
  --color "volume:$data/color/volume4.raw:4x4x2" -j 2 >/dev/null 2>&1
check "col3d: bake" test -s "$tmp/col3d.meso"
check "col3d: export" "$inspect" export "$tmp/col3d.meso" -o "$tmp/col3d.glb"
check "col3d: the glb passes every check" "$checker" check "$tmp/col3d.meso" "$tmp/col3d.glb"
check "col3d: the tile is the COLR at w = 1/2" "$checker" tile3d "$tmp/col3d.meso" "$tmp/col3d.glb" 0.5
check "colmesh: base colour on TEXCOORD_1" grep -q '"texCoord":1' "$tmp/colmesh.glb"
check "coltiled: base colour on TEXCOORD_0" sh -c "! grep -q 'TEXCOORD_1' '$tmp/coltiled.glb'"
check "colfrusta: COLOR_0" grep -q '"COLOR_0"' "$tmp/colfrusta.glb"

# 4. Bad input: coded errors, the exit codes of mesoinspect, nothing written.
cp "$tmp/mesh.meso" "$tmp/bad.meso"
size=$(wc -c <"$tmp/bad.meso")
printf '\377\377\377\377' | dd of="$tmp/bad.meso" bs=1 seek=$((size - 64)) conv=notrunc 2>/dev/null
check "corrupt payload: exit 3" exits 3 "$inspect" export "$tmp/bad.meso" -o "$tmp/bad.glb"
check "corrupt payload: a coded error" grep -q "error [0-9][0-9]*" "$tmp/err"
check "corrupt payload: nothing written" test ! -e "$tmp/bad.glb"
head -c 200 "$data/sphere.obj" >"$tmp/text.meso"
check "not a .meso: exit 3" exits 3 "$inspect" export "$tmp/text.meso" -o "$tmp/bad.glb"
check "not a .meso: error 1002 (magic)" grep -q "error 1002" "$tmp/err"
check "missing input: exit 2" exits 2 "$inspect" export "$tmp/none.meso" -o "$tmp/bad.glb"
check "nothing written for any of them" test ! -e "$tmp/bad.glb"
echo keep >"$tmp/keep.glb"
check "failed export keeps the old output" sh -c "! '$inspect' export '$tmp/bad.meso' -o '$tmp/keep.glb' 2>/dev/null && grep -q keep '$tmp/keep.glb'"
check "no temporary file left" sh -c "! ls -a '$tmp' | grep -q '\.tmp\.'"
mkdir "$tmp/dir.glb"
check "output is a directory: exit 2" exits 2 "$inspect" export "$tmp/mesh.meso" -o "$tmp/dir.glb"
check "unknown option: exit 1" exits 1 "$inspect" export "$tmp/mesh.meso" -o "$tmp/x.glb" --bogus
check "missing -o: exit 1" exits 1 "$inspect" export "$tmp/mesh.meso"
check "--object 99: exit 1" exits 1 "$inspect" export "$tmp/scene.meso" -o "$tmp/x.glb" --object 99
check "--object nosuch: exit 1" exits 1 "$inspect" export "$tmp/scene.meso" -o "$tmp/x.glb" --object nosuch
check "--frusta-grid 1: exit 1" exits 1 "$inspect" export "$tmp/frusta.meso" -o "$tmp/x.glb" --frusta-grid 1
check "no output for bad options" test ! -e "$tmp/x.glb"
check "--help exits 0" sh -c "'$inspect' export --help | grep -q 'glTF 2.0 binary'"
check "mesoinspect --help lists export" sh -c "'$inspect' --help | grep -q 'export   FILE -o OUT.glb'"

# 5. The checker itself rejects a broken file (it can fail).
cp "$tmp/mesh.glb" "$tmp/broken.glb"
printf '\001' | dd of="$tmp/broken.glb" bs=1 seek=8 conv=notrunc 2>/dev/null
check "checker: a wrong GLB length fails" sh -c "! '$checker' check '$tmp/mesh.meso' '$tmp/broken.glb' 2>/dev/null"
check "checker: another object's geometry fails" sh -c "! '$checker' check '$tmp/shell.meso' '$tmp/mesh.glb' 2>/dev/null"
check "checker: a flat normal map is not the analytic one" sh -c \
  "! '$checker' analytic '$tmp/hf.glb' 0.0 1.5 0.5 2>/dev/null"
exit $fail
