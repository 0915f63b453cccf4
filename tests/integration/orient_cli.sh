#!/bin/sh
# Inside-out meshes (bake/mesh_orient.h) in every command that reads a mesh:
# a copy of a bundled closed mesh with every face's winding reversed
# (generated here) is reoriented with a "mesobake warning:", its report
# records it ("reoriented_components": 1 and a "warnings" entry with E3250),
# and every chunk of the bake except META (the input's checksum differs) and
# RPRT (the report says it was reoriented) is byte-identical to the bake of
# the original -- shells, directors, frusta, cells, Draco meshes -- with one
# stated exception: the vertex normals stored in a raw MESH chunk agree to
# 1e-6, not to the bit (mesh_normals_close below). Reversing (a b c) to
# (a c b) and flipping back gives the original triangles exactly.
# The original's report has no such key, and nothing is written to stderr.
# usage: orient_cli.sh MESOBAKE MESOINSPECT TEST_DATA_DIR
set -u
bake=$1 inspect=$2 data=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { # DESCRIPTION COMMAND...
  d=$1; shift
  if "$@"; then echo "ok   $d"; else echo "FAIL $d"; fail=1; fi
}
num() { sed -n "s/.*\"$2\":[[:space:]]*\([-0-9.e+]*\).*/\1/p" "$1"; }

# Reverse every face: "f a b c" -> "f a c b" (the bundled meshes are
# triangles; v/vt/vn references move with their corner).
flip() { awk '$1 == "f" { t = $3; $3 = $4; $4 = t } { print }' "$1" >"$2"; }

# same_chunks A B: every chunk row of `info` but META and RPRT, dumped from
# both files as stored and compared byte for byte; the chunk lists agree too.
# mesh_normals_close A B: two raw MESH chunks (FORMAT.md §7.3) whose 32-bit
# words are all equal except inside the normals array, where the floats
# differ by at most 1e-6: OpenMesh computes a reversed face's normal from
# another corner, so the vertex normals of the flipped copy, negated back,
# can differ from the original's in the last bits.
mesh_normals_close() {
  od -A n -t u4 -v "$1" | tr -s ' ' '\n' | sed '/^$/d' >"$tmp/wa"
  od -A n -t u4 -v "$2" | tr -s ' ' '\n' | sed '/^$/d' >"$tmp/wb"
  od -A n -t f4 -v "$1" | tr -s ' ' '\n' | sed '/^$/d' >"$tmp/fa"
  od -A n -t f4 -v "$2" | tr -s ' ' '\n' | sed '/^$/d' >"$tmp/fb"
  paste "$tmp/wa" "$tmp/wb" "$tmp/fa" "$tmp/fb" | awk '
    NR == 1 { nv = $1 } NR == 7 { no = $1 / 4 }
    { i = NR - 1 }
    $1 != $2 {
      d = $3 - $4; if (d < 0) d = -d
      if (no > 0 && i >= no && i < no + 3 * nv && d <= 1e-6) { n++; if (d > max) max = d; next }
      bad = 1
    }
    END { printf "       MESH: %d normal components differ, by at most %g\n", n, max; exit bad || NR < 16 }'
}

rows='$1 ~ /^[0-9]+$/ && $2 ~ /^[A-Z0-9][A-Z0-9][A-Z0-9][A-Z0-9]$/ && $2 != "META" && $2 != "RPRT" { print $1, $2 }'
same_chunks() {
  "$inspect" info "$1" | awk "$rows" >"$tmp/rows_a"
  "$inspect" info "$2" | awk "$rows" >"$tmp/rows_b"
  cmp -s "$tmp/rows_a" "$tmp/rows_b" || { echo "       chunk lists differ"; return 1; }
  [ -s "$tmp/rows_a" ] || { echo "       no chunks"; return 1; }
  while read -r index type; do
    "$inspect" dump "$1" "$index" --stored -o "$tmp/chunk_a" >/dev/null 2>&1 || return 1
    "$inspect" dump "$2" "$index" --stored -o "$tmp/chunk_b" >/dev/null 2>&1 || return 1
    cmp -s "$tmp/chunk_a" "$tmp/chunk_b" && continue
    if [ "$type" = MESH ] && mesh_normals_close "$tmp/chunk_a" "$tmp/chunk_b"; then
      continue
    fi
    echo "       chunk $index ($type) differs"
    return 1
  done <"$tmp/rows_a"
  return 0
}

mkdir "$tmp/flipped"
for name in sphere torus; do
  flip "$data/$name.obj" "$tmp/flipped/$name.obj"
done
check "the flipped copy differs from the original" sh -c "! cmp -s '$data/sphere.obj' '$tmp/flipped/sphere.obj'"

# bake CMD MESH ARGS...: original and flipped, reports and stderr kept.
run() {
  cmd=$1 name=$2
  shift 2
  "$bake" $cmd -i "$data/$name.obj" -o "$tmp/$cmd.a.meso" --report "$tmp/$cmd.a.json" "$@" 2>"$tmp/$cmd.a.err"
  check "$cmd: original bakes" test $? = 0
  "$bake" $cmd -i "$tmp/flipped/$name.obj" -o "$tmp/$cmd.b.meso" --report "$tmp/$cmd.b.json" "$@" 2>"$tmp/$cmd.b.err"
  check "$cmd: inside-out copy bakes (exit 0)" test $? = 0
  check "$cmd: original: no warning, no reoriented_components" \
    sh -c "! grep -q . '$tmp/$cmd.a.err' && ! grep -q reoriented '$tmp/$cmd.a.json'"
  check "$cmd: inside-out copy: warning names the file and the flip" \
    grep -Eq "^mesobake warning: .*$name.obj: 1 of 1 closed components were inside-out" "$tmp/$cmd.b.err"
  check "$cmd: report: reoriented_components 1" test "$(num "$tmp/$cmd.b.json" reoriented_components)" = 1
  check "$cmd: report: warnings names E3250" grep -q '"E3250: 1 inside-out closed components' "$tmp/$cmd.b.json"
  check "$cmd: the .meso's own report records it too" \
    sh -c "'$inspect' info '$tmp/$cmd.b.meso' | grep -q 'reoriented_components'"
  check "$cmd: every chunk but META and RPRT is byte-identical to the original's" \
    same_chunks "$tmp/$cmd.a.meso" "$tmp/$cmd.b.meso"
}

run mesh sphere
run mesh sphere --draco
run shell sphere --thickness-rel 0.05
run shell sphere --thickness-rel 0.05 --kind envelope
run cells sphere --tiles 4 --tile-res 8
if "$bake" frusta --help | grep -q "a mesh"; then
  run frusta torus
else
  echo "FAIL frusta: this build cannot read meshes as skeleton input (CGAL); the suite needs it"
  fail=1
fi

exit $fail
