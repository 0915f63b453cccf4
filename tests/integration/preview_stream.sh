#!/bin/sh
# preview_stream.sh MESOBAKE MESOINSPECT DATA_DIR
#
# Every prefix at a level boundary draws (issue 14, Deliver 5), through
# `mesoinspect preview --stream-bytes N --stats` (Deliver 4): a mesh and a
# shell stored with parts and a cells object baked from the bundled data
# (test_rt_prefixes does the same in one process for every bundled mesh and
# skeleton as every kind, frusta included). For each level L, the first prefix_bytes of L
# (mesoinspect info --format json; FORMAT.md §7.10) are fed to preview at
# --pixel-error 0 (the finest level that has arrived, everywhere):
#  - it exits 0, says nothing on stderr (bytes not arrived yet are not an
#    error) and covers pixels;
#  - the stats name the level drawn: L itself when a whole level drew;
#    drawn in parts (a mesh whose parts' finer levels come later in the
#    file), every part's drawn level has an error no larger than L's (else
#    the whole level L, which has arrived, is the better picture);
#  - it read no more than had arrived, and its stats carry bytes_resident,
#    bytes_read, steps_per_pixel, gpu_ms and stream_bytes = N;
#  - what the uploads hold on the GPU is no more than libmeso's estimate
#    before them (its memory budget makes room by the estimate);
# and one byte less than the coarsest level's prefix draws nothing (exit 5).
# At a coarser pixel error (3 px, the mesh): where the whole file draws
# level W (as a bake without parts draws it), each prefix of level L draws
# the whole level max(W, L), or parts; parts that fell back from what the
# whole file draws (their finer levels not arrived) have no part drawn with
# a larger error than that whole level's. A thick torus shell whose coarser
# levels have base meshes of their own streams the same way, and is drawn
# at those levels only by the smooth mapping they were measured for.
set -u
MB=$1
MI=$2
DATA=$3
. "$(dirname "$0")/check_lib.sh"

bake() { # NAME ARGS...: bakes $T/NAME.meso, 77 when this build cannot
    name=$1
    shift
    run "$MB" "$@" -o "$T/$name.meso"
    if [ "$rc" -eq 5 ]; then
        echo "SKIP: mesobake cannot bake $name in this build" >&2
        exit 77
    fi
    expect_rc 0 "bake $name"
}
bake mesh mesh -i "$DATA/spot_uv.obj"
bake shell shell -i "$DATA/spot_uv.obj" --texture bricks:64 --thickness-rel 0.02
bake cells cells -i "$DATA/spot_low_resolution.obj"
# A thick shell over torus_uv: its native levels after level 0 have base
# meshes of their own (bake/shell_base_levels.c), with no texture level.
bake shellbase shell -i "$DATA/torus_uv.obj" --texture bricks:64 --thickness-rel 0.1

for name in mesh shell cells shellbase; do
    run "$MI" info --format json "$T/$name.meso"
    expect_rc 0 "$name: info --format json"
    cp "$T/out" "$T/$name.json"
    prefixes=$(python3 -c 'import json, sys; print(" ".join("%d:%d" % (l["lod"], l["prefix_bytes"]) for l in json.load(open(sys.argv[1]))["objects"][0]["levels"]))' "$T/$name.json")
    [ -n "$prefixes" ] || fail "$name: no levels listed"
    coarsest=
    for lp in $prefixes; do
        lod=${lp%%:*}
        n=${lp#*:}
        coarsest=$n
        run "$MI" preview "$T/$name.meso" -o "$T/p.png" --size 96x96 --pixel-error 0 --stream-bytes "$n" \
            --stats "$T/s.json"
        expect_rc 0 "$name: the first $n bytes (level $lod) draw"
        [ -s "$T/err" ] && fail "$name: the first $n bytes: stderr is not empty"
        run python3 - "$T/$name.json" "$T/s.json" "$lod" "$n" <<'PY'
import json, sys
info = json.load(open(sys.argv[1])); st = json.load(open(sys.argv[2]))
L, n = int(sys.argv[3]), int(sys.argv[4])
o = info["objects"][0]
err = {l["lod"]: l["error"] for l in o["levels"]}
def fail(msg): print(msg); sys.exit(1)
for k in ("bytes_resident", "bytes_read", "steps_per_pixel", "gpu_ms", "stream_bytes", "covered_pixels"):
    if k not in st: fail("stats lack " + k)
if st["stream_bytes"] != n: fail("stream_bytes %d, not %d" % (st["stream_bytes"], n))
if st["bytes_read"] > n: fail("read %d bytes of the %d that had arrived" % (st["bytes_read"], n))
if st["covered_pixels"] <= 0: fail("nothing drawn")
s = st["objects"][0]
# GPU bytes: what the uploads hold, never above what the budget made room for
if not 0 < s["gpu_bytes_resident"] <= s["gpu_bytes_estimated"]:
    fail("GPU bytes %d, estimated %d" % (s["gpu_bytes_resident"], s["gpu_bytes_estimated"]))
if st["gpu_bytes_resident"] != s["gpu_bytes_resident"]: fail("the total GPU bytes are not the object's")
if "part_levels_drawn" in s:
    perr = {(p["part"], p["lod"]): p["error"] for p in o["parts"]["levels"]}
    worst = max(perr[(q + 1, lv)] for q, lv in enumerate(s["part_levels_drawn"]))
    if worst > err[L]: fail("parts drawn with error %g where the whole level %d (%g) has arrived" % (worst, L, err[L]))
    if s["levels_drawn"] != min(s["part_levels_drawn"]): fail("levels_drawn is not the finest part's level")
elif s["levels_drawn"] != L:
    fail("level %d drawn, not %d" % (s["levels_drawn"], L))
print("ok")
PY
        expect_rc 0 "$name: the first $n bytes: $(cat "$T/out")"
    done
    run "$MI" preview "$T/$name.meso" -o "$T/p.png" --size 96x96 --stream-bytes $((coarsest - 1))
    expect_rc 5 "$name: one byte short of the coarsest level draws nothing"
done

# The mesh at 3 px: W from a bake without parts, the parts' levels from the whole file.
bake mesh_np mesh -i "$DATA/spot_uv.obj" --parts none
tau=3
run "$MI" preview "$T/mesh_np.meso" -o "$T/p.png" --size 256x256 --pixel-error $tau --stats "$T/w.json"
expect_rc 0 "mesh without parts at $tau px"
run "$MI" preview "$T/mesh.meso" -o "$T/p.png" --size 256x256 --pixel-error $tau --stats "$T/full.json"
expect_rc 0 "mesh at $tau px"
for lp in $(python3 -c 'import json, sys; print(" ".join("%d:%d" % (l["lod"], l["prefix_bytes"]) for l in json.load(open(sys.argv[1]))["objects"][0]["levels"]))' "$T/mesh.json"); do
    lod=${lp%%:*}
    n=${lp#*:}
    run "$MI" preview "$T/mesh.meso" -o "$T/p.png" --size 256x256 --pixel-error $tau --stream-bytes "$n" \
        --stats "$T/s.json"
    expect_rc 0 "mesh: the first $n bytes at $tau px"
    run python3 - "$T/mesh.json" "$T/w.json" "$T/full.json" "$T/s.json" "$lod" <<'PY'
import json, sys
info, w, full, st = (json.load(open(a)) for a in sys.argv[1:5])
L = int(sys.argv[5])
o = info["objects"][0]
err = {l["lod"]: l["error"] for l in o["levels"]}
W = w["objects"][0]["levels_drawn"]
whole = max(W, L)
s = st["objects"][0]
def fail(msg): print(msg); sys.exit(1)
if "part_levels_drawn" in s:
    fp = full["objects"][0].get("part_levels_drawn")
    if fp and any(a > b for a, b in zip(s["part_levels_drawn"], fp)):  # fell back
        perr = {(p["part"], p["lod"]): p["error"] for p in o["parts"]["levels"]}
        worst = max(perr[(q + 1, lv)] for q, lv in enumerate(s["part_levels_drawn"]))
        if worst > err[whole]:
            fail("parts %r drawn, worst error %g, where the whole level %d (%g) has arrived" %
                 (s["part_levels_drawn"], worst, whole, err[whole]))
elif s["levels_drawn"] != whole:
    fail("whole level %d drawn, not %d (W %d, arrived %d)" % (s["levels_drawn"], whole, W, L))
print("ok")
PY
    expect_rc 0 "mesh at $tau px, the first $n bytes: $(cat "$T/out")"
done

# Levels with a base mesh of their own are measured for the smooth mapping
# (and segment, slices): far away the smooth draw picks one, the curved and
# tetra draws never do (rt_levels.c usable).
own=$(python3 -c 'import json, sys; print(" ".join(str(l["lod"]) for l in json.load(open(sys.argv[1]))["objects"][0]["levels"] if l["lod"] > 0 and l["form"] == "native"))' "$T/shellbase.json")
[ -n "$own" ] || fail "shellbase: no native level with its own base mesh"
for tech in smooth curved tetra; do
    run "$MI" preview "$T/shellbase.meso" -o "$T/p.png" --zoom 0.1 --technique $tech --stats "$T/s.json"
    expect_rc 0 "shellbase far away, $tech"
    drawn=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["objects"][0]["levels_drawn"])' "$T/s.json")
    case " $own " in
    *" $drawn "*) [ $tech = smooth ] || fail "shellbase: $tech drew level $drawn, whose base mesh is its own" ;;
    *) [ $tech != smooth ] || fail "shellbase: smooth drew level $drawn, not one of $own" ;;
    esac
    ok
done

echo "preview_stream: $checks checks, $failures failures"
[ "$failures" -eq 0 ]
