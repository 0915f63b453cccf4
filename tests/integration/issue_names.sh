#!/bin/sh
# Every issue code of formats/meso_file.h (MESO_ISSUE_NAME NNNNu) has its
# name in mesoinspect's table (tools/mesoinspect/mesoinspect.c), which
# `validate --format json` prints: a code added without a name would print
# "name": null.
# usage: issue_names.sh SOURCE_ROOT
set -u
root=$1
fail=0 n=0
sed -n 's/^#define MESO_ISSUE_\([A-Z0-9_]*\) \([0-9]*\)u.*/\1 \2/p' "$root/formats/meso_file.h" >"${TMPDIR:-/tmp}/issue_names.$$"
while read -r name code; do
  [ "$code" = 0 ] && continue
  n=$((n + 1))
  if ! grep -q "{$code, \"$name\"}" "$root/tools/mesoinspect/mesoinspect.c"; then
    echo "FAIL issue $code ($name) has no name in mesoinspect's table"
    fail=1
  fi
done <"${TMPDIR:-/tmp}/issue_names.$$"
rm -f "${TMPDIR:-/tmp}/issue_names.$$"
[ "$n" -gt 100 ] || { echo "FAIL only $n issue codes found in meso_file.h"; fail=1; }
[ $fail = 0 ] && echo "ok   all $n issue codes have their names"
exit $fail
