#!/bin/sh
# layers.sh SOURCE_ROOT — the folders are the layers and every arrow points down:
#
#   examples/                    3  (mesoview)
#   tools/                       2  (mesobake, mesoinspect, tools/common)
#   bake/   runtime/             1  (libmeso_bake; libmeso + runtime/reference)
#   formats/                     0  (libmeso_format, frusta_pose, vec3d.h, ...)
#
# Checked two ways, both against the tree as it is (no list of files here):
#  1. every #include "x.h" in a layer's .c/.h/.cpp resolves to a header in the
#     same folder tree or a lower layer; bake/ and runtime/ never include each
#     other; a header that exists in two layers is itself a failure;
#  2. every meson dependency a layer's meson.build uses was declared in the same
#     or a lower layer (the link graph), with bake/ and runtime/ apart again.
# A failure names the file, the line and both layers.
set -u
root=$1
cd "$root" || exit 2
pass=0 fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }

layer_of() { # path -> "rank name"
    case $1 in
    formats/*) echo "0 formats" ;;
    bake/*) echo "1 bake" ;;
    runtime/*) echo "1 runtime" ;;
    tools/*) echo "2 tools" ;;
    examples/*) echo "3 examples" ;;
    *) echo "9 other" ;;
    esac
}
allowed() { # from-layer-rank from-name to-rank to-name
    [ "$3" -le "$1" ] || return 1
    [ "$1" = 1 ] && [ "$3" = 1 ] && [ "$2" != "$4" ] && return 1
    return 0
}

headers=$(find formats bake runtime tools examples -name '*.h' | sort)
[ -n "$headers" ] || { bad "no headers found under $root"; echo "0 passed, 1 failed"; exit 1; }
# Generated headers: the embedded shaders belong to runtime/.
gen="shaders_embedded.h:runtime/shaders_embedded.h"

checked=0
for f in $(find formats bake runtime tools examples \( -name '*.c' -o -name '*.h' -o -name '*.cpp' \) | sort); do
    set -- $(layer_of "$f"); frank=$1 fname=$2
    grep -n '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' "$f" | while IFS= read -r line; do
        n=${line%%:*}
        h=$(printf '%s\n' "$line" | sed 's/.*include[[:space:]]*"\([^"]*\)".*/\1/')
        base=${h##*/}
        # Resolve: next to the includer first (as the compiler does), else by name.
        dir=$(dirname "$f")
        if [ -f "$dir/$h" ]; then
            target="$dir/$h"
        else
            target=$(printf '%s\n' $headers | grep "/$base\$" || true)
            [ -n "$target" ] || target=$(printf '%s\n' "$gen" | sed -n "s|^$base:||p")
        fi
        if [ -z "$target" ]; then
            echo "FAIL: $f:$n includes \"$h\", which is no header of the tree"
            continue
        fi
        if [ "$(printf '%s\n' "$target" | wc -l)" -gt 1 ]; then
            echo "FAIL: $f:$n includes \"$h\", which exists twice: $(echo $target)"
            continue
        fi
        set -- $(layer_of "$target")
        allowed "$frank" "$fname" "$1" "$2" ||
            echo "FAIL: $f:$n ($fname) includes $target ($2): an arrow upwards or across"
    done >>"${TMPDIR:-/tmp}/layers.$$"
    checked=$((checked + 1))
done
if [ -s "${TMPDIR:-/tmp}/layers.$$" ]; then
    while IFS= read -r l; do bad "${l#FAIL: }"; done <"${TMPDIR:-/tmp}/layers.$$"
else
    ok
fi
rm -f "${TMPDIR:-/tmp}/layers.$$"
[ "$checked" -gt 50 ] && ok || bad "only $checked source files found: is $root the source tree?"

# 2. meson dependencies: where each *_dep is declared, and where it is used.
decl=$(grep -n '^[[:space:]]*[a-z_0-9]*_dep[[:space:]]*=' $(find formats bake runtime tools examples -name meson.build) |
    sed 's/^\([^:]*\):[0-9]*:[[:space:]]*\([a-z_0-9]*_dep\).*/\2 \1/' | sort -u)
[ -n "$decl" ] || bad "no meson dependencies declared"
for mb in $(find formats bake runtime tools examples -name meson.build | sort); do
    set -- $(layer_of "$mb"); frank=$1 fname=$2
    for dep in $(grep -o '[a-z_0-9]*_dep\b' "$mb" | sort -u); do
        # Declared in this file (a local dependency() lookup) or else where first declared.
        where=$(printf '%s\n' "$decl" | awk -v d="$dep" -v f="$mb" '$1 == d && $2 == f {print $2}')
        [ -n "$where" ] || where=$(printf '%s\n' "$decl" | awk -v d="$dep" '$1 == d {print $2}' | head -1)
        [ -n "$where" ] || continue # a system dependency (m, threads, libpng, ...)
        set -- $(layer_of "$where")
        if allowed "$frank" "$fname" "$1" "$2"; then ok; else
            bad "$mb ($fname) uses $dep, declared in $where ($2): a link upwards or across"
        fi
    done
done
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
