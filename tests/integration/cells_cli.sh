#!/bin/sh
# mesobake cells from the command line (FORMAT.md §7.2 kind 3, §7.8): the
# bundled sphere, spot and torus baked into cells objects that validate
# fully, the chunks and report keys the issue names, -j 1 = -j 2 byte for
# byte, the tile-map and colour variants, and bad input (a coded error, a
# non-zero exit, no output file); mesoinspect preview of a cells object
# with libmeso and with the exact reference, in all three modes, and of
# libmeso's depth and G-buffer passes (--pass); --colour from-mesh.
# usage: cells_cli.sh MESOBAKE MESOINSPECT TEST_DATA_DIR [PNG_PROBE]
set -u
bake=$1 inspect=$2 data=$3 probe=${4:-}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { # DESCRIPTION COMMAND...
  d=$1; shift
  if "$@"; then echo "ok   $d"; else echo "FAIL $d"; fail=1; fi
}
# The chunk of type $2 with the lowest lod (chunks are laid out lod
# descending): level 0's, or the one copy a TX3D has.
row() { "$inspect" info "$1" | awk -v t="$2" '$2 == t' | tail -n 1; }
key() { grep -q "\"$2\":" "$1"; }
num() { sed -n "s/.*\"$2\":[[:space:]]*\([-0-9.e+]*\).*/\1/p" "$1"; }

# 1. The bundled closed meshes, default tile map (Voronoi, 8 seeds, R = 32).
for m in sphere spot_low_resolution torus; do
  "$bake" cells -i "$data/$m.obj" -o "$tmp/$m.meso" --tiles 6 --tile-res 16 --report "$tmp/$m.json" -j 2 \
    >/dev/null 2>"$tmp/$m.err"
  check "$m: bake succeeds" test $? = 0 -a -s "$tmp/$m.meso"
  check "$m: validates fully" sh -c "'$inspect' validate --full '$tmp/$m.meso' >/dev/null"
  check "$m: object kind is cells" sh -c "'$inspect' info '$tmp/$m.meso' | grep -q ' cells '"
  for t in MESH CELL TILE SPLT MEMB NRMM COLR; do
    check "$m: has $t on object 1" sh -c "'$inspect' info '$tmp/$m.meso' | awk '\$2 == \"$t\" && \$4 == 1' | grep -q ."
  done
  for k in tiles split_cells cells_inside cells_outside cells_intersected bytes seconds_total voxelizer; do
    check "$m: report has $k" key "$tmp/$m.json" "$k"
  done
  check "$m: 216 tiles" test "$(num "$tmp/$m.json" tiles)" = 216
  check "$m: voxelizer parity (closed mesh)" grep -q '"voxelizer":[[:space:]]*"parity"' "$tmp/$m.json"
  check "$m: some cells inside" awk -v n="$(num "$tmp/$m.json" cells_inside)" 'BEGIN { exit !(n > 0) }'
  check "$m: bytes = file size" test "$(num "$tmp/$m.json" bytes)" = "$(wc -c <"$tmp/$m.meso" | tr -d ' ')"
  check "$m: TILE is 16x16x16" test "$(row "$tmp/$m.meso" TILE | awk '{print $9}')" = 16x16x16
  check "$m: info summarises CELL" sh -c "'$inspect' info '$tmp/$m.meso' | grep -q 'CELL: 6x6x6 tiles of 16^3 voxels'"
done

# Stand-in colours (FORMAT.md 7.3 VCOL): info's Levels table names a VCOL
# for every mesh level and none for a native one, and so does the JSON.
"$inspect" info "$tmp/spot_low_resolution.meso" |
  awk '/^Levels:/ { on = 1; next } on && /^$/ { exit } on && $1 == "1"' >"$tmp/levels.txt"
check "spot: mesh levels have vertex colours" sh -c "awk '\$3 == \"mesh\"' '$tmp/levels.txt' | grep -q . &&
  ! awk '\$3 == \"mesh\" && \$8 != \"VCOL\"' '$tmp/levels.txt' | grep -q ."
check "spot: native levels have none" sh -c "! awk '\$3 == \"native\" && \$8 != \"-\"' '$tmp/levels.txt' | grep -q ."
"$inspect" info --format json "$tmp/spot_low_resolution.meso" >"$tmp/levels.json"
check "spot: JSON levels[].vertex_colours for every level" test \
  "$(grep -c '"vertex_colours":' "$tmp/levels.json")" = "$(grep -c '"prefix_bytes":' "$tmp/levels.json")"

# 2. Determinism: -j 1 and -j 2 give the same bytes.
"$bake" cells -i "$data/spot_low_resolution.obj" -o "$tmp/j1.meso" --tiles 6 --tile-res 16 -j 1 >/dev/null 2>&1
check "-j 1 = -j 2 byte for byte" cmp -s "$tmp/j1.meso" "$tmp/spot_low_resolution.meso"

# 3. Variants: spheres, --cell-size, a raw tile map and a raw colour file,
# the winding path on an open mesh, -v progress.
"$bake" cells -i "$data/sphere.obj" -o "$tmp/sph.meso" --tile-map spheres:6:0.3 --tile-res 16 --cell-size 0.5 \
  --colour hash:5 --report "$tmp/sph.json" -v >/dev/null 2>"$tmp/sph.err"
check "spheres + --cell-size: validates" sh -c "'$inspect' validate --full '$tmp/sph.meso' >/dev/null"
check "--cell-size 0.5 on the unit sphere: 5 tiles per axis" test "$(num "$tmp/sph.json" tiles)" = 125
check "-v: one line per stage" test "$(grep -c '^mesobake: ' "$tmp/sph.err")" -ge 4
# one small sphere a tile (1.6 voxels of 32): halving erases it by 8 voxels
# a tile; the native levels stop there instead of failing the bake
check "a tile map that halving erases: bakes, one native level, validates" sh -c "'$bake' cells -i '$data/sphere.obj' \
  -o '$tmp/tiny.meso' --tile-map spheres:1:0.05 --tiles 4 >/dev/null 2>&1 &&
  '$inspect' validate --full '$tmp/tiny.meso' >/dev/null &&
  test \"\$('$inspect' info '$tmp/tiny.meso' | awk '\$3 == \"native\"' | wc -l)\" = 2"
# a raw 8^3 map: two slabs (indices 1, 2) along z, and an RGBA file
awk 'BEGIN { for (z = 0; z < 8; z++) for (i = 0; i < 64; i++) printf "%c%c", (z < 4 ? 1 : 2), 0 }' >"$tmp/slabs.raw"
awk 'BEGIN { for (i = 0; i < 512; i++) printf "%c%c%c%c", 200, 100, 50, 255 }' >"$tmp/rgba.raw"
"$bake" cells -i "$data/sphere.obj" -o "$tmp/raw.meso" --tile-map "$tmp/slabs.raw:8" --colour "$tmp/rgba.raw:8" \
  --tiles 4 --report "$tmp/raw.json" >/dev/null 2>&1
check "raw tile map + raw colours: validates" sh -c "'$inspect' validate --full '$tmp/raw.meso' >/dev/null"
check "raw slabs: 2 split cells" test "$(num "$tmp/raw.json" split_cells)" = 2
"$bake" cells -i "$data/cube_no_bottom.obj" -o "$tmp/open.meso" --tiles 4 --tile-res 8 --report "$tmp/open.json" \
  >/dev/null 2>&1
check "open mesh, auto: winding, validates" sh -c "grep -q '\"winding\"' '$tmp/open.json' && '$inspect' validate --full '$tmp/open.meso' >/dev/null"
"$bake" cells -i "$data/sphere.obj" -o "$tmp/vdb.meso" --tiles 4 --tile-res 8 --voxelizer vdb --report "$tmp/vdb.json" \
  >/dev/null 2>&1
check "--voxelizer vdb: the exact parity path" grep -q '"parity"' "$tmp/vdb.json"

# 4. Refusals: coded error, exit code, no output file.
refuse() { # NAME EXIT CODE ARGS...
  n=$1 want=$2 code=$3; shift 3
  "$bake" cells -o "$tmp/$n.meso" "$@" >/dev/null 2>"$tmp/$n.err"
  rc=$?
  check "refuse $n: exit $want" test "$rc" = "$want"
  [ -n "$code" ] && check "refuse $n: error E$code" grep -q "E$code" "$tmp/$n.err"
  check "refuse $n: no output file" test ! -e "$tmp/$n.meso"
}
refuse open_parity 3 3181 -i "$data/cube_no_bottom.obj" --voxelizer parity --tiles 2 --tile-res 8
refuse missing_mesh 2 "" -i "$tmp/nope.obj"
refuse bad_tile_map 1 3150 -i "$data/sphere.obj" --tile-map hexagons
refuse bad_seeds 1 3150 -i "$data/sphere.obj" --tile-map voronoi:0
refuse bad_radius 1 3150 -i "$data/sphere.obj" --tile-map spheres:4:2
refuse raw_wrong_size 3 3152 -i "$data/sphere.obj" --tile-map "$tmp/slabs.raw:9"
refuse raw_res_mismatch 1 3150 -i "$data/sphere.obj" --tile-map "$tmp/slabs.raw:8" --tile-res 16
refuse raw_missing 2 3151 -i "$data/sphere.obj" --tile-map "$tmp/nope.raw:8"
refuse bad_colour 1 3190 -i "$data/sphere.obj" --tiles 2 --tile-res 8 --colour plaid
refuse colour_size 3 3191 -i "$data/sphere.obj" --tiles 2 --tile-res 8 --colour "$tmp/slabs.raw:8"
# --colour from-mesh (--color too): a glTF's base colour as the TX3D colour grid.
"$bake" cells -i "$data/gltf/box.gltf" -o "$tmp/fm.meso" --tiles 3 --tile-res 8 --color from-mesh:20 -j 2 \
  >/dev/null 2>&1
check "from-mesh: bake succeeds" test -s "$tmp/fm.meso"
check "from-mesh: validates fully" sh -c "'$inspect' validate --full '$tmp/fm.meso' >/dev/null"
check "from-mesh: TX3D u8 x 4, 20x20x20 on object 1" \
  test "$(row "$tmp/fm.meso" TX3D | awk '{print $4, $7, $8, $9}')" = "1 u8 4 20x20x20"
"$bake" cells -i "$data/gltf/box.gltf" -o "$tmp/fm2.meso" --tiles 3 --tile-res 8 --colour from-mesh:20 -j 1 \
  >/dev/null 2>&1
check "from-mesh: -j 1 = -j 2, --colour = --color" cmp -s "$tmp/fm.meso" "$tmp/fm2.meso"
refuse from_mesh_obj 3 3562 -i "$data/sphere.obj" --tiles 2 --tile-res 8 --colour from-mesh
refuse from_mesh_g 1 3190 -i "$data/gltf/box.gltf" --tiles 2 --tile-res 8 --colour from-mesh:1
refuse too_many_voxels 1 3180 -i "$data/sphere.obj" --tiles 1024 --tile-res 32
refuse both_sizes 1 "" -i "$data/sphere.obj" --tiles 4 --cell-size 0.5
refuse bad_voxelizer 1 "" -i "$data/sphere.obj" --voxelizer magic
refuse unknown_flag 1 "" -i "$data/sphere.obj" --frobnicate
refuse no_input 1 ""
# mesoinspect preview of a cells object: libmeso (EGL) and the exact
# reference agree at the centre pixel (on the object) and leave the corners
# to the background, in each mode; bad preview options are usage errors.
if [ -n "$probe" ]; then
  for mode in first reflect refract; do
    "$inspect" preview "$tmp/sphere.meso" -o "$tmp/p_ref.png" --size 64x64 --zoom 1.6 --cells $mode --reference \
      >/dev/null 2>&1
    check "preview --reference --cells $mode: writes a PNG" test -s "$tmp/p_ref.png"
    ref_px=$("$probe" "$tmp/p_ref.png")
    check "preview --reference --cells $mode: centre on the object, corner background" \
      sh -c "test \"$(echo "$ref_px" | sed -n 6p)\" != \"$(echo "$ref_px" | sed -n 2p)\""
    if "$inspect" preview "$tmp/sphere.meso" -o "$tmp/p_gl.png" --size 64x64 --zoom 1.6 --cells $mode \
      >/dev/null 2>&1; then
      gl_px=$("$probe" "$tmp/p_gl.png")
      check "preview --cells $mode (libmeso): same corner as the reference" \
        test "$(echo "$gl_px" | sed -n 2p)" = "$(echo "$ref_px" | sed -n 2p)"
      check "preview --cells $mode (libmeso): centre within 8/255 of the reference" \
        awk -v a="$(echo "$gl_px" | sed -n 6p)" -v b="$(echo "$ref_px" | sed -n 6p)" 'BEGIN { split(a, x, " ");
          split(b, y, " "); for (i = 1; i <= 3; ++i) { d = x[i] - y[i]; if (d < -8 || d > 8) exit 1 } }'
    else
      echo "skip preview (libmeso): no EGL in this build"
    fi
  done
fi
# --pass (libmeso's passes, meso_rt_draw_desc.pass): depth as grey (the
# object lit, nearest 255 .. farthest 32; background 0), the G-buffer as three
# files beside the named one, which is not written; not with --reference.
if [ -n "$probe" ] && "$inspect" preview "$tmp/sphere.meso" -o "$tmp/pd.png" --size 64x64 --zoom 1.6 \
    --pass depth >/dev/null 2>&1; then
  px=$("$probe" "$tmp/pd.png")
  check "preview --pass depth: corner is 0" test "$(echo "$px" | sed -n 2p)" = "0 0 0 255"
  check "preview --pass depth: centre grey in 32..255" awk -v a="$(echo "$px" | sed -n 6p)" \
    'BEGIN { split(a, x, " "); exit !(x[1] == x[2] && x[2] == x[3] && x[1] >= 32) }'
  "$inspect" preview "$tmp/sphere.meso" -o "$tmp/g.png" --size 64x64 --zoom 1.6 --pass gbuffer >/dev/null 2>&1
  check "preview --pass gbuffer: exit 0" test $? = 0
  check "preview --pass gbuffer: g-albedo, g-normal, g-depth written, g.png not" \
    sh -c "test -s '$tmp/g-albedo.png' -a -s '$tmp/g-normal.png' -a -s '$tmp/g-depth.png' -a ! -e '$tmp/g.png'"
  check "preview --pass gbuffer: depth file = --pass depth" cmp -s "$tmp/g-depth.png" "$tmp/pd.png"
  # The centre's normal faces the camera (yaw 30, pitch 20: towards +z mostly).
  check "preview --pass gbuffer: centre normal faces the camera" awk -v a="$("$probe" "$tmp/g-normal.png" | sed -n 6p)" \
    'BEGIN { split(a, x, " "); exit !(x[3] > 200 && x[1] > 128 && x[2] > 128) }'
fi
for opt in "--cells magic" "--bounces 9" "--cell-step -1" "--zoom 0" "--pass magic" "--pass depth --reference"; do
  # shellcheck disable=SC2086
  "$inspect" preview "$tmp/sphere.meso" -o "$tmp/never.png" $opt >/dev/null 2>&1
  check "preview $opt: usage error (exit 1), no PNG" sh -c "test $? = 1 && ! test -e '$tmp/never.png'"
done

# A failed bake leaves an existing output untouched.
cp "$tmp/sphere.meso" "$tmp/keep_me.meso"
"$bake" cells -i "$data/cube_no_bottom.obj" -o "$tmp/keep_me.meso" --voxelizer parity >/dev/null 2>&1
check "failed bake: existing output untouched" cmp -s "$tmp/sphere.meso" "$tmp/keep_me.meso"
"$bake" --help | grep -q "cells"
check "mesobake --help lists cells" test $? = 0
"$bake" cells --help | grep -q -- "--tile-map"
check "cells --help documents --tile-map" test $? = 0
exit $fail
