#!/bin/sh
# check_exports.sh — a shared library exports exactly the functions its
# installed headers declare with the export macro: every defined dynamic
# symbol (`nm -D --defined-only`) is declared, and every declared function is
# exported. Both lists are printed on a mismatch.
# usage: check_exports.sh LIBRARY MACRO[,MACRO...] HEADER...
#   e.g. check_exports.sh build/runtime/libmeso.so MESO_API runtime/meso_rt.h formats/meso_file.h
#   A library that also re-exports another's API names both macros, e.g.
#   MESO_BAKE_API,MESO_API with bake/meso_bake.h formats/meso_file.h.
# NM names the nm to use (default nm). A declaration is a line that starts
# with one of the macros; the function's name is the identifier before its
# first '(' (the headers keep one declaration per line, STYLE.md §3). Symbols the
# toolchain adds (_init, _fini, _edata, _end, __bss_start, and any other name
# starting with '_', which C reserves) are not the library's API.
set -eu
export LC_ALL=C
[ $# -ge 3 ] || { echo "usage: $0 LIBRARY MACRO[,MACRO...] HEADER..." >&2; exit 2; }
lib=$1 macro=$2
shift 2
nm=${NM:-nm}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT

"$nm" -D --defined-only "$lib" >"$T/nm" || { echo "$nm -D failed on $lib" >&2; exit 2; }
awk 'NF >= 3 && $3 !~ /^_/ { sub(/@.*/, "", $3); print $3 }' "$T/nm" | sort -u >"$T/exported"

cat "$@" >"$T/headers"
: >"$T/declared.all"
for m in $(echo "$macro" | tr ',' ' '); do
    sed -n "s/^[[:space:]]*$m[[:space:]]\{1,\}\([^(]*[^A-Za-z0-9_(]\)\{0,1\}\([A-Za-z_][A-Za-z0-9_]*\)[[:space:]]*(.*/\2/p" \
        "$T/headers" >>"$T/declared.all"
done
sort -u "$T/declared.all" >"$T/declared"

[ -s "$T/declared" ] || { echo "no function declared with $macro in: $*" >&2; exit 1; }
[ -s "$T/exported" ] || { echo "$lib exports nothing" >&2; exit 1; }

comm -23 "$T/exported" "$T/declared" >"$T/extra"
comm -13 "$T/exported" "$T/declared" >"$T/missing"
status=0
if [ -s "$T/extra" ]; then
    echo "FAIL: $lib exports symbols no header declares with $macro:" >&2
    sed 's/^/  /' "$T/extra" >&2
    status=1
fi
if [ -s "$T/missing" ]; then
    echo "FAIL: functions declared with $macro that $lib does not export:" >&2
    sed 's/^/  /' "$T/missing" >&2
    status=1
fi
[ $status -ne 0 ] || echo "$lib exports exactly the $(wc -l <"$T/declared") functions declared with $macro"
exit $status
