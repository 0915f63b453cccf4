#!/bin/sh
# The exit-code table of README ("Exit codes") walked row by row, for every
# mesobake command and for mesoinspect: each failure kind exits with its
# documented code, stderr names the problem, and no output file appears.
#   1 command-line error   2 IO failure   3 invalid input file
#   8 a shell left with defects (mesobake shell without --allow-defects)
#   (4 internal errors and 5, a missing adapter, cannot be provoked on
#   purpose in a full build: they are not rows here.)
# Every malformed input is generated in the test's temp dir.
# usage: exit_codes.sh MESOBAKE MESOINSPECT TEST_DATA_DIR
set -u
bake=$1 inspect=$2 data=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
rows=0

# row CODE PATTERN DESCRIPTION COMMAND...: runs COMMAND (its output file,
# if any, is $tmp/out.*), asserts the exit code, that stderr matches the
# extended regexp PATTERN (case-insensitive; validate answers on stdout),
# and that no $tmp/out.* exists.
row() {
  want=$1 pat=$2 d=$3
  shift 3
  rows=$((rows + 1))
  rm -f "$tmp"/out.*
  "$@" >"$tmp/stdout" 2>"$tmp/stderr"
  got=$?
  why=""
  [ "$got" = "$want" ] || why="exit $got, expected $want"
  # (validate reports on stdout, which it was asked for; the others on stderr)
  cat "$tmp/stderr" "$tmp/stdout" | grep -Eqi -- "$pat" || why="$why; the diagnostics do not match /$pat/"
  set -- "$tmp"/out.*
  [ -e "$1" ] && why="$why; wrote $1"
  if [ -z "$why" ]; then
    echo "ok   [$want] $d"
  else
    echo "FAIL [$want] $d: $why"
    sed 's/^/       stderr: /' "$tmp/stderr" | head -5
    fail=1
  fi
}

# --- inputs ---------------------------------------------------------------
mesh="$data/sphere.obj"
printf '' >"$tmp/empty.obj"
printf 'this is not a mesh\n' >"$tmp/words.obj"
cp "$mesh" "$tmp/sphere.xyz"
printf '1 1 0 0 0 1 -1\n' >"$tmp/one_node.swc"
printf '1 1 1e300 0 0 1 -1\n2 3 0 1 0 1 1\n' >"$tmp/huge.swc"
printf '1 1 0 0 0 0 -1\n2 3 0 1 0 0 1\n3 3 0 2 0 0 2\n' >"$tmp/zero_radii.swc"
printf '1 1 0 0 0 1 -1\n2 3 0 1 0 1\n' >"$tmp/six_fields.swc"
printf '1 1 0 0 0 1 -1\n2 3 0 1 nan 1 1\n' >"$tmp/nan.swc"
printf '0 0 0 0\n0 1 0 0\n' >"$tmp/zero_radii.skel"
printf '0 0 0 1\n0 0 -1e300 1\n' >"$tmp/huge.skel"
printf '0 0 0 1\n' >"$tmp/one_node.skel"
printf '0 0 0 1\n0 0 0 1\n' >"$tmp/zero_length.skel"
printf '0 0 0 1 5\n0 1 0 1\n' >"$tmp/bad_parent.skel"
printf '\211PNG\r\n\032\n this is not a PNG' >"$tmp/bad.png"
head -c 63 /dev/zero >"$tmp/vol63.raw"      # 4x4x4 needs 64 bytes
head -c 100 /dev/zero >"$tmp/tiles100.raw"  # R = 4 needs 2 * 64 bytes
head -c 128 /dev/zero >"$tmp/zeros4.raw"    # R = 4, every cell 0
printf 'MESO but not really' >"$tmp/garbage.meso"
"$bake" mesh -i "$mesh" -o "$tmp/good.meso" >/dev/null 2>&1 || { echo "FAIL cannot bake a good file"; exit 1; }
head -c 100 "$tmp/good.meso" >"$tmp/truncated.meso"

# --- 1: command-line errors -------------------------------------------------
for cmd in mesh shell cells frusta; do
  row 1 "unrecognized option '--bogus'" "$cmd: unknown option" "$bake" $cmd -i "$mesh" -o "$tmp/out.meso" --bogus
  row 1 "usage|needs -i" "$cmd: no -i" "$bake" $cmd -o "$tmp/out.meso"
  row 1 "needs a value" "$cmd: option without its value" "$bake" $cmd -o "$tmp/out.meso" -i
done
row 1 "unknown command" "unknown command" "$bake" bake -i "$mesh" -o "$tmp/out.meso"
row 1 "--draco-bits" "mesh --draco-bits 0,10,12 (below 1)" "$bake" mesh -i "$mesh" -o "$tmp/out.meso" --draco-bits 0,10,12
row 1 "--draco-bits.*N in 2..24" "mesh --draco-bits 1,1,1 (one-bit normals, documented as refused)" \
  "$bake" mesh -i "$mesh" -o "$tmp/out.meso" --draco-bits 1,1,1
for bits in 25,10,12 14,25,12 14,10,25; do
  row 1 "--draco-bits.*1\.\.24" "mesh --draco-bits $bits (above the documented 24)" \
    "$bake" mesh -i "$mesh" -o "$tmp/out.meso" --draco-bits $bits
done
row 1 "--draco-bits" "mesh --draco-bits 4294967310,10,12 (int overflow)" \
  "$bake" mesh -i "$mesh" -o "$tmp/out.meso" --draco-bits 4294967310,10,12
row 1 "--draco-bits" "mesh --draco-bits 14,10 (two fields)" "$bake" mesh -i "$mesh" -o "$tmp/out.meso" --draco-bits 14,10
row 1 "--parts expects" "mesh --parts 63 (parts below 64 triangles)" "$bake" mesh -i "$mesh" -o "$tmp/out.meso" --parts 63
row 1 "--parts expects" "mesh --parts some (not a count)" "$bake" mesh -i "$mesh" -o "$tmp/out.meso" --parts some
row 1 "--draco-bits" "mesh --draco-bits 14,10,12,1 (four fields)" \
  "$bake" mesh -i "$mesh" -o "$tmp/out.meso" --draco-bits 14,10,12,1
row 1 "--thickness" "shell --thickness 1e999 (overflow)" "$bake" shell -i "$mesh" -o "$tmp/out.meso" --thickness 1e999
row 1 "--theta" "shell --theta '' (empty)" "$bake" shell -i "$mesh" -o "$tmp/out.meso" --theta ''
row 1 "-j" "shell -j 99999999999999999999 (long overflow)" "$bake" shell -i "$mesh" -o "$tmp/out.meso" -j 99999999999999999999
row 1 "--tiling" "shell --tiling 1,1e400" "$bake" shell -i "$mesh" -o "$tmp/out.meso" --tiling 1,1e400
row 1 "--dist-res" "shell --dist-res 18446744073709551617x8x8" \
  "$bake" shell -i "$mesh" -o "$tmp/out.meso" --dist-res 18446744073709551617x8x8
row 1 "--tiles" "cells --tiles 18446744073709551616" "$bake" cells -i "$mesh" -o "$tmp/out.meso" --tiles 18446744073709551616
row 1 "RNG" "cells --tile-map voronoi:8:-1 (negative seed)" \
  "$bake" cells -i "$mesh" -o "$tmp/out.meso" --tile-map voronoi:8:-1
row 1 "RNG" "cells --tile-map voronoi:8:18446744073709551616 (overflow)" \
  "$bake" cells -i "$mesh" -o "$tmp/out.meso" --tile-map voronoi:8:18446744073709551616
row 1 "colour" "cells --colour hash:-1 (negative seed)" "$bake" cells -i "$mesh" -o "$tmp/out.meso" --colour hash:-1
row 1 "--tolerance" "frusta --tolerance 1e400" "$bake" frusta -i "$tmp/one_node.swc" -o "$tmp/out.meso" --tolerance 1e400
row 1 "--relief-repeat" "frusta --relief-repeat -1" \
  "$bake" frusta -i "$data/neurom_simple.swc" -o "$tmp/out.meso" --relief bricks --relief-repeat -1
row 1 "--size" "preview --size 4294967297x1 (int overflow)" \
  "$inspect" preview "$tmp/good.meso" -o "$tmp/out.png" --size 4294967297x1
row 1 "--size" "preview --size 64x64x" "$inspect" preview "$tmp/good.meso" -o "$tmp/out.png" --size 64x64x
row 1 "--size" "preview --size -64x64" "$inspect" preview "$tmp/good.meso" -o "$tmp/out.png" --size -64x64
row 1 "--object" "preview --object 18446744073709551617" \
  "$inspect" preview "$tmp/good.meso" -o "$tmp/out.png" --object 18446744073709551617
row 1 "--object" "preview --object -1" "$inspect" preview "$tmp/good.meso" -o "$tmp/out.png" --object -1
row 1 "--format" "info --format yaml" "$inspect" info "$tmp/good.meso" --format yaml
row 1 "unknown command|usage" "mesoinspect: unknown command" "$inspect" inspect "$tmp/good.meso"

# --- 2: IO failures -----------------------------------------------------------
for cmd in mesh shell cells; do
  row 2 "$tmp/missing.obj" "$cmd: input not found" "$bake" $cmd -i "$tmp/missing.obj" -o "$tmp/out.meso"
done
row 2 "$tmp/missing.swc" "frusta: skeleton not found" "$bake" frusta -i "$tmp/missing.swc" -o "$tmp/out.meso"
row 2 "$tmp/missing.skel" "frusta: text skeleton not found" "$bake" frusta -i "$tmp/missing.skel" -o "$tmp/out.meso"
row 2 "$tmp/missing.obj" "frusta: mesh not found" "$bake" frusta -i "$tmp/missing.obj" -o "$tmp/out.meso"
row 2 "missing.png" "shell: texture file not found" \
  "$bake" shell -i "$mesh" -o "$tmp/out.meso" --texture "height:$tmp/missing.png"
row 2 "missing.raw" "cells: tile map file not found" \
  "$bake" cells -i "$mesh" -o "$tmp/out.meso" --tile-map "$tmp/missing.raw:4" --tile-res 4
row 2 "missing.meso" "info: file not found" "$inspect" info "$tmp/missing.meso"
row 2 "missing.meso" "validate: file not found" "$inspect" validate "$tmp/missing.meso"
row 2 "missing.meso" "preview: file not found" "$inspect" preview "$tmp/missing.meso" -o "$tmp/out.png"

# --- 3: invalid input files ---------------------------------------------------
for cmd in mesh shell cells; do
  row 3 "E3251.*unknown extension" "$cmd: unknown mesh extension" "$bake" $cmd -i "$tmp/sphere.xyz" -o "$tmp/out.meso"
  row 3 "E3251.*/dev/null" "$cmd: -i /dev/null" "$bake" $cmd -i /dev/null -o "$tmp/out.meso"
  row 3 "(E3100|E3200|E3252).*(empty file|no vertices|no triangles)" "$cmd: empty .obj" "$bake" $cmd -i "$tmp/empty.obj" -o "$tmp/out.meso"
  row 3 "(E3100|E3200|E3252).*(empty file|no vertices|no triangles)" "$cmd: .obj of words" "$bake" $cmd -i "$tmp/words.obj" -o "$tmp/out.meso"
done
row 3 "(E3100|E3200|E3252).*(empty file|no vertices|no triangles)" "frusta: empty .obj" "$bake" frusta -i "$tmp/empty.obj" -o "$tmp/out.meso"
row 3 "E3140" "frusta: -i /dev/null (an empty text skeleton)" "$bake" frusta -i /dev/null -o "$tmp/out.meso"
row 3 "E3301.*one node.*no segment" "frusta: one-node SWC" "$bake" frusta -i "$tmp/one_node.swc" -o "$tmp/out.meso"
row 3 "E3301.*no segment" "frusta: one-node text skeleton" "$bake" frusta -i "$tmp/one_node.skel" -o "$tmp/out.meso"
row 3 "E3300.*line 1.*1e\+300" "frusta: SWC coordinate 1e300" "$bake" frusta -i "$tmp/huge.swc" -o "$tmp/out.meso"
row 3 "E3300.*line 2" "frusta: text coordinate -1e300" "$bake" frusta -i "$tmp/huge.skel" -o "$tmp/out.meso"
row 3 "E3302.*every radius is 0" "frusta: SWC radii all zero" "$bake" frusta -i "$tmp/zero_radii.swc" -o "$tmp/out.meso"
row 3 "E3302.*every radius is 0" "frusta: text radii all zero" \
  "$bake" frusta -i "$tmp/zero_radii.skel" -o "$tmp/out.meso"
row 3 "E3303.*no segment has both" "frusta: only zero-length segments" \
  "$bake" frusta -i "$tmp/zero_length.skel" -o "$tmp/out.meso"
row 3 "E3141.*line 2" "frusta: SWC line of six fields" "$bake" frusta -i "$tmp/six_fields.swc" -o "$tmp/out.meso"
row 3 "E3143.*line 2" "frusta: SWC NaN" "$bake" frusta -i "$tmp/nan.swc" -o "$tmp/out.meso"
row 3 "E3146.*line 1" "frusta: text parent out of range" "$bake" frusta -i "$tmp/bad_parent.skel" -o "$tmp/out.meso"
row 3 "E3122.*bad.png" "shell: texture PNG that is not one" \
  "$bake" shell -i "$mesh" -o "$tmp/out.meso" --texture "height:$tmp/bad.png"
row 3 "E3122.*vol63.raw" "shell: raw volume of the wrong size" \
  "$bake" shell -i "$mesh" -o "$tmp/out.meso" --texture "volume:$tmp/vol63.raw:4x4x4"
row 3 "E3122.*bad.png" "frusta: relief PNG that is not one" \
  "$bake" frusta -i "$data/neurom_simple.swc" -o "$tmp/out.meso" --relief "height:$tmp/bad.png"
row 3 "tiles100.raw.*100 bytes" "cells: tile map of the wrong size" \
  "$bake" cells -i "$mesh" -o "$tmp/out.meso" --tile-map "$tmp/tiles100.raw:4" --tile-res 4
row 3 "no cells" "cells: tile map file of zeros" \
  "$bake" cells -i "$mesh" -o "$tmp/out.meso" --tile-map "$tmp/zeros4.raw:4" --tile-res 4
row 3 "colour file.*tiles100.raw" "cells: colour file of the wrong size" \
  "$bake" cells -i "$mesh" -o "$tmp/out.meso" --tile-res 4 --colour "$tmp/tiles100.raw:4"
row 3 "garbage.meso" "info: not a .meso file" "$inspect" info "$tmp/garbage.meso"
row 3 "truncated.meso" "validate: truncated .meso" "$inspect" validate "$tmp/truncated.meso"
row 3 "truncated.meso" "preview: truncated .meso" "$inspect" preview "$tmp/truncated.meso" -o "$tmp/out.png"
row 3 "garbage.meso" "diff: not a .meso file" "$inspect" diff "$tmp/garbage.meso" "$tmp/good.meso"

# --- 8: a shell left with defects -------------------------------------------------
row 8 "E3115.*inverted prisms" "shell --no-repair over spot (inverted prisms left)" \
  "$bake" shell -i "$data/spot_low_resolution.obj" -o "$tmp/out.meso" --no-repair

# --- the documented Draco range is the accepted one -----------------------------
# (spot_uv: positions, normals and uvs all quantised; --levels 1 keeps it
# short: every level is encoded alike, meso_bake.h MESO_DRACO_MAX_BITS)
for bits in 1,2,1 24,24,24 14,10,12; do
  rm -f "$tmp/d.meso"
  "$bake" mesh -i "$data/spot_uv.obj" -o "$tmp/d.meso" --draco-bits $bits --levels 1 >"$tmp/stdout" 2>"$tmp/stderr"
  rc=$?
  rows=$((rows + 1))
  if [ $rc = 0 ] && [ -s "$tmp/d.meso" ] && "$inspect" validate --full "$tmp/d.meso" >/dev/null; then
    echo "ok   [0] mesh --draco-bits $bits (inside the documented range) bakes and validates"
  else
    echo "FAIL [0] mesh --draco-bits $bits: exit $rc"; sed 's/^/       stderr: /' "$tmp/stderr" | head -3; fail=1
  fi
done

# --- each --help states the table -------------------------------------------------
for cmd in mesh shell cells frusta; do
  rows=$((rows + 1))
  if "$bake" $cmd --help | grep -q "Exit codes: 0 success, 1 command-line error, 2 I/O failure, 3 invalid input"; then
    echo "ok   mesobake $cmd --help states the exit codes"
  else
    echo "FAIL mesobake $cmd --help does not state the exit codes"; fail=1
  fi
done

echo "$rows rows"
exit $fail
