#!/bin/sh
# mesobake shell from the command line: byte-identical output for -j 1 and
# -j 2, the report's keys, exit 8 for a shell left with defects unless
# --allow-defects, and bad input (the defective meshes MAKE_DEFECTIVE
# generates, see tests/common/defective_meshes.h, plus small ones written
# here): a coded error, a non-zero exit, and no output file.
# usage: shell_cli.sh MESOBAKE MESOINSPECT TEST_DATA_DIR MAKE_DEFECTIVE
set -u
bake=$1 inspect=$2 data=$3 make_defective=$4
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { # DESCRIPTION COMMAND...
  d=$1; shift
  if "$@"; then echo "ok   $d"; else echo "FAIL $d"; fail=1; fi
}

"$bake" shell -i "$data/spot_low_resolution.obj" -o "$tmp/j1.meso" -j 1 --report "$tmp/r.json" >/dev/null 2>&1
check "bake with -j 1 succeeds" test -s "$tmp/j1.meso"
"$bake" shell -i "$data/spot_low_resolution.obj" -o "$tmp/j2.meso" -j 2 >/dev/null 2>&1
check "-j 1 and -j 2 give byte-identical files" cmp -s "$tmp/j1.meso" "$tmp/j2.meso"
check "the file validates fully" "$inspect" validate --full "$tmp/j1.meso" >/dev/null
for key in prisms inverted_prisms offset_self_intersections thickness_ratio_min thickness_ratio_mean \
           allowed_ratio_min allowed_ratio_mean vertices_below_half_allowed vertices_allowed_below_requested \
           vertices_regrown vertices_bent \
           vertices_lp vertices_normal seconds_total; do
  check "report has \"$key\"" grep -q "\"$key\":" "$tmp/r.json"
done
check "prisms = triangle count (1654)" grep -q '"prisms":[[:space:]]*1654,' "$tmp/r.json"
check "SDIR and STHK chunks are present" sh -c "'$inspect' info '$tmp/j1.meso' | grep -q SDIR && '$inspect' info '$tmp/j1.meso' | grep -q STHK"
"$bake" shell -i "$data/saddle.obj" -o "$tmp/env.meso" --kind envelope >/dev/null 2>&1
check "envelope shells of open surfaces bake" test -s "$tmp/env.meso"

# Envelopes are drawn from bottom to top, and each layer repaired against
# the base alone left such prisms inverted (bake/shell_envelope.h): spot_uv
# at the default 5 % kept 18 and at 10 % 51, and the bake was refused
# (exit 8, E3115). Now: exit 0, nothing inverted or intersecting, and the
# file validates in full.
for t in 0.05 0.1; do
  rc=0
  "$bake" shell -i "$data/spot_uv.obj" -o "$tmp/envt.meso" --kind envelope --thickness-rel $t \
    --report "$tmp/envt.json" >/dev/null 2>&1 || rc=$?
  check "spot_uv envelope $t: exit 0 (got $rc)" test "$rc" = 0
  for key in inverted_prisms offset_self_intersections offset_base_intersections; do
    check "spot_uv envelope $t: $key = 0" grep -q "\"$key\":[[:space:]]*0," "$tmp/envt.json"
  done
  check "spot_uv envelope $t: the file validates fully" "$inspect" validate --full "$tmp/envt.meso" >/dev/null
done
# ...and on every bundled closed mesh at 10 % (spot_low_resolution and blub
# need the stage there).
for mesh in spot_low_resolution blub_fish_low_resolution torus torus_uv sphere; do
  "$bake" shell -i "$data/$mesh.obj" -o "$tmp/envt.meso" --kind envelope --thickness-rel 0.1 \
    --report "$tmp/envt.json" >/dev/null 2>&1
  for key in inverted_prisms offset_self_intersections offset_base_intersections; do
    check "$mesh envelope 0.1: $key = 0" grep -q "\"$key\":[[:space:]]*0," "$tmp/envt.json"
  done
done

num() { # KEY: the number under KEY in $tmp/goal.json
  sed -n "s/.*\"$1\":[[:space:]]*\([-+0-9.eE]*\).*/\1/p" "$tmp/goal.json"
}
# The goal, on the bundled closed meshes: zero inverted prisms and
# zero self- or base intersections at 10 % exterior and 5 % interior with the
# defaults (hybrid + repair).
for mesh in spot_low_resolution blub_fish_low_resolution torus torus_uv sphere; do
  for kt in "exterior 0.1" "interior 0.05"; do
    set -- $kt
    "$bake" shell -i "$data/$mesh.obj" -o "$tmp/goal.meso" --kind "$1" --thickness-rel "$2" \
      --report "$tmp/goal.json" >/dev/null 2>&1
    for key in inverted_prisms offset_self_intersections offset_base_intersections; do
      check "$mesh $1 $2: $key = 0" grep -q "\"$key\":[[:space:]]*0," "$tmp/goal.json"
    done
    # Thickness kept (bake/shell_allowed.h): allowed <= requested, so the
    # ratio to the allowed is never below the ratio to the requested, and it
    # is capped at 1 per vertex (1e-6: float directors of the requested
    # length are a rounding over or under it); the counts count vertices.
    check "$mesh $1 $2: thickness_ratio <= allowed_ratio <= 1" awk -v a="$(num allowed_ratio_min)" \
      -v b="$(num allowed_ratio_mean)" -v c="$(num thickness_ratio_min)" -v d="$(num thickness_ratio_mean)" \
      'BEGIN { exit !(a != "" && a >= c - 1e-6 && b >= d - 1e-6 && a <= b && b <= 1) }'
    check "$mesh $1 $2: allowed counts <= vertices" awk -v h="$(num vertices_below_half_allowed)" \
      -v l="$(num vertices_allowed_below_requested)" -v n="$(num vertices_normal)" -v p="$(num vertices_lp)" \
      'BEGIN { exit !(h != "" && l != "" && h <= n + p && l <= n + p) }'
  done
done

# Defects left (--no-repair on spot: inverted prisms): exit 8, E3115, no
# .meso, but the --report file, which says what is left; --allow-defects
# writes the shell, exit 0.
rm -f "$tmp/nr.meso" "$tmp/nr.json"
"$bake" shell -i "$data/spot_low_resolution.obj" -o "$tmp/nr.meso" --no-repair --report "$tmp/nr.json" \
  >/dev/null 2>"$tmp/nr.err"
rc=$?
check "--no-repair with defects: exit 8 (got $rc)" test "$rc" = 8
check "--no-repair with defects: E3115 names them" grep -q "E3115.*inverted prisms" "$tmp/nr.err"
check "--no-repair with defects: no output" test ! -e "$tmp/nr.meso"
check "--no-repair with defects: report written, output_written false" \
  grep -q '"output_written":[[:space:]]*false' "$tmp/nr.json"
check "--no-repair with defects: report counts inverted prisms" \
  sh -c "grep -q '\"inverted_prisms\":[[:space:]]*[1-9]' '$tmp/nr.json'"
"$bake" shell -i "$data/spot_low_resolution.obj" -o "$tmp/nr.meso" --no-repair --allow-defects >/dev/null 2>&1
rc=$?
check "--no-repair --allow-defects: exit 0 (got $rc)" test "$rc" = 0
check "--no-repair --allow-defects: writes the shell" test -s "$tmp/nr.meso"
for key in seconds_field seconds_directors seconds_repair seconds_validate; do
  check "report has \"$key\"" grep -q "\"$key\":" "$tmp/r.json"
done
# Where nothing limits the normal offset (sphere, torus at 10 % exterior:
# every director keeps its full length) all of the allowed is kept; on spot
# the geometry limits some vertices (its ears and legs face each other).
"$bake" shell -i "$data/torus.obj" -o "$tmp/goal.meso" --thickness-rel 0.1 --report "$tmp/goal.json" >/dev/null 2>&1
check "torus exterior 0.1: all of the allowed kept" awk -v b="$(num allowed_ratio_mean)" \
  -v h="$(num vertices_below_half_allowed)" 'BEGIN { exit !(b > 0.9999 && h == 0) }'
"$bake" shell -i "$data/spot_low_resolution.obj" -o "$tmp/goal.meso" --thickness-rel 0.1 \
  --report "$tmp/goal.json" >/dev/null 2>&1
check "spot exterior 0.1: the geometry limits some vertices" awk -v l="$(num vertices_allowed_below_requested)" \
  'BEGIN { exit !(l > 0) }'
# Regrow (bake/shell_regrow.h) gives back length to directors repair
# shortened, never more than repair took (the goal loop above checks the
# shells stay valid with it).
check "spot exterior 0.1: regrow lengthens some shortened directors" awk -v g="$(num vertices_regrown)" \
  -v s="$(num vertices_shortened)" 'BEGIN { exit !(g > 0 && g <= s) }'
# Bend (bake/shell_bend.h) turns directors regrow could not lengthen
# towards the normal (tests/unit/test_shell_bend.c checks what it may do);
# only directors repair shortened bend, and on blub at 10 % exterior some do.
rm -f "$tmp/goal.json"
check "blub exterior 0.1 bakes" "$bake" shell -i "$data/blub_fish_low_resolution.obj" -o "$tmp/goal.meso" \
  --thickness-rel 0.1 --report "$tmp/goal.json"
check "blub exterior 0.1: bend turns some shortened directors" awk -v b="$(num vertices_bent)" \
  -v s="$(num vertices_shortened)" 'BEGIN { exit !(b > 0 && b <= s) }'

refuse() { # DESCRIPTION EXPECTED_EXIT INPUT
  rm -f "$tmp/out.meso"
  "$bake" shell -i "$3" -o "$tmp/out.meso" >"$tmp/stdout" 2>"$tmp/stderr"
  rc=$?
  check "$1: exit $2 (got $rc)" test "$rc" = "$2"
  check "$1: says 'mesobake error'" grep -q "mesobake error" "$tmp/stderr"
  check "$1: writes no output" test ! -e "$tmp/out.meso"
}
: >"$tmp/empty.obj"
refuse "empty file" 3 "$tmp/empty.obj"
refuse "missing file" 2 "$tmp/nope.obj"
printf 'v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n' >"$tmp/nan.obj"
refuse "NaN coordinate" 3 "$tmp/nan.obj"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 2 1 4\n' >"$tmp/fin.obj"
refuse "non-manifold fin" 3 "$tmp/fin.obj"
printf 'v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n' >"$tmp/degenerate.obj"
refuse "degenerate face" 3 "$tmp/degenerate.obj"
printf 'not a mesh at all\n' >"$tmp/garbage.off"
refuse "garbage" 3 "$tmp/garbage.off"
# Generated stand-ins for the unlicensed defective meshes the tests read
# from outside the repository before
# (same defects: duplicated faces in both orientations, an unwelded
# self-intersecting union of two boxes as OBJ and binary PLY, an open
# multi-component soup, intersecting open parts). Missing files fail.
mkdir "$tmp/defective"
check "make_defective writes the defective meshes" "$make_defective" "$tmp/defective"
for f in doubled_faces.obj two_boxes.obj two_boxes.ply soup.obj open_parts.obj; do
  refuse "defective/$f" 3 "$tmp/defective/$f"
done
# folded_cube is topologically clean: its fold is geometric. It must
# either bake a valid shell or be refused; never crash.
check "folded_cube.obj exists" test -s "$tmp/defective/folded_cube.obj"
"$bake" shell -i "$tmp/defective/folded_cube.obj" -o "$tmp/fold.meso" >/dev/null 2>&1
rc=$?
check "folded_cube: exit 0 or 3 (got $rc)" sh -c "[ $rc = 0 ] || [ $rc = 3 ]"
# --update (bake/shell_update.c; tests/integration/test_shell_update.c checks
# the directors against full re-bakes): an unchanged mesh recomputes
# nothing; other options, another topology or a file that is not a shell
# are refused with their codes, and nothing is written.
"$bake" shell -i "$data/torus.obj" -o "$tmp/old.meso" --thickness 0.05 >/dev/null 2>&1
"$bake" shell -i "$data/torus.obj" -o "$tmp/upd.meso" --thickness 0.05 --update "$tmp/old.meso" \
  --report "$tmp/upd.json" >/dev/null 2>&1
check "--update of an unchanged mesh succeeds" test -s "$tmp/upd.meso"
check "--update reports 0 vertices recomputed" grep -q '"vertices_recomputed":[[:space:]]*0' "$tmp/upd.json"
"$inspect" dump "$tmp/old.meso" SDIR -o "$tmp/old.sdir" >/dev/null 2>&1
"$inspect" dump "$tmp/upd.meso" SDIR -o "$tmp/upd.sdir" >/dev/null 2>&1
check "--update of an unchanged mesh keeps SDIR byte for byte" cmp -s "$tmp/old.sdir" "$tmp/upd.sdir"
update_refused() { # DESCRIPTION EXIT CODE ARGS...
  what=$1 want=$2 code=$3; shift 3
  rm -f "$tmp/refused.meso"
  "$bake" shell -o "$tmp/refused.meso" "$@" 2>"$tmp/err.txt" >/dev/null
  rc=$?
  check "--update $what: exit $want (got $rc)" test "$rc" = "$want"
  check "--update $what: E$code" grep -q "E$code" "$tmp/err.txt"
  check "--update $what: nothing written" test ! -e "$tmp/refused.meso"
}
update_refused "other thickness" 1 3117 -i "$data/torus.obj" --thickness 0.06 --update "$tmp/old.meso"
update_refused "other topology" 3 3118 -i "$data/sphere.obj" --thickness 0.05 --update "$tmp/old.meso"
"$bake" mesh -i "$data/torus.obj" -o "$tmp/mesh.meso" >/dev/null 2>&1
update_refused "of a mesh file" 3 3116 -i "$data/torus.obj" --thickness 0.05 --update "$tmp/mesh.meso"
check "usage: conflicting thickness flags exit 1" sh -c "'$bake' shell -i x -o y --thickness 1 --thickness-rel 0.1 2>/dev/null; [ \$? = 1 ]"
check "usage: bad kind exits 1" sh -c "'$bake' shell -i x -o y --kind sideways 2>/dev/null; [ \$? = 1 ]"
exit $fail
