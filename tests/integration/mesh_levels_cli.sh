#!/bin/sh
# mesh_levels_cli.sh MESOBAKE MESOINSPECT DATA_DIR
#
# `mesobake mesh --levels` and `mesoinspect info`'s levels (issue 14): the
# bundled torus gets coarse levels (one MESH per lod, fewer triangles each,
# errors non-decreasing from 0), `mesoinspect info --format json` lists them
# with bytes and prefix_bytes equal to what the chunk listing of the same
# file gives (recomputed here from offsets and stored sizes: FORMAT.md
# §7.10), the text output has one line per level, --levels 1 writes no
# LODS and one MESH, --levels N caps the count, Draco levels validate in
# full, -j 1 and -j 2 give the same bytes, pack keeps the levels, bad
# values exit 1; a mesh's parts (FORMAT.md 7.11) against the chunk
# listing, in preview --stats, --parts none, pack.
set -u
MB=$1
MI=$2
DATA=$3
. "$(dirname "$0")/check_lib.sh"

run "$MB" mesh -i "$DATA/torus.obj" -o "$T/t.meso" --report "$T/r.json"
if [ "$rc" -eq 5 ]; then
    echo "SKIP: mesobake has no mesh import or meshoptimizer in this build" >&2
    exit 77
fi
expect_rc 0 "bake torus with levels"
run "$MI" validate --full "$T/t.meso"
expect_rc 0 "levels validate in full"
run "$MI" info --format json "$T/t.meso"
expect_rc 0 "info --format json"
cp "$T/out" "$T/info.json"
NF=$(grep -c '^f ' "$DATA/torus.obj")
run python3 - "$T/info.json" "$T/r.json" "$NF" "$(wc -c <"$T/t.meso")" <<'PY'
import json, sys
info = json.load(open(sys.argv[1])); rep = json.load(open(sys.argv[2]))
nf = int(sys.argv[3]); size = int(sys.argv[4])
def fail(msg): print(msg); sys.exit(1)
obj = info["objects"][0]; lv = obj["levels"]; chunks = info["chunks"]
if len(lv) < 3: fail("fewer than 3 levels: %d" % len(lv))
pad = lambda c: c["offset"] + c["stored_size"]  # where its stored bytes end (FORMAT.md 7.10)
head = max(pad(c) for c in chunks if c["type"] in ("META", "OBJT", "LODS"))
meshes = [c for c in chunks if c["type"] == "MESH"]
if len(meshes) != len(lv): fail("%d MESH chunks for %d levels" % (len(meshes), len(lv)))
prev_err, prev_tri = -1.0, None
for L, l in enumerate(lv):
    if l["lod"] != L or l["form"] != "native": fail("level %d: lod/form %r" % (L, l))
    m = [c for c in meshes if c["lod"] == L]
    if len(m) != 1: fail("level %d: %d MESH chunks" % (L, len(m)))
    m = m[0]
    if l["bytes"] != m["stored_size"]: fail("level %d bytes %d != MESH stored %d" % (L, l["bytes"], m["stored_size"]))
    if l["prefix_bytes"] != max(head, pad(m)): fail("level %d prefix %d != %d" % (L, l["prefix_bytes"], max(head, pad(m))))
    if l["prefix_bytes"] > size: fail("prefix beyond the file")
    tri = m["mesh"]["triangle_count"]
    if l["triangles"] != tri: fail("level %d triangles %r != chunk %d" % (L, l["triangles"], tri))
    if L == 0 and (tri != nf or l["error"] != 0): fail("level 0: %d triangles (OBJ %d), error %g" % (tri, nf, l["error"]))
    if prev_tri is not None and not tri < prev_tri: fail("triangles not decreasing at level %d" % L)
    if l["error"] < prev_err: fail("error decreasing at level %d" % L)
    if abs(l["error"] - rep["levels"][L]["error"]) > 1e-6 * max(1, l["error"]): fail("info and report errors differ")
    if rep["levels"][L]["triangles"] != tri: fail("report triangles differ")
    prev_err, prev_tri = l["error"], tri
# coarse first in the file: each coarser level's prefix is shorter
if not all(lv[i]["prefix_bytes"] > lv[i + 1]["prefix_bytes"] for i in range(len(lv) - 1)): fail("prefixes not nested")
print(len(lv))
PY
expect_rc 0 "levels in info --format json against the chunk listing"
NLEV=$(cat "$T/out")

# text: one line per level under "Levels:"
run "$MI" info "$T/t.meso"
LINES=$(awk '/^Levels:/ { on = 1; next } on && /^$/ { exit } on && $1 == "1" { n++ } END { print n + 0 }' "$T/out")
expect_eq "$LINES" "$NLEV" "text info: one line per level"

# --levels 1: the finest only, no LODS
run "$MB" mesh -i "$DATA/torus.obj" -o "$T/one.meso" --levels 1
expect_rc 0 "--levels 1"
run "$MI" info --format json "$T/one.meso"
cp "$T/out" "$T/j.json"
run python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
types = [c["type"] for c in d["chunks"]]
assert "LODS" not in types and types.count("MESH") == 1, types
assert len(d["objects"][0]["levels"]) == 1 and d["objects"][0]["levels"][0]["error"] == 0
' "$T/j.json"
expect_rc 0 "--levels 1: one MESH, no LODS, one level"

# --levels 3 caps the chain
run "$MB" mesh -i "$DATA/torus.obj" -o "$T/three.meso" --levels 3
expect_rc 0 "--levels 3"
run "$MI" info --format json "$T/three.meso"
cp "$T/out" "$T/j.json"
run python3 -c 'import json, sys; assert len(json.load(open(sys.argv[1]))["objects"][0]["levels"]) == 3' "$T/j.json"
expect_rc 0 "--levels 3: three levels"

# threads never change the bytes
run "$MB" mesh -i "$DATA/torus.obj" -o "$T/j1.meso" -j 1
expect_rc 0 "-j 1"
run "$MB" mesh -i "$DATA/torus.obj" -o "$T/j2.meso" -j 2
expect_rc 0 "-j 2"
same_bytes "$T/j1.meso" "$T/j2.meso" "-j 1 and -j 2"
same_bytes "$T/j1.meso" "$T/t.meso" "-j 1 and all cores"

# Draco: every level compressed, validates in full
run "$MB" mesh -i "$DATA/torus.obj" -o "$T/d.meso" --draco
if [ "$rc" -ne 5 ]; then
    expect_rc 0 "--draco with levels"
    run "$MI" validate --full "$T/d.meso"
    expect_rc 0 "Draco levels validate in full"
    run "$MI" info --format json "$T/d.meso"
    cp "$T/out" "$T/j.json"
    run python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
m = [c for c in d["chunks"] if c["type"] == "MESH"]
assert len(m) == len(d["objects"][0]["levels"]) >= 3 and all(c["encoding"] == 1 for c in m), m
' "$T/j.json"
    expect_rc 0 "--draco: one Draco MESH per level"
fi

# pack keeps each object's levels, renumbered, in one LODS chunk
run "$MB" pack "$T/one.meso" "$T/t.meso" -o "$T/pack.meso"
expect_rc 0 "pack a one-level and a levelled file"
run "$MI" validate --full "$T/pack.meso"
expect_rc 0 "packed levels validate in full"
run "$MI" info --format json "$T/pack.meso"
cp "$T/out" "$T/p.json"
run python3 -c '
import json, sys
p = json.load(open(sys.argv[1])); t = json.load(open(sys.argv[2]))
a, b = p["objects"]
assert len(a["levels"]) == 1 and a["levels"][0]["error"] == 0, a["levels"]
src = t["objects"][0]["levels"]
assert [l["error"] for l in b["levels"]] == [l["error"] for l in src], (b["levels"], src)
assert [l["triangles"] for l in b["levels"]] == [l["triangles"] for l in src]
assert [l["bytes"] for l in b["levels"]] == [l["bytes"] for l in src]
' "$T/p.json" "$T/info.json"
expect_rc 0 "packed object 2 has the levels of the levelled input"

# bad values
for bad in 0 17 x -1; do
    run "$MB" mesh -i "$DATA/torus.obj" -o "$T/bad.meso" --levels "$bad"
    expect_rc 1 "--levels $bad"
    expect_err "levels" "--levels $bad names the option"
done
[ ! -e "$T/bad.meso" ] && ok || fail "a refused command wrote its output"

# Parts (FORMAT.md 7.11): spot_uv gets them by default; info lists each
# part level with the bytes and prefix its PMSH chunk gives in the chunk
# listing; preview --stats reports the level each part drew (all 0 at
# pixel error 0, and no part coarser than at a larger pixel error, whose
# resident bytes are no more); --parts none writes none; pack keeps them.
run "$MB" mesh -i "$DATA/spot_uv.obj" -o "$T/s.meso"
expect_rc 0 "bake spot_uv with parts"
run "$MI" validate --full "$T/s.meso"
expect_rc 0 "parts validate in full"
run "$MI" info --format json "$T/s.meso"
cp "$T/out" "$T/s.json"
# The preview's GL driver (Mesa) leaks under LeakSanitizer, as in
# pack_cli.sh: only the preview runs without leak detection.
export MESA_SHADER_CACHE_DISABLE="${MESA_SHADER_CACHE_DISABLE:-true}" EGL_PLATFORM=surfaceless
for tau in 0 16; do
    run env ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" "$MI" preview "$T/s.meso" -o "$T/s$tau.png" --size 256x256 --zoom 3 --pixel-error $tau --stats "$T/st$tau.json"
    expect_rc 0 "preview at pixel error $tau"
done
run python3 - "$T/s.json" "$T/st0.json" "$T/st16.json" <<'PY'
import json, sys
info = json.load(open(sys.argv[1])); s0 = json.load(open(sys.argv[2])); s16 = json.load(open(sys.argv[3]))
def fail(msg): print(msg); sys.exit(1)
parts = info["objects"][0]["parts"]
if not parts or parts["count"] < 2: fail("spot_uv has no parts: %r" % parts)
chunks = info["chunks"]
head = max(c["offset"] + c["stored_size"] for c in chunks if c["type"] in ("META", "OBJT", "LODS", "PRTS"))
for l in parts["levels"]:
    m = [c for c in chunks if c["type"] == "PMSH" and c["lod"] == l["lod"] and c["dims"][0] == l["part"]]
    if len(m) != 1: fail("part %d lod %d: %d PMSH chunks" % (l["part"], l["lod"], len(m)))
    if l["chunk"] != m[0]["index"] or l["bytes"] != m[0]["stored_size"]: fail("part %d lod %d: chunk or bytes" % (l["part"], l["lod"]))
    if l["prefix_bytes"] != max(head, m[0]["offset"] + m[0]["stored_size"]): fail("part %d lod %d: prefix" % (l["part"], l["lod"]))
p0 = s0["objects"][0].get("part_levels_drawn"); p16 = s16["objects"][0].get("part_levels_drawn")
if p0 is None or len(p0) != parts["count"] or any(p0): fail("pixel error 0: %r" % p0)
if p16 is None or len(p16) != parts["count"]: fail("pixel error 16: %r" % p16)
if s16["objects"][0]["bytes_resident"] > s0["objects"][0]["bytes_resident"]: fail("more bytes at 16 px")
print("parts %d, levels drawn at 16 px %r" % (parts["count"], p16))
PY
expect_rc 0 "parts: info against the chunks, preview --stats part levels"
run "$MB" mesh -i "$DATA/spot_uv.obj" -o "$T/sn.meso" --parts none
run "$MI" info --format json "$T/sn.meso"
grep -q '"parts":[[:space:]]*null' "$T/out" && ok || fail "--parts none still wrote parts"
run "$MB" pack "$T/s.meso" "$T/t.meso" -o "$T/sp.meso"
expect_rc 0 "pack a mesh with parts"
run "$MI" validate --full "$T/sp.meso"
expect_rc 0 "the packed file validates in full"
run "$MI" info "$T/sp.meso"
expect_out "Parts of object 1" "pack keeps the parts"

echo "mesh_levels_cli: $checks checks, $failures failures"
[ "$failures" -eq 0 ]
