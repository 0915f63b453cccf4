#!/bin/sh
# mesh_guard_cli.sh MESOBAKE
#
# Every command that reads a mesh (mesh, shell, cells, frusta -i MESH) refuses
# each malformed mesh with exit 3, the mesh guard's code (bake/mesh_guard.h)
# on stderr, and no output file; the same tetrahedron written correctly bakes
# (so the refusals are the guard's, not a broken command line). The files are
# generated here: NaN/Inf coordinates, indices 0 / out of range / negative,
# two-corner faces, duplicated faces, truncated or garbage PLY headers, and
# headers claiming 2^31 or 4e9 or negative counts.
set -u

MB=$1

. "$(dirname "$0")/check_lib.sh" # $T, run, expect_*, fail, ok

V='v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n'
F='f 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n'
OFFV='OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n'
PLYH='ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n'

mk() { printf "$2" >"$T/$1"; }
mk good.obj "$V$F"
mk nan.obj 'v 0 0 0\nv nan 0 0\nv 0 1 0\nv 0 0 1\n'"$F"
mk inf.obj 'v 0 0 0\nv 1 0 0\nv 0 1 inf\nv 0 0 1\n'"$F"
mk range.obj "$V"'f 1 3 2\nf 1 2 4\nf 2 3 5\nf 1 4 3\n'
mk zero.obj "$V"'f 0 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n'
mk two.obj "$V"'f 1 3\nf 1 2 4\nf 2 3 4\nf 1 4 3\n'
mk dup.obj "$V$F"'f 1 3 2\n'
mk negidx.off "$OFFV"'3 0 2 1\n3 0 1 3\n3 1 2 -1\n3 0 3 2\n'
mk range.off "$OFFV"'3 0 2 1\n3 0 1 3\n3 1 2 4\n3 0 3 2\n'
mk huge.off 'OFF\n4000000000 1 0\n0 0 0\n'
mk negcount.off 'OFF\n-4 4 0\n0 0 0\n'
mk negidx.ply "$PLYH"'3 0 2 1\n3 0 1 3\n3 1 2 -1\n3 0 3 2\n'
mk range.ply "$PLYH"'3 0 2 1\n3 0 1 3\n3 1 2 9\n3 0 3 2\n'
mk truncated.ply 'ply\nformat ascii 1.0\nelem'
mk garbage.ply 'ply\nformat ascii 1.0\n\001\002garbage\377\n'
mk huge.ply 'ply\nformat binary_little_endian 1.0\nelement vertex 2147483648\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n'
mk huge4e9.ply 'ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n'
mk negcount.ply 'ply\nformat ascii 1.0\nelement vertex -1\nend_header\n'
mk short.stl 'solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid x\n'
mk nan.stl 'solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 nan 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid x\n'
head -c 183 /dev/zero >"$T/size.stl"
# one triangle repeated 128000 times (the slow case of issue 21, scaled down)
{ printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\n'; i=0; while [ $i -lt 1000 ]; do printf 'f 1 2 3\n'; i=$((i + 1)); done; } >"$T/dup1k.obj"
for i in 1 2 3 4 5 6 7; do cat "$T/dup1k.obj" "$T/dup1k.obj" >"$T/d" && mv "$T/d" "$T/dup1k.obj"; done

CASES="nan.obj:3206 inf.obj:3206 range.obj:3209 zero.obj:3208 two.obj:3207 dup.obj:3212 dup1k.obj:3212
negidx.off:3209 range.off:3209 huge.off:3202 negcount.off:3203
negidx.ply:3209 range.ply:3209 truncated.ply:3203 garbage.ply:3203 huge.ply:3202 huge4e9.ply:3202 negcount.ply:3203
short.stl:3214 nan.stl:3206 size.stl:3202"

for cmd in mesh shell cells frusta; do
    rm -f "$T/ok.meso"
    "$MB" $cmd -i "$T/good.obj" -o "$T/ok.meso" >/dev/null 2>"$T/err"
    rc=$?
    # the tetrahedron is valid input: mesh bakes it; the others may refuse
    # it for their own reasons, but never with a guard code
    if [ $cmd = mesh ] && { [ $rc -ne 0 ] || [ ! -s "$T/ok.meso" ]; }; then fail "mesh good.obj: exit $rc"; else ok; fi
    if grep -q 'E32[0-4][0-9]' "$T/err"; then fail "$cmd good.obj: a guard code for a valid file"; else ok; fi
    for c in $CASES; do
        f=${c%%:*} code=${c##*:}
        rm -f "$T/x.meso"
        "$MB" $cmd -i "$T/$f" -o "$T/x.meso" >/dev/null 2>"$T/err"
        rc=$?
        if [ $rc -eq 3 ]; then ok; else fail "$cmd $f: exit $rc, expected 3"; fi
        if grep -q "E$code" "$T/err"; then ok; else fail "$cmd $f: stderr lacks E$code"; fi
        if [ -e "$T/x.meso" ]; then fail "$cmd $f: wrote an output file"; else ok; fi
    done
done
ls -a "$T" | grep -q '\.tmp\.' && fail "a temporary output file was left behind"

echo "$checks checks passed, $failures failed"
[ $failures -eq 0 ]
