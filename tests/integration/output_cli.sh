#!/bin/sh
# output_cli.sh MESOBAKE MESOINSPECT DATA_DIR
#
# Outputs never harm what is there (issue 21, FORMAT.md §10):
# - an -o that is a symbolic link is written through to its final target,
#   atomically in the target's directory; the link stays a link;
# - a dangling link, a FIFO, a directory, a socket or a device node (our own,
#   made with mknod in the temp dir, never the real /dev/null) is refused
#   with exit 2 before any work, and left as it was; the same for --report,
#   mesoinspect preview -o and dump -o;
# - a run whose --report cannot be written publishes no .meso (an existing
#   one stays byte-identical);
# - SIGINT, SIGTERM and SIGHUP while the outputs are staged leave no
#   ".NAME.tmp.XXXXXX" file and the old outputs byte-identical. The moment is
#   made deterministic by the test-only hook MESO_TEST_HOLD_OUTPUTS
#   (tools/common/cli_output.h): with every temporary file complete, the program
#   waits for a signal instead of renaming; the test waits (bounded) for the
#   temporary files to appear, then sends the signal. No timing race.
set -u

MB=$1
MI=$2
DATA=$3

. "$(dirname "$0")/check_lib.sh" # $T, run, expect_*, fail, ok
# `ls -ld` type letter of $1 (d, l, p, s, c, -), without following links
kind() { ls -ld "$1" | cut -c1; }

MESH="$DATA/sphere.obj"
W="$T/w"
mkdir "$W"

# The reference: a plain bake to a new file.
run "$MB" mesh -i "$MESH" -o "$T/ref.meso"
expect_rc 0 "reference bake"

# ------------------------------------------------ symlinks are written through
mkdir "$W/real"
echo old >"$W/real/t.meso"
ln -s real/t.meso "$W/link.meso"
ln -s link.meso "$W/link2.meso"
for l in link.meso link2.meso; do
    echo old >"$W/real/t.meso"
    run "$MB" mesh -i "$MESH" -o "$W/$l"
    expect_rc 0 "-o $l (a symbolic link)"
    same_bytes "$W/real/t.meso" "$T/ref.meso" "-o $l: the target gets the bake"
    if [ "$(kind "$W/link.meso")" = l ] && [ "$(readlink "$W/link.meso")" = real/t.meso ] &&
        [ "$(kind "$W/link2.meso")" = l ] && [ "$(readlink "$W/link2.meso")" = link.meso ]; then
        ok
    else
        fail "-o $l: the links are no longer the same links"
    fi
    expect_only "$W" "real link.meso link2.meso" "-o $l: link directory"
    expect_only "$W/real" "t.meso" "-o $l: target directory"
done
# --report through a link too, and mesoinspect dump -o through a link.
ln -s real/r.json "$W/r-link.json"
echo old >"$W/real/r.json"
run "$MB" mesh -i "$MESH" -o "$W/link.meso" --report "$W/r-link.json"
expect_rc 0 "--report through a symbolic link"
if grep -q '"triangles"' "$W/real/r.json" && [ "$(kind "$W/r-link.json")" = l ]; then ok; else
    fail "--report through a symbolic link: target not written or link replaced"; fi
run "$MI" dump "$T/ref.meso" META -o "$T/meta.json"
expect_rc 0 "dump META to a new file"
echo old >"$W/real/meta.json"
ln -s real/meta.json "$W/meta-link"
run "$MI" dump "$T/ref.meso" META -o "$W/meta-link"
expect_rc 0 "dump -o a symbolic link"
same_bytes "$W/real/meta.json" "$T/meta.json" "dump -o a symbolic link: the target gets the chunk"
expect_only "$W" "real link.meso link2.meso r-link.json meta-link" "dump through a link: link directory"
expect_only "$W/real" "t.meso r.json meta.json" "dump through a link: target directory"
rm -rf "$W"
mkdir "$W"

# ------------------------------------------- non-regular files are refused
# A FIFO is refused before it is opened: were it opened, the run would block.
mkfifo "$W/fifo"
ln -s nothing/here.meso "$W/dangling"
ln -s fifo "$W/to-fifo"
mkdir "$W/dir"
python3 -c 'import socket, sys; socket.socket(socket.AF_UNIX).bind(sys.argv[1])' "$W/sock" 2>/dev/null ||
    fail "cannot make a socket with python3"
nodes="fifo:FIFO dangling:dangling to-fifo:FIFO dir:directory sock:socket"
if mknod "$W/null" c 1 3 2>/dev/null; then
    nodes="$nodes null:device"
elif [ "$(id -u)" -eq 0 ]; then
    fail "running as root but mknod failed"
else
    echo "not root: no device node case (FIFO, socket, directory, links tested)"
fi
names=$(for n in $nodes; do printf '%s ' "${n%%:*}"; done)
ls -lA "$W" >"$T/before"
for n in $nodes; do
    name=${n%%:*}
    what=${n#*:}
    run "$MB" mesh -i "$MESH" -o "$W/$name"
    expect_rc 2 "-o $name"
    expect_err_text "$W/$name" "-o $name: message names the path"
    expect_err_text "$what" "-o $name: message says what it is"
    run "$MB" mesh -i "$MESH" -o "$T/new.meso" --report "$W/$name"
    expect_rc 2 "--report $name"
    expect_err_text "$what" "--report $name: message says what it is"
    if [ -e "$T/new.meso" ]; then fail "--report $name: the .meso was published"; rm -f "$T/new.meso"; else ok; fi
    run "$MI" preview "$T/ref.meso" -o "$W/$name" --reference
    expect_rc 2 "mesoinspect preview -o $name"
    expect_err_text "$what" "preview -o $name: message says what it is"
    run "$MI" dump "$T/ref.meso" META -o "$W/$name"
    expect_rc 2 "mesoinspect dump -o $name"
    expect_err_text "$what" "dump -o $name: message says what it is"
done
ls -lA "$W" >"$T/after"
same_bytes "$T/after" "$T/before" "refused destinations: the directory listing (kinds, sizes, targets)"
expect_only "$W" "$names" "refused destinations"
expect_only "$T" "ref.meso meta.json w out err before after" "refused destinations: nothing published"
rm -rf "$W"
mkdir "$W"

# ------------------------------------- a failed --report publishes nothing
run "$MB" mesh -i "$MESH" -o "$W/x.meso" --report "$W/nodir/r.json"
expect_rc 2 "--report nodir/r.json"
expect_err_text "$W/nodir/r.json" "--report nodir/r.json: message names the path"
expect_only "$W" "" "--report nodir/r.json: no .meso published"
echo old-meso >"$W/x.meso"
cp "$W/x.meso" "$T/x.old"
run "$MB" mesh -i "$MESH" -o "$W/x.meso" --report "$W/nodir/r.json"
expect_rc 2 "--report nodir/r.json over an existing .meso"
same_bytes "$W/x.meso" "$T/x.old" "--report nodir/r.json: the old .meso is byte-identical"
expect_only "$W" "x.meso" "--report nodir/r.json over an existing .meso"
# The same file named by -o and --report: refused, the old file kept.
run "$MB" mesh -i "$MESH" -o "$W/x.meso" --report "$W/x.meso"
expect_rc 1 "-o and --report the same file"
same_bytes "$W/x.meso" "$T/x.old" "-o and --report the same file: the old file is byte-identical"
expect_only "$W" "x.meso" "-o and --report the same file"

# ------------------------------------ signals while the outputs are staged
# `env --default-signal` undoes the SIG_IGN a non-interactive shell gives a
# background job's SIGINT (a program keeps an inherited ignore, as nohup needs).
env --default-signal=INT true 2>/dev/null || fail "env --default-signal is needed to send SIGINT to a background job"
# wait_temps PATTERN N: wait until N files match $W/PATTERN (at most 60 s).
wait_temps() {
    i=0
    while [ "$i" -lt 600 ]; do
        [ "$(ls -A "$W" | grep -c "$1")" -ge "$2" ] && return 0
        sleep 0.1
        i=$((i + 1))
    done
    return 1
}
echo old-report >"$W/r.json"
cp "$W/r.json" "$T/r.old"
for sig in INT TERM HUP; do
    MESO_TEST_HOLD_OUTPUTS=1 env --default-signal=INT \
        "$MB" mesh -i "$MESH" -o "$W/x.meso" --report "$W/r.json" >"$T/out" 2>"$T/err" &
    pid=$!
    if wait_temps '^\.\(x\.meso\|r\.json\)\.tmp\.' 2; then
        ok
    else
        fail "SIG$sig: the staged temporary files never appeared"
    fi
    kill -s "$sig" "$pid"
    wait "$pid"
    rc=$?
    case $sig in INT) num=2 ;; TERM) num=15 ;; HUP) num=1 ;; esac
    expect_rc $((128 + num)) "SIG$sig during a bake: ended by the signal"
    expect_only "$W" "x.meso r.json" "SIG$sig during a bake: no temporary file left"
    same_bytes "$W/x.meso" "$T/x.old" "SIG$sig during a bake: old .meso intact"
    same_bytes "$W/r.json" "$T/r.old" "SIG$sig during a bake: old report intact"
done
# mesoinspect too (dump -o).
MESO_TEST_HOLD_OUTPUTS=1 "$MI" dump "$T/ref.meso" META -o "$W/x.meso" >"$T/out" 2>"$T/err" &
pid=$!
if wait_temps '^\.x\.meso\.tmp\.' 1; then ok; else fail "mesoinspect: the staged temporary file never appeared"; fi
kill -s TERM "$pid"
wait "$pid"
rc=$?
expect_rc 143 "SIGTERM during mesoinspect dump"
expect_only "$W" "x.meso r.json" "SIGTERM during mesoinspect dump: no temporary file left"
same_bytes "$W/x.meso" "$T/x.old" "SIGTERM during mesoinspect dump: old file intact"
# Without the hook the same command publishes (the hook is what held it).
run "$MB" mesh -i "$MESH" -o "$W/x.meso" --report "$W/r.json"
expect_rc 0 "the bake without the hook"
same_bytes "$W/x.meso" "$T/ref.meso" "the bake without the hook: published"
expect_only "$W" "x.meso r.json" "the bake without the hook"

echo "output_cli: $checks checks, $failures failures"
[ "$failures" -eq 0 ]
