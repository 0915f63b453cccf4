#!/bin/sh
# Limits up front (issue 21, deliverable 4): requests over the memory budget
# (--max-memory, bake/memory_budget.h) are refused before anything large is
# allocated: cells grids, texture and volume sizes, --dist-res, PNG headers,
# raw volumes that cannot hold their declared size, skeleton files. Each
# refusal: the exit code (1 for a request from the options, 3 for a size an
# input file dictates), the error code and the estimate in the message, no
# output file. Every run is under `timeout 20`: a regression that starts
# allocating fails here instead of hanging (a guard, not a timed assertion).
# usage: limits_cli.sh MESOBAKE TEST_DATA_DIR FUZZ_CORPUS_DIR
set -u
bake=$1 data=$2 corpus=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
spot="$data/spot_low_resolution.obj"
spot_uv="$data/spot_uv.obj"

# refuse NAME EXIT PATTERN ARGS...: mesobake ARGS (which write $tmp/out.meso)
# exits EXIT, says PATTERN on stderr, and leaves no output file.
refuse() {
  name=$1 want=$2 pattern=$3
  shift 3
  rm -f "$tmp/out.meso"
  timeout 20 "$bake" "$@" >"$tmp/stdout" 2>"$tmp/stderr"
  got=$?
  if [ "$got" -ne "$want" ]; then
    echo "FAIL $name: exit $got, expected $want"; sed 's/^/     /' "$tmp/stderr"; fail=1
  elif ! grep -Eq -- "$pattern" "$tmp/stderr"; then
    echo "FAIL $name: stderr does not match '$pattern':"; sed 's/^/     /' "$tmp/stderr"; fail=1
  elif [ -e "$tmp/out.meso" ]; then
    echo "FAIL $name: wrote an output file"; fail=1
  else
    echo "ok   $name (exit $got)"
  fi
}
# accept NAME ARGS...: mesobake ARGS exits 0 and writes $tmp/out.meso.
accept() {
  name=$1
  shift
  rm -f "$tmp/out.meso"
  timeout 120 "$bake" "$@" >"$tmp/stdout" 2>"$tmp/stderr"
  got=$?
  if [ "$got" -eq 0 ] && [ -s "$tmp/out.meso" ]; then
    echo "ok   $name"
  else
    echo "FAIL $name: exit $got"; sed 's/^/     /' "$tmp/stderr"; fail=1
  fi
}
est='needs about [0-9.]+ [KMGTP]iB, more than the memory budget'

# 1. cells: the grid products of the issue (estimates: 26 GiB, 8.1 GiB, 18 TiB).
refuse "cells --tile-res 1024" 1 "E3400: .*1024\^3 voxels per tile.*$est" \
  cells -i "$spot" -o "$tmp/out.meso" --tile-res 1024 --max-memory 8G
refuse "cells --tiles 1024 --tile-res 16" 1 "E3400: .*16\^3 voxels per tile, 1024x1024x1024 tiles.*$est" \
  cells -i "$spot" -o "$tmp/out.meso" --tiles 1024 --tile-res 16 --max-memory 4G
refuse "cells --tiles 16384 --tile-res 1 (default budget)" 1 "E3400: .*16384x16384x16384 tiles.*TiB, more than" \
  cells -i "$spot" -o "$tmp/out.meso" --tiles 16384 --tile-res 1
refuse "cells: raw tile map shorter than R^3" 3 "E3152: .*65 bytes" \
  cells -i "$spot" -o "$tmp/out.meso" --tile-map "$corpus/png/huge_header_65535.png:64"

# 2. A small budget refuses a bake that the default lets through.
refuse "cells --tile-res 16 under --max-memory 50M" 1 "E3400: .*$est 50 MiB" \
  cells -i "$spot" -o "$tmp/out.meso" --tile-res 16 --max-memory 50M
accept "cells --tile-res 16 under the default budget" cells -i "$spot" -o "$tmp/out.meso" --tile-res 16
accept "cells --tile-res 16 under --max-memory 1.5GiB" cells -i "$spot" -o "$tmp/out.meso" --tile-res 16 \
  --max-memory 1.5GiB

# 3. --max-memory values: plain bytes and suffixes parse; junk, zero,
# negative, fractions of a byte and overflow are usage errors.
for bad in abc 0 -5 1.5 12Q 99999999999999999999 8G8 ""; do
  refuse "--max-memory '$bad' is a usage error" 1 "max-memory expects a size" \
    cells -i "$spot" -o "$tmp/out.meso" --max-memory "$bad"
done
for cmd in mesh shell frusta; do
  in=$spot_uv
  [ "$cmd" = frusta ] && in="$data/neurom_simple.swc"
  refuse "$cmd --max-memory junk" 1 "max-memory expects a size" $cmd -i "$in" -o "$tmp/out.meso" --max-memory 1x
  "$bake" $cmd --help | grep -q -- "--max-memory SIZE" && echo "ok   $cmd --help lists --max-memory" ||
    { echo "FAIL $cmd --help lists --max-memory"; fail=1; }
done
accept "mesh --max-memory 2147483648" mesh -i "$spot_uv" -o "$tmp/out.meso" --max-memory 2147483648

# 4. Textures and volumes.
refuse "PNG header claiming 65535^2 (65 bytes)" 3 "E3401: .*65535x65535 pixels.*$est" \
  shell -i "$spot_uv" -o "$tmp/out.meso" --texture "height:$corpus/png/huge_header_65535.png"
refuse "PNG with truncated IDAT data" 3 "E3122: .*truncated_idat.png" \
  shell -i "$spot_uv" -o "$tmp/out.meso" --texture "height:$corpus/png/truncated_idat.png"
refuse "PNG cut short" 3 "E3122: .*truncated_file.png" \
  shell -i "$spot_uv" -o "$tmp/out.meso" --texture "height:$corpus/png/truncated_file.png"
head -c 64 /dev/zero >"$tmp/v64.raw"
refuse "volume 4096^3 over a 64-byte file" 3 "E3122: .*has 64 bytes, expected exactly 68719476736" \
  shell -i "$spot_uv" -o "$tmp/out.meso" --texture "volume:$tmp/v64.raw:4096x4096x4096"
refuse "volume 4x4x5 over a 64-byte file" 3 "E3122: .*expected exactly 80" \
  shell -i "$spot_uv" -o "$tmp/out.meso" --texture "volume:$tmp/v64.raw:4x4x5"
if truncate -s 1G "$tmp/v1g.raw" 2>/dev/null; then # sparse: no disk used
  refuse "volume 1024^3 (a 1 GiB file) over --max-memory 4G" 1 "E3400: .*1024x1024x1024.*$est" \
    shell -i "$spot_uv" -o "$tmp/out.meso" --texture "volume:$tmp/v1g.raw:1024x1024x1024" --max-memory 4G
else
  echo "FAIL cannot create a sparse 1 GiB file in $tmp"; fail=1
fi
refuse "built-in volume cells:256 over --max-memory 100M" 1 "E3400: .*cells:256.*$est" \
  shell -i "$spot_uv" -o "$tmp/out.meso" --texture cells:256 --max-memory 100M
refuse "--dist-res 512^3 over --max-memory 1G" 1 "E3400: .*distance map 512x512x512.*$est" \
  shell -i "$spot_uv" -o "$tmp/out.meso" --texture bricks:64 --dist-res 512x512x512 --max-memory 1G

# 5. Skeletons and reliefs (frusta).
awk 'BEGIN { print "1 1 0 0 0 1 -1"; for (i = 2; i <= 40000; ++i) printf "%d 3 %d 0 0 0.5 %d\n", i, i, i - 1 }' \
  >"$tmp/chain.swc"
refuse "SWC of 40000 lines over --max-memory 100M" 3 "E3402: .*40000 nodes.*$est" \
  frusta -i "$tmp/chain.swc" -o "$tmp/out.meso" --max-memory 100M
refuse "relief PNG header claiming 65535^2" 3 "E3401: .*65535x65535" \
  frusta -i "$data/neurom_simple.swc" -o "$tmp/out.meso" --relief "height:$corpus/png/huge_header_65535.png"

# 6. Meshes: --max-memory is the mesh guard's bound too (bake/mesh_guard.h).
# spot_low_resolution.obj is 128 KB: a 100 KB budget refuses it in every
# command that reads a mesh, the default lets it through.
for cmd in mesh shell cells; do
  refuse "$cmd: mesh over --max-memory 100K" 3 "E3201: .*allowed \\(raise it with --max-memory" \
    $cmd -i "$spot" -o "$tmp/out.meso" --max-memory 100K
done
refuse "frusta -i MESH over --max-memory 100K" 3 "E3201: .*--max-memory" \
  frusta -i "$spot" -o "$tmp/out.meso" --max-memory 100K
accept "mesh under the default budget" mesh -i "$spot" -o "$tmp/out.meso"

exit $fail
