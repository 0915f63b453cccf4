#!/bin/sh
# The cache of `mesobake batch` serves a bake only while the baker makes the
# same bytes: its key includes MESO_BATCH_CACHE_VERSION (tools/mesobake/batch.h),
# which must be bumped whenever a change makes any bake's bytes differ. This
# test holds the SHA-256 of one bake of every kind under the recorded cache
# version (tests/data/batch_cache_version.txt) and fails when the bytes
# changed but the version did not — or the version changed but the digests
# were not re-recorded. After a deliberate change: bump the version, run
#   tests/integration/batch_cache_version.sh MESOBAKE tests/data --record
# and commit the file.
# usage: batch_cache_version.sh MESOBAKE TEST_DATA_DIR [--record]
set -u
record=${3:-}
bake=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
data=$(cd "$2" && pwd) || exit 1
known=$data/batch_cache_version.txt
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1
for f in torus.obj sphere.obj spot_uv.obj saguaro.skel neurom_simple.swc; do cp "$data/$f" . || exit 1; done

version=$("$bake" --version | sed -n 's/.*batch cache \([0-9]*\)).*/\1/p')
arch=$(uname -m)
[ -n "$version" ] || { echo "FAIL: mesobake --version names no batch cache version"; exit 1; }

# One bake of every kind and of the options that take other code paths.
bakes() {
  "$bake" mesh -i torus.obj -o mesh.meso &&
  "$bake" mesh -i torus.obj -o draco.meso --draco &&
  "$bake" shell -i sphere.obj -o shell.meso &&
  "$bake" shell -i spot_uv.obj -o shell_bricks.meso --texture bricks:64 --tiling 4 &&
  "$bake" shell -i sphere.obj -o shell_weave.meso --texture weave:32 --kind interior --directors lp &&
  "$bake" cells -i sphere.obj -o cells.meso --tiles 4 --tile-res 16 &&
  "$bake" frusta -i saguaro.skel -o frusta_relief.meso --relief bricks:64 &&
  "$bake" frusta -i neurom_simple.swc -o frusta_swc.meso &&
  "$bake" frusta -i torus.obj -o frusta_mesh.meso
}
bakes 2>"$tmp/err" || { echo "FAIL: a bake failed:"; cat "$tmp/err"; exit 1; }
{
  echo "cache-version $version"
  echo "arch $arch"
  sha256sum -- *.meso
} >"$tmp/now.txt"

if [ "$record" = --record ]; then
  cp "$tmp/now.txt" "$known" && echo "recorded $known" && exit 0
  exit 1
fi
[ -f "$known" ] || { echo "FAIL: $known is missing"; exit 1; }
if cmp -s "$known" "$tmp/now.txt"; then
  echo "ok: $(grep -c meso "$known") bakes have the digests recorded for batch cache version $version ($arch)"
  exit 0
fi
old_version=$(sed -n 's/^cache-version //p' "$known")
old_arch=$(sed -n 's/^arch //p' "$known")
echo "FAIL: bakes differ from $known:"
diff "$known" "$tmp/now.txt" | sed 's/^/  /'
if [ "$old_arch" != "$arch" ]; then
  echo "the digests were recorded on $old_arch, this is $arch: floating point differs across architectures"
  echo "(the cache key includes the architecture); record this one's beside it if it must run here"
elif [ "$old_version" = "$version" ]; then
  echo "the bytes changed but MESO_BATCH_CACHE_VERSION did not: bump it (tools/mesobake/batch.h) so no"
  echo "cache serves the old bytes, then re-record with: $0 MESOBAKE TEST_DATA_DIR --record"
else
  echo "MESO_BATCH_CACHE_VERSION is now $version: re-record the digests with: $0 MESOBAKE TEST_DATA_DIR --record"
fi
exit 1
