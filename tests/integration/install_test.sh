#!/bin/sh
# `meson install` installs libmeso (static and shared), its headers and a
# meso.pc that a C program builds and links against; the program runs. The
# same for libmeso_bake (meso_bake.h, meso-bake.pc).
# usage: install_test.sh BUILD_DIR CC [SANITIZERS]
set -eu
build=$1 cc=$2 san=${3:-none}
# A sanitized libmeso needs the sanitizer runtime in the consumer too.
sanflags=""
[ "$san" = none ] || sanflags="-fsanitize=$san"
dest=$(mktemp -d)
trap 'rm -rf "$dest"' EXIT
meson install -C "$build" --destdir "$dest" --no-rebuild >"$dest.log" 2>&1 || { cat "$dest.log"; rm -f "$dest.log"; exit 1; }
rm -f "$dest.log"
pc=$(find "$dest" -name meso.pc | head -n 1)
[ -n "$pc" ] || { echo "no meso.pc installed"; exit 1; }
ls "$(dirname "$pc")"/../libmeso.a >/dev/null
ls "$(dirname "$pc")"/../libmeso.so* >/dev/null
cat > "$dest/use_meso.c" <<'C'
#include <meso_rt.h>
#include <stdio.h>
#include <string.h>
int main(void) {
    meso_rt* rt = NULL;
    /* No GL here: a NULL loader must be refused, and the format library answers. */
    if (meso_rt_create(&(meso_rt_desc){0}, &rt) != MESO_ERR_INVALID_ARG) return 1;
    if (strcmp(meso_result_string(MESO_ERR_TRUNCATED), "") == 0) return 2;
    if (meso_crc32c(0, "123456789", 9) != 0xE3069283u) return 3;
    printf("ok %d.%d\n", MESO_FORMAT_MAJOR, MESO_FORMAT_MINOR);
    return 0;
}
C
# The sysroot prefixes every path pkg-config prints, --variable included.
export PKG_CONFIG_PATH="$(dirname "$pc")" PKG_CONFIG_SYSROOT_DIR="$dest"
flags=$(pkg-config --cflags --libs meso)
$cc -std=c99 -Wall -Werror $sanflags "$dest/use_meso.c" $flags -o "$dest/use_meso"
LD_LIBRARY_PATH="$(pkg-config --variable=libdir meso)" "$dest/use_meso" | grep -qx "ok 1.1"
echo "installed meso.pc builds and runs a C program"

# libmeso_bake: meso-bake.pc, the header beside meso_file.h, a program that
# bakes nothing (no input: refused with a message) but links and runs.
pcb=$(find "$dest" -name meso-bake.pc | head -n 1)
[ -n "$pcb" ] || { echo "no meso-bake.pc installed"; exit 1; }
ls "$(dirname "$pcb")"/../libmeso_bake.so* >/dev/null
cat > "$dest/use_bake.c" <<'C'
#include <meso_bake.h>
#include <stdio.h>
int main(void) {
    meso_bake_mesh_options o = meso_bake_mesh_defaults();
    meso_bake_output* out = NULL;
    meso_error err = {0};
    if (meso_bake_mesh(&o, &out, NULL, &err) != MESO_ERR_INVALID_ARG || out || !err.message[0]) return 1;
    printf("ok %s\n", meso_bake_directors_name(MESO_DIRECTORS_LP));
    return 0;
}
C
flags=$(pkg-config --cflags --libs meso-bake)
$cc -std=c99 -Wall -Werror $sanflags "$dest/use_bake.c" $flags -o "$dest/use_bake"
LD_LIBRARY_PATH="$(pkg-config --variable=libdir meso-bake)" "$dest/use_bake" | grep -qx "ok lp"
# Statically: libmeso_bake.a carries the format library and the adapters;
# `pkg-config --static` must name everything else, the C++ runtime included.
libdir=$(pkg-config --variable=libdir meso-bake)
static_flags=$(pkg-config --static --cflags --libs meso-bake | sed "s|-lmeso_bake|$libdir/libmeso_bake.a|")
$cc -std=c99 -Wall -Werror $sanflags "$dest/use_bake.c" $static_flags -o "$dest/use_bake_static"
"$dest/use_bake_static" | grep -qx "ok lp"
echo "installed meso-bake.pc builds and runs a C program, shared and static"
