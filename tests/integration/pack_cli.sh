#!/bin/sh
# mesobake pack (issue 16, "several objects per file"): every kind baked
# from bundled data (a raw and a Draco mesh, a textured shell, frusta,
# cells), packed into one file. Checked against the inputs themselves:
# objects numbered in input order with their kinds and (made unique) names;
# every chunk's stored bytes (type, flags, lod, encoding, element type,
# dims, sizes and CRC32C, from 'mesoinspect info') equal to its source
# chunk's; the file valid in full; each object drawn by libmeso from the
# packed file the same as from its own file (mesoinspect preview --object,
# pixel for pixel, by id and by name); determinism; a packed file packs again. Bad input: a
# damaged input (one payload byte flipped), a missing one, a non-.meso
# file, no input, the output named as an input: each refused with its exit
# code and a message naming the file, nothing written.
# usage: pack_cli.sh MESOBAKE MESOINSPECT TEST_DATA_DIR PNG_PROBE
set -u
bake=$1 inspect=$2 data=$3 probe=$4
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { # DESCRIPTION COMMAND...
  d=$1; shift
  if "$@"; then echo "ok   $d"; else echo "FAIL $d"; fail=1; fi
}
# Previews run headless GL; LeakSanitizer reports bytes inside the Mesa
# driver, so only the preview calls run without leak detection (as the GL
# tests do, tests/meson.build gl_env); the baker keeps it. Mesa's shader
# cache: the build's when meson gives one (gl_cache), else none.
export MESA_SHADER_CACHE_DISABLE="${MESA_SHADER_CACHE_DISABLE:-true}" EGL_PLATFORM=surfaceless
preview() { ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" "$inspect" preview "$@"; }
# chunks FILE OBJECT: that object's chunk rows without index, object and offset
chunks() { "$inspect" info "$1" | awk -v o="$2" 'NF == 14 && $4 == o && $1 ~ /^[0-9]+$/ {
  print $2, $3, $5, $6, $7, $8, $9, $11, $12, $13 }'; }

"$bake" mesh -i "$data/spot_low_resolution.obj" -o "$tmp/mesh.meso" >/dev/null 2>&1 &&
  "$bake" mesh -i "$data/spot_low_resolution.obj" -o "$tmp/draco.meso" --draco --name spot_draco >/dev/null 2>&1 &&
  "$bake" shell -i "$data/sphere.obj" -o "$tmp/shell.meso" --thickness-rel 0.05 --texture bricks:64 -j 2 \
    >/dev/null 2>&1 &&
  "$bake" frusta -i "$data/saguaro.skel" -o "$tmp/frusta.meso" --relief bricks:64 >/dev/null 2>&1 &&
  "$bake" cells -i "$data/spot_low_resolution.obj" -o "$tmp/cells.meso" -j 2 >/dev/null 2>&1
check "bakes succeed" test $? = 0

# 1. Pack: mesh, draco, shell, frusta, cells, and the mesh again (a name clash).
set -- mesh draco shell frusta cells mesh
ins=""
for f in "$@"; do ins="$ins $tmp/$f.meso"; done
# shellcheck disable=SC2086
"$bake" pack $ins -o "$tmp/scene.meso" --report "$tmp/scene.json" 2>"$tmp/warn"
check "pack exits 0" test $? = 0
check "packed file validates in full" sh -c "'$inspect' validate --full '$tmp/scene.meso' >/dev/null"
check "6 objects listed" sh -c "'$inspect' info '$tmp/scene.meso' | grep -q '^Objects (6):'"
kinds=$("$inspect" info "$tmp/scene.meso" | awk '/^Objects/ {on = 1; next} on && /^ +[0-9]+ / {print $2} /^$/ {on = 0}' |
  tr '\n' ' ')
check "kinds in input order (got: $kinds)" test "$kinds" = "mesh mesh shell frusta cells mesh "
# The cells object and the second mesh are named after the same input as the first mesh.
check "the clashing names became spot_low_resolution.obj~2 and ~3" \
  sh -c "'$inspect' info '$tmp/scene.meso' | grep -q '^ *5  cells  *spot_low_resolution.obj~2 ' &&
         '$inspect' info '$tmp/scene.meso' | grep -q '^ *6  mesh  *spot_low_resolution.obj~3 '"
check "the rename is warned (E3482 in the report)" grep -q "E3482" "$tmp/scene.json"
check "the renames are warned on stderr" grep -q "renamed 'spot_low_resolution.obj~3'" "$tmp/warn"
id=0
for f in "$@"; do
  id=$((id + 1))
  chunks "$tmp/$f.meso" 1 >"$tmp/src.txt"
  chunks "$tmp/scene.meso" $id >"$tmp/dst.txt"
  check "object $id ($f): $(wc -l <"$tmp/src.txt") chunks stored byte for byte" \
    sh -c "test -s '$tmp/src.txt' && cmp -s '$tmp/src.txt' '$tmp/dst.txt'"
done
check "the Draco mesh stays Draco" sh -c "'$inspect' info '$tmp/scene.meso' | awk '\$2 == \"MESH\" && \$4 == 2' | grep -q draco"

# 2. libmeso draws each object of the packed file as from its own file.
id=0
for f in "$@"; do
  id=$((id + 1))
  preview "$tmp/$f.meso" -o "$tmp/own.png" --size 96x72 >/dev/null 2>&1
  a=$?
  preview "$tmp/scene.meso" --object $id -o "$tmp/packed.png" --size 96x72 >/dev/null 2>&1
  b=$?
  out=$("$probe" --diff "$tmp/own.png" "$tmp/packed.png")
  check "object $id ($f): drawn from the packed file as from its own (differing pixels, max: $out)" \
    test $a = 0 -a $b = 0 -a "${out% *}" = 0
done

# Addressable by name too: the frusta object by its name is the frusta object by its id.
preview "$tmp/scene.meso" --object 4 -o "$tmp/by_id.png" --size 96x72 >/dev/null 2>&1 &&
  preview "$tmp/scene.meso" --object saguaro.skel -o "$tmp/by_name.png" --size 96x72 >/dev/null 2>&1
check "preview --object NAME draws the object of that name" cmp -s "$tmp/by_id.png" "$tmp/by_name.png"
preview "$tmp/scene.meso" --object no_such_name -o "$tmp/none.png" >/dev/null 2>"$tmp/err"
check "preview --object with an unknown name: usage error (exit 1)" test $? = 1
check "... listing the file's objects" grep -q "4 'saguaro.skel'" "$tmp/err"
check "... and writing nothing" test ! -e "$tmp/none.png"

# A name that starts with a digit is a name ("3d" is not an id).
"$bake" mesh -i "$data/spot_low_resolution.obj" -o "$tmp/3d.meso" --name 3d >/dev/null 2>&1
preview "$tmp/3d.meso" --object 3d -o "$tmp/3d.png" --size 32x24 >/dev/null 2>&1
check "preview --object 3d: the object named 3d" test $? = 0 -a -s "$tmp/3d.png"

# 3. Deterministic; a packed file packs again (objects 7 and 8 after 1..6).
# shellcheck disable=SC2086
"$bake" pack $ins -o "$tmp/again.meso" 2>/dev/null
check "packing again gives the same bytes" cmp -s "$tmp/scene.meso" "$tmp/again.meso"
"$bake" pack "$tmp/scene.meso" "$tmp/frusta.meso" -o "$tmp/nested.meso" 2>/dev/null
check "a packed file packs again (7 objects)" sh -c "'$inspect' info '$tmp/nested.meso' | grep -q '^Objects (7):'"
chunks "$tmp/scene.meso" 4 >"$tmp/a.txt"
chunks "$tmp/nested.meso" 7 >"$tmp/b.txt"
check "nested: the frusta object's chunks unchanged" cmp -s "$tmp/a.txt" "$tmp/b.txt"

# 4. Bad input: refused, named, nothing written.
refuse() { # DESCRIPTION EXIT PATTERN ARGS...
  what=$1 want=$2 pat=$3; shift 3
  rm -f "$tmp/bad.meso"
  "$bake" pack "$@" -o "$tmp/bad.meso" >/dev/null 2>"$tmp/err"
  got=$?
  check "$what: exit $want (got $got)" test $got = "$want"
  check "$what: message says '$pat'" grep -q -- "$pat" "$tmp/err"
  check "$what: nothing written" test ! -e "$tmp/bad.meso"
}
# Flip one byte inside the frusta file's last chunk payload (RELF).
size=$(wc -c <"$tmp/frusta.meso")
cp "$tmp/frusta.meso" "$tmp/damaged.meso"
printf '\377' | dd of="$tmp/damaged.meso" bs=1 seek=$((size - 100)) conv=notrunc 2>/dev/null
refuse "a damaged input" 3 "damaged.meso:" "$tmp/mesh.meso" "$tmp/damaged.meso"
refuse "a missing input" 2 "nothere.meso" "$tmp/mesh.meso" "$tmp/nothere.meso"
refuse "a mesh file, not a .meso" 3 "sphere.obj" "$data/sphere.obj"
"$bake" pack "$tmp/mesh.meso" -o "$tmp/bad.meso" -h >/dev/null 2>&1
check "-h with inputs and -o: help only (exit 0), nothing written" test $? = 0 -a ! -e "$tmp/bad.meso"
"$bake" pack -o "$tmp/bad.meso" >/dev/null 2>"$tmp/err"
check "no input: usage error (exit 1)" test $? = 1
check "no input: nothing written" test ! -e "$tmp/bad.meso"
cp "$tmp/mesh.meso" "$tmp/self.meso"
"$bake" pack "$tmp/self.meso" "$tmp/frusta.meso" -o "$tmp/self.meso" >/dev/null 2>"$tmp/err"
check "output named as an input: usage error (exit 1)" test $? = 1
check "output named as an input: the input untouched" cmp -s "$tmp/mesh.meso" "$tmp/self.meso"
exit $fail
