# check_lib.sh — what the command-line test scripts share. Source it first:
#   . "$(dirname "$0")/check_lib.sh"
# It makes the temp dir $T (removed on exit), the counters $failures and
# $checks, and these checks (each one adds to a counter):
#   run CMD...              CMD with stdout/stderr in $T/out, $T/err; exit in $rc
#   expect_rc N DESC        the last run exited N
#   expect_out RE DESC      stdout of the last run matches RE (grep -E)
#   expect_err RE DESC      stderr of the last run matches RE (grep -E)
#   expect_err_text S DESC  stderr of the last run contains S literally (grep -F)
#   expect_eq GOT WANT DESC
#   expect_only DIR "F..." DESC   nothing in DIR but the files named
#   same_bytes A B DESC     A and B have the same bytes
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
trap 'exit 1' INT TERM

failures=0
checks=0

fail() {
    failures=$((failures + 1))
    echo "FAIL: $*" >&2
    if [ -s "$T/out" ]; then echo "--- stdout:" >&2; head -n 20 "$T/out" >&2; fi
    if [ -s "$T/err" ]; then echo "--- stderr:" >&2; head -n 20 "$T/err" >&2; fi
}
ok() { checks=$((checks + 1)); }
run() {
    "$@" >"$T/out" 2>"$T/err"
    rc=$?
}
expect_rc() {
    if [ "$rc" -eq "$1" ]; then ok; else fail "$2: exit $rc, expected $1"; fi
}
expect_out() {
    if grep -Eq -- "$1" "$T/out"; then ok; else fail "$2: stdout lacks /$1/"; fi
}
expect_err() {
    if grep -Eq -- "$1" "$T/err"; then ok; else fail "$2: stderr lacks /$1/"; fi
}
expect_err_text() {
    if grep -Fq -- "$1" "$T/err"; then ok; else fail "$2: stderr lacks '$1'"; fi
}
expect_eq() {
    if [ "$1" = "$2" ]; then ok; else fail "$3: got '$1', expected '$2'"; fi
}
expect_only() {
    extra=$(ls -A "$1" | while read -r f; do
        case " $2 " in *" $f "*) ;; *) echo "$f" ;; esac
    done)
    if [ -z "$extra" ]; then ok; else fail "$3: unexpected files in $1: $extra"; fi
}
same_bytes() {
    if cmp -s "$1" "$2"; then ok; else fail "$3: $1 differs from $2"; fi
}
