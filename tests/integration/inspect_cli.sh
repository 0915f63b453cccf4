#!/bin/sh
# inspect_cli.sh MESOINSPECT MESOBAKE DATA_DIR MESO_FILE_H
#
# mesoinspect's command line against files baked by mesobake: info (counts
# checked against the OBJ source), validate (cheap and full, on good, flipped
# and truncated files), dump (decoded vs stored bytes), diff (exit 0/7) and
# the CLI conventions of STYLE.md §8 (usage, --help, --version, exit codes).
# Expectations come from the inputs (OBJ line counts, meso_file.h issue
# constants, file sizes), not from mesoinspect's own output.
set -u

MI=$1
MB=$2
DATA=$3
HDR=$4

. "$(dirname "$0")/check_lib.sh" # $T, run, expect_*, fail, ok
# issue code constant from meso_file.h
issue_code() {
    sed -n "s/^#define MESO_ISSUE_$1 \([0-9]*\)u.*/\1/p" "$HDR"
}
# column NAME of the chunk table row for TYPE in `mesoinspect info FILE` text
chunk_col() {
    "$MI" info "$1" 2>/dev/null | awk -v type="$2" -v want="$3" '
        $1 == "#" && $2 == "type" { for (i = 1; i <= NF; i++) col[$i] = i; intab = 1; next }
        intab && NF >= 14 && $2 == type { print $(col[want]); exit }'
}
# all values of a numeric JSON key in a document (whitespace-insensitive)
json_nums() {
    tr -d ' \t\r\n' <"$1" | grep -o "\"$2\":[0-9-]*" | cut -d: -f2
}
size_of() { wc -c <"$1" | tr -d ' '; }

CODE_PAYLOAD_CRC=$(issue_code PAYLOAD_CRC)
CODE_FILE_TRUNCATED=$(issue_code FILE_TRUNCATED)
CODE_HDR_TRUNCATED=$(issue_code HDR_TRUNCATED)
CODE_HDR_MAGIC=$(issue_code HDR_MAGIC)
[ -n "$CODE_PAYLOAD_CRC" ] && [ -n "$CODE_FILE_TRUNCATED" ] && [ -n "$CODE_HDR_MAGIC" ] ||
    { echo "cannot read issue codes from $HDR" >&2; exit 1; }

# ---------------------------------------------------------------- bake inputs
# One level each (--levels 1): the checks below address "the" MESH chunk;
# levels of detail have their own test (mesh_levels_cli.sh).
run "$MB" mesh -i "$DATA/sphere.obj" -o "$T/a.meso" --levels 1
if [ "$rc" -eq 5 ]; then
    echo "SKIP: mesobake has no mesh import in this build" >&2
    exit 77
fi
expect_rc 0 "bake sphere"
run "$MB" mesh -i "$DATA/sphere.obj" -o "$T/a2.meso" --levels 1
expect_rc 0 "bake sphere again"
run "$MB" mesh -i "$DATA/torus.obj" -o "$T/torus.meso" --levels 1
expect_rc 0 "bake torus"
have_draco=1
run "$MB" mesh -i "$DATA/sphere.obj" -o "$T/d.meso" --draco --levels 1
if [ "$rc" -eq 5 ]; then have_draco=0; else expect_rc 0 "bake sphere --draco"; fi

# ------------------------------------------------------------------- info
# Counts the test knows from the OBJ file: every `v` line is a vertex and
# every `f` line a triangle (the file has only 3-vertex faces).
NV=$(grep -c '^v ' "$DATA/sphere.obj")
NF=$(grep -c '^f ' "$DATA/sphere.obj")
NONTRI=$(awk '$1 == "f" && NF != 4' "$DATA/sphere.obj" | wc -l | tr -d ' ')
expect_eq "$NONTRI" 0 "sphere.obj has only triangles"
expect_eq "$NV" 642 "sphere.obj vertex lines"

run "$MI" info "$T/a.meso" --format json
expect_rc 0 "info --format json"
cp "$T/out" "$T/info_a.json"
expect_eq "$(json_nums "$T/info_a.json" vertex_count | sort -u)" "$NV" "info json vertex_count"
expect_eq "$(json_nums "$T/info_a.json" index_count | sort -u)" "$((3 * NF))" "info json index_count"
expect_eq "$(json_nums "$T/info_a.json" file_size)" "$(size_of "$T/a.meso")" "info json file_size = file size"
expect_out '"crc_ok":[[:space:]]*true' "info json crc status"
if grep -Eq '"crc_ok":[[:space:]]*false' "$T/out"; then fail "info json: a CRC is bad on a fresh bake"; else ok; fi
expect_out '"name":[[:space:]]*"sphere.obj"' "info json object name"
expect_out '"generator":[[:space:]]*"mesobake' "info json META embedded"
expect_out '"triangles":[[:space:]]*'"$NF" "info json RPRT embedded"

run "$MI" info "$T/a.meso" --format mini-json
expect_rc 0 "info --format mini-json"
expect_eq "$(wc -l <"$T/out" | tr -d ' ')" 1 "mini-json is one line"

run "$MI" info "$T/a.meso"
expect_rc 0 "info text"
expect_out '^ *[0-9]+ +MESH +REQUIRED' "info text MESH row with REQUIRED flag"
expect_out "$NV vertices, $((3 * NF)) indices" "info text MESH counts"

MESH_OFF=$(chunk_col "$T/a.meso" MESH offset)
MESH_STORED=$(chunk_col "$T/a.meso" MESH stored)
MESH_DECODED=$(chunk_col "$T/a.meso" MESH decoded)
MESH_INDEX=$(chunk_col "$T/a.meso" MESH '#')
[ -n "$MESH_OFF" ] && [ -n "$MESH_STORED" ] && [ -n "$MESH_DECODED" ] || { fail "no MESH row in info"; exit 1; }
expect_eq "$MESH_STORED" "$MESH_DECODED" "raw MESH stored = decoded size"
# the MESH payload lies inside the file, 64-aligned
[ $((MESH_OFF % 64)) -eq 0 ] && [ $((MESH_OFF + MESH_STORED)) -le "$(size_of "$T/a.meso")" ] && ok ||
    fail "MESH offset $MESH_OFF / size $MESH_STORED not inside the file"

if [ "$have_draco" -eq 1 ]; then
    run "$MI" info "$T/d.meso" --format json
    expect_rc 0 "info draco"
    expect_eq "$(json_nums "$T/out" vertex_count | sort -u)" "$NV" "draco info vertex_count"
    expect_eq "$(json_nums "$T/out" index_count | sort -u)" "$((3 * NF))" "draco info index_count"
    expect_out '"encoding_name":[[:space:]]*"draco"' "draco info encoding"
fi

# ----------------------------------------------------------------- validate
run "$MI" validate --full "$T/a.meso"
expect_rc 0 "validate --full on a fresh bake"
expect_out "^$T/a.meso: valid\$" "validate summary line"
run "$MI" validate "$T/a.meso" --format json
expect_rc 0 "validate json"
expect_out '"valid":[[:space:]]*true' "validate json valid"
expect_out '"level":[[:space:]]*"cheap"' "validate json level cheap"
if [ "$have_draco" -eq 1 ]; then
    run "$MI" validate --full "$T/d.meso"
    expect_rc 0 "validate --full on a Draco bake (decoded)"
fi

# flip one byte in the middle of the MESH payload
cp "$T/a.meso" "$T/bad.meso"
POS=$((MESH_OFF + MESH_STORED / 2))
OLD=$(od -An -tu1 -j "$POS" -N1 "$T/bad.meso" | tr -d ' ')
if [ "$OLD" = 255 ]; then printf '\000'; else printf '\377'; fi |
    dd of="$T/bad.meso" bs=1 seek="$POS" conv=notrunc 2>/dev/null
cmp -s "$T/a.meso" "$T/bad.meso" && fail "byte flip did not change the file" || ok

run "$MI" validate --full "$T/bad.meso"
expect_rc 3 "validate --full after a flipped payload byte"
expect_out "error $CODE_PAYLOAD_CRC at offset $MESH_OFF \\(chunk $MESH_INDEX\\)" "validate names the CRC issue"
expect_out ': 1 issue$' "validate counts one issue"
run "$MI" validate --full "$T/bad.meso" --format json
expect_rc 3 "validate --full json after a flip"
expect_out '"valid":[[:space:]]*false' "validate json invalid"
expect_out '"level":[[:space:]]*"full"' "validate json level full"
expect_eq "$(json_nums "$T/out" code)" "$CODE_PAYLOAD_CRC" "validate json code"
expect_eq "$(json_nums "$T/out" chunk)" "$MESH_INDEX" "validate json chunk"
expect_eq "$(json_nums "$T/out" offset)" "$MESH_OFF" "validate json offset"
run "$MI" validate "$T/bad.meso"
expect_rc 0 "cheap validate does not read payloads"
run "$MI" info "$T/bad.meso"
expect_rc 0 "info on a file with a bad payload CRC"
expect_out 'MESH .* BAD$' "info shows the MESH CRC as BAD"
expect_err 'warning' "info warns about the bad CRC"

# truncated files
SIZE=$(size_of "$T/a.meso")
head -c $((SIZE - 64)) "$T/a.meso" >"$T/short.meso"
run "$MI" validate "$T/short.meso"
expect_rc 3 "validate on a truncated file"
expect_out "error $CODE_FILE_TRUNCATED" "truncation issue code"
run "$MI" validate --full "$T/short.meso" --format json
expect_rc 3 "validate --full json on a truncated file"
expect_out '"valid":[[:space:]]*false' "truncated json invalid"
head -c 10 "$T/a.meso" >"$T/tiny.meso"
run "$MI" validate "$T/tiny.meso"
expect_rc 3 "validate on a 10-byte file"
expect_out "error $CODE_HDR_TRUNCATED" "header truncation issue code"
run "$MI" info "$T/short.meso"
expect_rc 3 "info on a truncated file"
expect_err "error $CODE_FILE_TRUNCATED at offset" "info prints the coded error with its offset"

# --------------------------------------------------------------------- dump
run "$MI" dump "$T/a.meso" MESH -o "$T/mesh_dec.bin"
expect_rc 0 "dump MESH decoded"
run "$MI" dump "$T/a.meso" MESH:1 --stored -o "$T/mesh_st.bin"
expect_rc 0 "dump MESH:1 --stored"
cmp -s "$T/mesh_dec.bin" "$T/mesh_st.bin" && ok || fail "raw MESH: decoded dump != stored dump"
expect_eq "$(size_of "$T/mesh_dec.bin")" "$MESH_DECODED" "dumped size = decoded_size"
"$MI" dump "$T/a.meso" "$MESH_INDEX" -o - >"$T/mesh_idx.bin" 2>"$T/err"
rc=$?
expect_rc 0 "dump by TOC index to stdout"
cmp -s "$T/mesh_dec.bin" "$T/mesh_idx.bin" && ok || fail "dump by index != dump by type"
# the stored bytes are the file's bytes at the MESH offset
dd if="$T/a.meso" of="$T/mesh_file.bin" bs=64 skip=$((MESH_OFF / 64)) count=$(((MESH_STORED + 63) / 64)) 2>/dev/null
head -c "$MESH_STORED" "$T/mesh_file.bin" >"$T/mesh_file2.bin"
cmp -s "$T/mesh_st.bin" "$T/mesh_file2.bin" && ok || fail "stored dump != file bytes at the MESH offset"
run "$MI" dump "$T/a.meso" META -o -
expect_rc 0 "dump META"
expect_out '"generator"' "META is the bake metadata"
if [ "$have_draco" -eq 1 ]; then
    D_DECODED=$(chunk_col "$T/d.meso" MESH decoded)
    D_STORED=$(chunk_col "$T/d.meso" MESH stored)
    run "$MI" dump "$T/d.meso" MESH:1:0 -o "$T/d_dec.bin"
    expect_rc 0 "dump Draco MESH decoded"
    expect_eq "$(size_of "$T/d_dec.bin")" "$D_DECODED" "Draco dump size = decoded_size"
    expect_eq "$D_DECODED" "$MESH_DECODED" "Draco decodes to the raw layout size"
    run "$MI" dump "$T/d.meso" MESH --stored -o "$T/d_st.bin"
    expect_rc 0 "dump Draco MESH --stored"
    expect_eq "$(size_of "$T/d_st.bin")" "$D_STORED" "Draco stored dump size"
    [ "$D_STORED" -lt "$D_DECODED" ] && ok || fail "Draco stored size $D_STORED not smaller than $D_DECODED"
fi
run "$MI" dump "$T/bad.meso" MESH -o "$T/never.bin"
expect_rc 3 "dump of a chunk failing its CRC"
expect_err "error $CODE_PAYLOAD_CRC" "dump names the CRC issue"
[ -e "$T/never.bin" ] && fail "dump wrote output for a bad chunk" || ok
run "$MI" dump "$T/a.meso" TX2D:1:2 -o "$T/never.bin"
expect_rc 1 "dump of a chunk spec matching nothing"
expect_err "no chunk matches 'TX2D:1:2'" "dump says the spec matches nothing"
run "$MI" dump "$T/a.meso" 99 -o "$T/never.bin"
expect_rc 1 "dump of an out-of-range index"
run "$MI" dump "$T/a.meso" MES -o "$T/never.bin"
expect_rc 1 "dump with a malformed chunk spec"
expect_err "See 'mesoinspect --help'\\." "malformed spec hint"
[ -e "$T/never.bin" ] && fail "dump wrote output for an unmatched spec" || ok
run "$MI" dump "$T/a.meso" MESH
expect_rc 1 "dump without -o"

# --------------------------------------------------------------------- diff
run "$MI" diff "$T/a.meso" "$T/a.meso"
expect_rc 0 "diff of a file with itself"
cmp -s "$T/a.meso" "$T/a2.meso" && ok || fail "baking the same input twice is not byte-identical"
run "$MI" diff "$T/a.meso" "$T/a2.meso" --format json
expect_rc 0 "diff of two identical bakes"
expect_out '"identical":[[:space:]]*true' "diff json identical"
run "$MI" diff "$T/a.meso" "$T/torus.meso"
expect_rc 7 "diff sphere vs torus"
expect_out '^MESH:1:0' "sphere vs torus: MESH differs"
expect_out 'mesh.vertex_count +642 -> ' "sphere vs torus: vertex counts"
run "$MI" diff "$T/a.meso" "$T/torus.meso" --format json
expect_rc 7 "diff json sphere vs torus"
expect_out '"identical":[[:space:]]*false' "diff json not identical"
if [ "$have_draco" -eq 1 ]; then
    run "$MI" diff "$T/a.meso" "$T/d.meso"
    expect_rc 7 "diff raw vs Draco bake"
    expect_out '^MESH' "raw vs Draco diff mentions MESH"
    expect_out 'encoding +raw -> draco' "raw vs Draco: encoding field"
    expect_out 'parameters\.encoding' "raw vs Draco: META key"
fi
run "$MI" diff "$T/a.meso" "$T/bad.meso"
expect_rc 3 "diff against a file with a bad chunk"

# ------------------------------------------------------- CLI conventions
run "$MI"
expect_rc 1 "no arguments"
expect_err '^Usage: mesoinspect' "no arguments: short usage on stderr"
run "$MI" --bogus
expect_rc 1 "unknown flag"
expect_err "^mesoinspect error: unrecognized option '--bogus'\$" "unknown flag message"
expect_err "^See 'mesoinspect --help'\\.\$" "unknown flag hint"
run "$MI" frobnicate
expect_rc 1 "unknown command"
expect_err "See 'mesoinspect --help'\\." "unknown command hint"
for cmd in info validate diff dump; do
    run "$MI" $cmd --bogus
    expect_rc 1 "$cmd --bogus"
    expect_err "^See 'mesoinspect --help'\\.\$" "$cmd --bogus hint"
    run "$MI" $cmd
    expect_rc 1 "$cmd without arguments"
    run "$MI" $cmd --help
    expect_rc 0 "$cmd --help"
    expect_out "^Usage: mesoinspect $cmd" "$cmd --help usage"
done
run "$MI" info "$T/a.meso" --format xml
expect_rc 1 "--format xml"
expect_err "See 'mesoinspect --help'\\." "--format xml hint"
run "$MI" --help
expect_rc 0 "--help"
for cmd in info validate dump diff preview; do
    expect_out "^  $cmd " "--help lists $cmd"
done
if [ -s "$T/err" ]; then fail "--help wrote to stderr"; else ok; fi
run "$MI" -h
expect_rc 0 "-h"
run "$MI" --version
expect_rc 0 "--version"
expect_out '^mesoinspect [0-9]+\.[0-9]+\.[0-9]+ \(format [0-9]+\.[0-9]+\)$' "--version format"
# same tool and format version as mesobake (which also names its batch cache version)
expect_eq "$(sed 's/^mesoinspect //' "$T/out")" "$("$MB" --version | sed 's/^mesobake //; s/, batch cache [0-9]*)$/)/')" \
    "--version matches mesobake"

# input errors
for cmd in info validate; do
    run "$MI" $cmd "$T/does-not-exist.meso"
    expect_rc 2 "$cmd on a missing file"
    expect_err '^mesoinspect error: ' "$cmd missing file diagnostic"
    run "$MI" $cmd "$DATA/sphere.obj"
    expect_rc 3 "$cmd on a text file"
done
expect_out "error $CODE_HDR_MAGIC at offset 0" "validate names the bad magic"
run "$MI" info "$T"
expect_rc 2 "info on a directory"
run "$MI" diff "$T/a.meso" "$T/does-not-exist.meso"
expect_rc 2 "diff with a missing file"
run "$MI" diff "$DATA/sphere.obj" "$T/a.meso"
expect_rc 3 "diff with a text file"
run "$MI" dump "$T/does-not-exist.meso" MESH -o "$T/never.bin"
expect_rc 2 "dump of a missing file"
: >"$T/empty.meso"
run "$MI" validate "$T/empty.meso"
expect_rc 3 "validate on an empty file"

echo "inspect_cli: $checks checks passed, $failures failed"
[ "$failures" -eq 0 ]
