#!/bin/sh
# mesobake shell --texture from the command line (FORMAT.md §7.2, "Shell
# prisms and texture space"): built-in height fields and volumes, a PNG
# height map, the TX2D/TX3D + DIST chunks and MESH uvs they add, META and
# report keys, --tiling/--dist-res/--dist-type, byte-identical output for
# -j 1 and -j 2, interior shells' two-layer SDIR, bad specs (a coded
# error, a non-zero exit, and no output file) and meshes split at uv seams.
# usage: shell_texture_cli.sh MESOBAKE MESOINSPECT TEST_DATA_DIR WRITE_HEIGHT_PNG
set -u
bake=$1 inspect=$2 data=$3 writepng=$4
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { # DESCRIPTION COMMAND...
  d=$1; shift
  if "$@"; then echo "ok   $d"; else echo "FAIL $d"; fail=1; fi
}
spot="$data/spot_low_resolution.obj"
# chunk_row FILE TYPE: the chunk's row of 'mesoinspect info'
chunk_row() { "$inspect" info "$1" | awk -v t="$2" '$2 == t && $5 == 0'; } # level 0's
bytes() { wc -c <"$1" | tr -d ' '; }

# 1. Built-in height field on a mesh without uvs: planar fallback + warning.
"$bake" shell -i "$spot" -o "$tmp/bricks.meso" --texture bricks --report "$tmp/bricks.json" \
  >/dev/null 2>"$tmp/bricks.err"
check "bricks: bake succeeds" test -s "$tmp/bricks.meso"
check "bricks: validates fully" sh -c "'$inspect' validate --full '$tmp/bricks.meso' >/dev/null"
check "bricks: TX2D u16 256x256x1 on object 1" sh -c "'$inspect' info '$tmp/bricks.meso' | awk '\$2 == \"TX2D\" && \$4 == 1 && \$5 == 0 && \$7 == \"u16\" && \$9 == \"256x256x1\"' | grep -q ."
check "bricks: DIST u8 on object 1" sh -c "'$inspect' info '$tmp/bricks.meso' | awk '\$2 == \"DIST\" && \$4 == 1 && \$7 == \"u8\"' | grep -q ."
check "bricks: MESH carries uvs" sh -c "'$inspect' info '$tmp/bricks.meso' | grep -q 'attributes positions normals uvs'"
check "bricks: warns about the missing uvs" grep -q "warning: .*no texture coordinates" "$tmp/bricks.err"
check "bricks: META records the texture" sh -c "'$inspect' info '$tmp/bricks.meso' | grep -q '\"spec\":[[:space:]]*\"bricks\"'"
for key in uv_source dist_res tiling dist_solid_cells; do
  check "bricks: report has texture.$key" grep -q "\"$key\":" "$tmp/bricks.json"
done
check "bricks: report says the uvs are planar" grep -q '"uv_source":[[:space:]]*"planar"' "$tmp/bricks.json"
"$inspect" dump "$tmp/bricks.meso" DIST:1:0 -o "$tmp/bricks.dist" >/dev/null 2>&1
dims=$(chunk_row "$tmp/bricks.meso" DIST | awk '{print $9}')
expect=$(echo "$dims" | awk -F x '{print $1 * $2 * $3}')
check "bricks: DIST payload is W*H*D bytes ($dims)" test "$(bytes "$tmp/bricks.dist")" = "$expect"

# 2. Built-in volume, twice with different thread counts.
"$bake" shell -i "$spot" -o "$tmp/weave1.meso" --texture weave -j 1 >/dev/null 2>&1
"$bake" shell -i "$spot" -o "$tmp/weave2.meso" --texture weave -j 2 >/dev/null 2>&1
check "weave: bake succeeds" test -s "$tmp/weave1.meso"
check "weave: -j 1 and -j 2 give byte-identical files" cmp -s "$tmp/weave1.meso" "$tmp/weave2.meso"
check "weave: validates fully" sh -c "'$inspect' validate --full '$tmp/weave1.meso' >/dev/null"
check "weave: TX3D u8 128x128x64" sh -c "'$inspect' info '$tmp/weave1.meso' | awk '\$2 == \"TX3D\" && \$4 == 1 && \$7 == \"u8\" && \$9 == \"128x128x64\"' | grep -q ."
check "weave: default DIST is 64x64x32" sh -c "'$inspect' info '$tmp/weave1.meso' | awk '\$2 == \"DIST\" && \$9 == \"64x64x32\"' | grep -q ."
"$inspect" dump "$tmp/weave1.meso" TX3D:1 -o "$tmp/weave.tx" >/dev/null 2>&1
check "weave: TX3D payload is 128*128*64 bytes" test "$(bytes "$tmp/weave.tx")" = 1048576

# 3. Options: tiling, distance-map resolution and store type.
"$bake" shell -i "$spot" -o "$tmp/cells.meso" --texture cells:16 --tiling 2,3 --dist-res 8x6x4 --dist-type f32 \
  >/dev/null 2>&1
check "cells: bake succeeds" test -s "$tmp/cells.meso"
check "cells: validates fully" sh -c "'$inspect' validate --full '$tmp/cells.meso' >/dev/null"
check "cells: DIST f32 8x6x4" sh -c "'$inspect' info '$tmp/cells.meso' | awk '\$2 == \"DIST\" && \$7 == \"f32\" && \$9 == \"8x6x4\"' | grep -q ."
"$inspect" dump "$tmp/cells.meso" DIST -o "$tmp/cells.dist" >/dev/null 2>&1
check "cells: DIST payload is 8*6*4 floats" test "$(bytes "$tmp/cells.dist")" = 768
check "cells: META records tiling [2, 3]" sh -c "'$inspect' info '$tmp/cells.meso' --format json | tr -d ' \t\n' | grep -q '\"tiling\":\[2,3\]'"

# 4. PNG height maps (16- and 8-bit) on a mesh with its own uvs (no warning).
"$writepng" "$tmp/h16.png" 16 32 && "$writepng" "$tmp/h8.png" 8 24
"$bake" shell -i "$data/saddle.obj" -o "$tmp/png16.meso" --kind envelope --texture "height:$tmp/h16.png" \
  --report "$tmp/png16.json" >/dev/null 2>"$tmp/png16.err"
check "png16: bake succeeds" test -s "$tmp/png16.meso"
check "png16: validates fully" sh -c "'$inspect' validate --full '$tmp/png16.meso' >/dev/null"
check "png16: TX2D u16 32x32x1" sh -c "'$inspect' info '$tmp/png16.meso' | awk '\$2 == \"TX2D\" && \$7 == \"u16\" && \$9 == \"32x32x1\"' | grep -q ."
check "png16: the mesh's own uvs are used" grep -q '"uv_source":[[:space:]]*"mesh"' "$tmp/png16.json"
check "png16: no uv warning" sh -c "! grep -q warning '$tmp/png16.err'"
"$bake" shell -i "$spot" -o "$tmp/png8.meso" --texture "height:$tmp/h8.png" >/dev/null 2>&1
check "png8: TX2D u8 24x24x1" sh -c "'$inspect' info '$tmp/png8.meso' | awk '\$2 == \"TX2D\" && \$7 == \"u8\" && \$9 == \"24x24x1\"' | grep -q ."

# 5. Interior shells: SDIR has two layers (layer 0 zero, layer 1 inwards).
"$bake" shell -i "$spot" -o "$tmp/int.meso" --kind interior --texture bricks:64 >/dev/null 2>&1
check "interior: validates fully" sh -c "'$inspect' validate --full '$tmp/int.meso' >/dev/null"
check "interior: SDIR is 829x2x1" sh -c "'$inspect' info '$tmp/int.meso' | awk '\$2 == \"SDIR\" && \$9 == \"829x2x1\"' | grep -q ."
"$inspect" dump "$tmp/int.meso" SDIR -o "$tmp/int.sdir" >/dev/null 2>&1
check "interior: SDIR layer 0 is all zero" sh -c "head -c 9948 '$tmp/int.sdir' | od -An -v -tx1 | tr -s ' \n' '\n\n' | grep -v '^$' | grep -qv '^00$' && exit 1 || exit 0"
check "interior: SDIR layer 1 is not" sh -c "tail -c 9948 '$tmp/int.sdir' | od -An -v -tx1 | tr -s ' \n' '\n\n' | grep -v '^$' | grep -qv '^00$'"

# 6. Bad specs and options: coded error, non-zero exit, no output.
refuse() { # DESCRIPTION EXPECTED_EXIT EXPECTED_TEXT ARGS...
  d=$1 code=$2 text=$3; shift 3
  rm -f "$tmp/out.meso"
  "$bake" shell -i "$spot" -o "$tmp/out.meso" "$@" >"$tmp/stdout" 2>"$tmp/stderr"
  rc=$?
  check "$d: exit $code (got $rc)" test "$rc" = "$code"
  check "$d: says '$text'" grep -q -- "$text" "$tmp/stderr"
  check "$d: writes no output" test ! -e "$tmp/out.meso"
}
printf 'short' >"$tmp/short.raw"
refuse "unknown texture" 1 "mesobake error E3120" --texture marble
refuse "bad RES" 1 "E3120.*RES" --texture bricks:3
refuse "raw without size" 1 "E3120" --texture "volume:$tmp/short.raw"
refuse "missing PNG" 2 "E3121.*nope.png" --texture "height:$tmp/nope.png"
refuse "PNG that is not a PNG" 3 "E3122.*not a PNG" --texture "height:$tmp/short.raw"
refuse "raw of the wrong size" 3 "E3122.*expected exactly 64" --texture "volume:$tmp/short.raw:4x4x4"
refuse "bad --dist-res" 1 "--dist-res expects" --texture bricks --dist-res 8x8
refuse "bad --dist-type" 1 "--dist-type expects" --texture bricks --dist-type f16
refuse "bad --tiling" 1 "--tiling expects" --texture bricks --tiling 0,1
refuse "--tiling without --texture" 1 "need --texture" --tiling 2
# animated texture functions (FORMAT.md 7.2): only for a time-dependent built-in
refuse "--time on a static texture" 1 "need a time-dependent texture (boil)" --texture bricks:16 --time 1
refuse "--frames without --texture" 1 "need a time-dependent texture" --frames 2
refuse "--fps without --frames" 1 "fps needs frames" --texture boil:8 --fps 3
refuse "bad --frames" 1 "--frames expects" --texture boil:8 --frames 0
refuse "bad --time" 1 "--time expects" --texture boil:8 --time nan
check "help documents boil, --time and --frames" sh -c "'$bake' shell --help | grep -q 'boil\[:RES\]' && '$bake' shell --help | grep -q -- '--frames N'"
check "help documents --texture and the built-ins" sh -c "'$bake' shell --help | grep -q 'bricks\[:RES\]'"

# 7. uv seams: each distinct (vertex, corner uv) pair is one MESH vertex, the
# copies sharing position and director; seam_vertices counts the copies.
# vertex_count FILE: the MESH vertex count of object 1
vertex_count() { "$inspect" info "$1" --format json | tr -d ' \t\n' | grep -o '"vertex_count":[0-9]*' | head -n 1 | cut -d: -f2; }
# floats FILE OFFSET COUNT: COUNT f32 from OFFSET, one per line
floats() { od -An -v -tf4 -j "$2" -N $(($3 * 4)) "$1" | tr -s ' \n' '\n\n' | grep -v '^$'; }
# shared FILE.meso: every MESH position has a single director (SDIR layer 0)
shared() {
  "$inspect" dump "$1" MESH:1:0 -o "$tmp/s.mesh" >/dev/null 2>&1 && "$inspect" dump "$1" SDIR -o "$tmp/s.sdir" >/dev/null 2>&1 || return 1
  n=$(od -An -tu4 -N4 "$tmp/s.mesh" | tr -d ' ') off=$(od -An -tu8 -j16 -N8 "$tmp/s.mesh" | tr -d ' ')
  floats "$tmp/s.mesh" "$off" $((3 * n)) | paste -d ' ' - - - >"$tmp/s.pos"
  test "$(wc -l <"$tmp/s.pos" | tr -d ' ')" = "$n" || return 1
  floats "$tmp/s.sdir" 0 $((3 * n)) | paste -d ' ' - - - | paste -d '|' "$tmp/s.pos" - |
    awk -F '|' 'NF != 2 { bad = 1 } ($1 in d) && d[$1] != $2 { bad = 1 } { d[$1] = $2 } END { exit bad }'
}
# seams FILE.json N: the report's texture.seam_vertices is N
seams() { tr -d ' \t\n' <"$1" | grep -q "\"seam_vertices\":$2[,}]"; }
octa_vertices() {
  printf 'v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n'
}
# An octahedron, 6 vertices: vt k is vertex k's uv in every face but two.
# Vertex 5 takes vt 7 in faces 3 and 4, vertex 1 takes vt 8 in face 8:
# 6 + 2 distinct (vertex, uv) pairs.
{
  octa_vertices
  printf 'vt 0.75 0.5\nvt 0.25 0.5\nvt 0.5 0.75\nvt 0.5 0.25\nvt 0.5 0.5\nvt 0 0\nvt 0.9 0.9\nvt 0.1 0.9\n'
  printf 'f 1/1 3/3 5/5\nf 3/3 2/2 5/5\nf 2/2 4/4 5/7\nf 4/4 1/1 5/7\n'
  printf 'f 3/3 1/1 6/6\nf 2/2 3/3 6/6\nf 4/4 2/2 6/6\nf 1/8 4/4 6/6\n'
} >"$tmp/octa.obj"
{
  octa_vertices
  printf 'f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n'
} >"$tmp/octa_plain.obj"
# A cube of quads, each mapped onto the unit square in listing order. Per
# vertex the distinct uvs of its three faces: 2 3 3 2 3 3 2 2 = 20 pairs.
{
  printf 'v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n'
  printf 'vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n'
  printf 'f 1/1 4/2 3/3 2/4\nf 5/1 6/2 7/3 8/4\nf 1/1 2/2 6/3 5/4\n'
  printf 'f 2/1 3/2 7/3 6/4\nf 3/1 4/2 8/3 7/4\nf 4/1 1/2 5/3 8/4\n'
} >"$tmp/quads.obj"
"$bake" shell -i "$tmp/octa.obj" -o "$tmp/seam1.meso" --texture bricks:64 -j 1 --report "$tmp/seam.json" -v \
  >/dev/null 2>"$tmp/seam.err"
"$bake" shell -i "$tmp/octa.obj" -o "$tmp/seam2.meso" --texture bricks:64 -j 2 >/dev/null 2>&1
check "seam: bake succeeds" test -s "$tmp/seam1.meso"
check "seam: validates fully" sh -c "'$inspect' validate --full '$tmp/seam1.meso' >/dev/null"
check "seam: MESH has 6 + 2 vertices" test "$(vertex_count "$tmp/seam1.meso")" = 8
check "seam: SDIR and STHK follow (8)" sh -c "'$inspect' info '$tmp/seam1.meso' | awk '(\$2 == \"SDIR\" || \$2 == \"STHK\") && \$9 == \"8x1x1\"' | grep -c . | grep -qx 2"
check "seam: report says seam_vertices 2" seams "$tmp/seam.json" 2
check "seam: -v says so" grep -q "2 seam vertices" "$tmp/seam.err"
check "seam: copies share position and director" shared "$tmp/seam1.meso"
check "seam: -j 1 and -j 2 give byte-identical files" cmp -s "$tmp/seam1.meso" "$tmp/seam2.meso"
"$bake" shell -i "$tmp/octa.obj" -o "$tmp/seam_env.meso" --kind envelope --texture bricks:64 >/dev/null 2>&1
check "seam envelope: validates fully" sh -c "'$inspect' validate --full '$tmp/seam_env.meso' >/dev/null"
check "seam envelope: SDIR is 8x2x1" sh -c "'$inspect' info '$tmp/seam_env.meso' | awk '\$2 == \"SDIR\" && \$9 == \"8x2x1\"' | grep -q ."
"$bake" shell -i "$tmp/quads.obj" -o "$tmp/quads.meso" --texture bricks:64 --report "$tmp/quads.json" >/dev/null 2>&1
check "seam quads: validates fully" sh -c "'$inspect' validate --full '$tmp/quads.meso' >/dev/null"
check "seam quads: MESH has 8 + 12 vertices" test "$(vertex_count "$tmp/quads.meso")" = 20
check "seam quads: report says seam_vertices 12" seams "$tmp/quads.json" 12
check "seam quads: copies share position and director" shared "$tmp/quads.meso"
# Without --texture nothing is split (one uv per vertex, as before) and the
# report has no seam_vertices.
"$bake" shell -i "$tmp/octa.obj" -o "$tmp/seam_notex.meso" --report "$tmp/seam_notex.json" >/dev/null 2>&1
check "seam, no texture: MESH keeps 6 vertices" test "$(vertex_count "$tmp/seam_notex.meso")" = 6
check "seam, no texture: no seam_vertices" sh -c "! grep -q seam_vertices '$tmp/seam_notex.json'"
# Without per-face uvs, or with one uv per vertex, the vertices are the input's.
"$bake" shell -i "$tmp/octa_plain.obj" -o "$tmp/plain.meso" --texture bricks:64 --report "$tmp/plain.json" \
  >/dev/null 2>&1
check "no uvs: MESH keeps 6 vertices" test "$(vertex_count "$tmp/plain.meso")" = 6
check "no uvs: seam_vertices 0" seams "$tmp/plain.json" 0
check "one uv per vertex (saddle): MESH keeps 1089 vertices" test "$(vertex_count "$tmp/png16.meso")" = 1089
check "one uv per vertex (saddle): seam_vertices 0" seams "$tmp/png16.json" 0

# 8. Animated texture functions (FORMAT.md 7.2): --frames stores the frames,
# info lists them, and the reference preview of the frame at --time T is
# the preview of a static bake at T, pixel for pixel.
"$bake" shell -i "$spot" -o "$tmp/seq.meso" --texture boil:16 --frames 4 --fps 8 -j 2 2>/dev/null
"$bake" shell -i "$spot" -o "$tmp/t2.meso" --texture boil:16 --time 0.25 -j 2 2>/dev/null
check "frames: info shows the ANIM record" sh -c "'$inspect' info '$tmp/seq.meso' | grep -q 'ANIM: 4 frames at 8 fps'"
check "frames: validate --full" "$inspect" validate --full "$tmp/seq.meso"
"$inspect" preview "$tmp/seq.meso" -o "$tmp/seq2.png" --reference --time 0.3 --size 40x40 --samples 32 >/dev/null 2>&1
"$inspect" preview "$tmp/t2.meso" -o "$tmp/t2.png" --reference --size 40x40 --samples 32 >/dev/null 2>&1
"$inspect" preview "$tmp/seq.meso" -o "$tmp/seq0.png" --reference --size 40x40 --samples 32 >/dev/null 2>&1
check "frames: preview --reference --time 0.3 (frame 2) = the bake at 0.25" cmp -s "$tmp/seq2.png" "$tmp/t2.png"
check "frames: ... and not frame 0" sh -c "! cmp -s '$tmp/seq0.png' '$tmp/t2.png'"

# 9. Native coarser levels of a height field (FORMAT.md 7.10): info lists
# them, and preview --reference --level L draws level L's own height field
# (another image than level 0's); a level that is a mesh stand-in, or none,
# leaves the object out with a note and, with nothing left, exits 5; --level
# without --reference is a usage error.
"$bake" shell -i "$data/spot_uv.obj" -o "$tmp/lv.meso" --texture bricks:256 --thickness-rel 0.02 -j 2 2>/dev/null
check "levels: info lists native level 1" sh -c "'$inspect' info '$tmp/lv.meso' | awk '\$2 == 1 && \$3 == \"native\"' | grep -q ."
standin=$("$inspect" info "$tmp/lv.meso" | awk '$1 == 1 && $3 == "mesh" {print $2; exit}')
"$inspect" preview "$tmp/lv.meso" -o "$tmp/lv0.png" --reference --size 40x40 --samples 32 >/dev/null 2>&1
"$inspect" preview "$tmp/lv.meso" -o "$tmp/lv1.png" --reference --level 1 --size 40x40 --samples 32 >/dev/null 2>&1
check "levels: preview --reference --level 1 writes an image" test -s "$tmp/lv1.png"
check "levels: ... not level 0's" sh -c "! cmp -s '$tmp/lv0.png' '$tmp/lv1.png'"
"$inspect" preview "$tmp/lv.meso" -o "$tmp/lvs.png" --reference --level "$standin" --size 40x40 --samples 32 \
  >/dev/null 2>"$tmp/lvs.err"
check "levels: --level $standin (the mesh stand-in): exit 5" test $? -eq 5
check "levels: ... says it is a mesh stand-in" grep -q "level $standin is a mesh stand-in" "$tmp/lvs.err"
check "levels: ... writes no image" test ! -e "$tmp/lvs.png"
"$inspect" preview "$tmp/lv.meso" -o "$tmp/lvg.png" --level 1 >/dev/null 2>"$tmp/lvg.err"
check "levels: --level without --reference: exit 1" test $? -eq 1
exit $fail
