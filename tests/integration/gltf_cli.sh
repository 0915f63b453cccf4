#!/bin/sh
# glTF 2.0 input in every command that reads a mesh (issue 16): mesh, shell,
# cells and frusta bake the textured box (.gltf, .glb, embedded buffer, Draco)
# and one node of the scene (--node); every malformed file of tests/data/gltf
# is refused by each command with exit 3, its code (bake/gltf_model.h) and no
# output file. The bundled sphere as .glb bakes the OBJ's MESH positions.
# usage: gltf_cli.sh MESOBAKE TEST_DATA_DIR
set -u
bake=$1 data=$2
g=$data/gltf
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { # DESCRIPTION COMMAND...
  d=$1; shift
  if "$@"; then echo "ok   $d"; else echo "FAIL $d"; fail=1; fi
}
# args of each command that keep its bake small
opts() {
  case $1 in
    cells) echo "--tiles 2 --tile-res 8" ;;
    *) echo "" ;;
  esac
}

for cmd in mesh shell cells frusta; do
  for f in box.gltf box.glb box_embedded.gltf box_draco.glb; do
    # shellcheck disable=SC2046
    check "$cmd $f" "$bake" $cmd -i "$g/$f" -o "$tmp/$cmd.meso" $(opts $cmd)
    check "$cmd $f wrote" test -s "$tmp/$cmd.meso"
    rm -f "$tmp/$cmd.meso"
  done
  # shellcheck disable=SC2046
  check "$cmd --node B" "$bake" $cmd -i "$g/scene.gltf" --node B -o "$tmp/$cmd.meso" $(opts $cmd)
  rm -f "$tmp/$cmd.meso"
done

refuse() { # CMD FILE CODE [args]
  cmd=$1 f=$2 code=$3; shift 3
  # shellcheck disable=SC2046
  "$bake" $cmd -i "$g/$f" -o "$tmp/out.meso" $(opts $cmd) "$@" 2>"$tmp/err"
  rc=$?
  if [ $rc -eq 3 ] && grep -q "E$code" "$tmp/err" && [ ! -e "$tmp/out.meso" ]; then
    echo "ok   $cmd $f refused: E$code"
  else
    echo "FAIL $cmd $f: exit $rc (want 3, E$code), $(cat "$tmp/err")"
    fail=1
  fi
  rm -f "$tmp/out.meso"
}
for cmd in mesh shell cells frusta; do
  refuse $cmd bad_index.gltf 3505
  refuse $cmd bad_missing_buffer.gltf 3501
  refuse $cmd bad_position_type.gltf 3504
  refuse $cmd bad_index_type.gltf 3504
  refuse $cmd bad_accessor_bounds.gltf 3503
  refuse $cmd bad_view_bounds.gltf 3503
  refuse $cmd bad_zeros_count.gltf 3503
  refuse $cmd big_texture.gltf 3512 --max-memory 32M
  refuse $cmd bad_nan.gltf 3506
  refuse $cmd bad_cycle.gltf 3507
  refuse $cmd bad_two_parents.gltf 3507
  refuse $cmd bad_schema.gltf 3500
  refuse $cmd bad_not_json.gltf 3500
  refuse $cmd bad_lines.gltf 3508
  refuse $cmd bad_sparse.gltf 3509
  refuse $cmd bad_extension.gltf 3509
  refuse $cmd bad_reference.gltf 3502
  refuse $cmd bad_texture.gltf 3512
  refuse $cmd bad_empty.gltf 3513
  refuse $cmd scene.gltf 3510 --node nope
done
# the memory budget of the mesh guard holds for glTF too
refuse mesh box.gltf 3201 --max-memory 1000

# the bundled sphere: the .glb's MESH positions and triangles are the OBJ's
check "sphere obj" "$bake" mesh -i "$data/sphere.obj" -o "$tmp/obj.meso"
check "sphere glb" "$bake" mesh -i "$g/sphere.glb" -o "$tmp/glb.meso"
check "same size" test "$(wc -c <"$tmp/obj.meso")" -eq "$(wc -c <"$tmp/glb.meso")"

# big_texture.gltf itself is fine: it bakes within the default budget.
check "big_texture.gltf bakes without --max-memory" "$bake" mesh -i "$g/big_texture.gltf" -o "$tmp/big.meso"
rm -f "$tmp/big.meso"

# mesobake batch keys a .gltf by the files it names too: box.bin edited (one
# texture coordinate moved by a float's last bit) re-bakes the job;
# untouched, it stays cached.
mkdir -p "$tmp/b/out"
cp "$g/box.gltf" "$g/box.bin" "$tmp/b/" 2>/dev/null
for n in "$g"/*.png; do [ -e "$n" ] && cp "$n" "$tmp/b/"; done
printf '{"jobs": [{"name": "box", "command": "mesh", "input": "box.gltf", "output": "out/box.meso"}]}\n' \
  >"$tmp/b/m.json"
top() { sed -n "s/.*\"$2\":[[:space:]]*\([0-9]*\).*/\1/p" "$1" | head -n 1; }
"$bake" batch "$tmp/b/m.json" --cache "$tmp/cache" --report "$tmp/b1.json" >/dev/null 2>&1
"$bake" batch "$tmp/b/m.json" --cache "$tmp/cache" --report "$tmp/b2.json" >/dev/null 2>&1
check "batch: an unchanged .gltf and .bin stay cached" test "$(top "$tmp/b2.json" jobs_cached)" = 1
# Byte 576 is the low byte of the first TEXCOORD_0 float (bufferViews[2]).
printf '\001' | dd of="$tmp/b/box.bin" bs=1 seek=576 conv=notrunc 2>/dev/null
"$bake" batch "$tmp/b/m.json" --cache "$tmp/cache" --report "$tmp/b3.json" >/dev/null 2>&1
check "batch: box.bin edited re-bakes the .gltf's job" test "$(top "$tmp/b3.json" jobs_baked)" = 1
exit $fail
