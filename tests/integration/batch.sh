#!/bin/sh
# mesobake batch (issue 17, tools/mesobake/batch.h) from the command line:
# a manifest of mixed jobs (mesh, --draco, shell with built-in and PNG
# textures, --tiling, --kind, cells, frusta from .skel with --relief and from
# .swc, a job taking its command from "defaults") bakes byte for byte what the
# single `mesobake COMMAND` does in the manifest's directory; the cache
# (a re-run copies nothing and leaves outputs' time stamps alone, a touched
# input stays cached, a changed input, option or texture file re-bakes exactly
# its jobs, a damaged entry is a miss); failing jobs (bad mesh, missing file)
# reported by name with exit 6 while the others complete; three batches at
# once sharing one cache; invalid manifests refused with their E345x code and
# nothing written; --no-cache; keys independent of where the project lives.
# (Known-answer digests under MESO_BATCH_CACHE_VERSION: batch_cache_version.sh.)
# Everything runs in a temporary directory with a private --cache.
# usage: batch.sh MESOBAKE MESOINSPECT TEST_DATA_DIR WRITE_HEIGHT_PNG
set -u
bake=$1 inspect=$2 data=$3 writepng=$4
abs() { case $1 in /*) echo "$1" ;; *) echo "$PWD/$1" ;; esac; }
bake=$(abs "$bake") inspect=$(abs "$inspect") data=$(abs "$data") writepng=$(abs "$writepng")
tmp=$(mktemp -d)
short=$(mktemp -d /tmp/mbXXXXXX) # a short base for the $TMPDIR lengths below
trap 'rm -rf "$tmp" "$short"' EXIT
fail=0
ok() { echo "ok   $1"; }
bad() { echo "FAIL $*"; fail=1; }
check() { # DESCRIPTION COMMAND...
  d=$1; shift
  if "$@"; then ok "$d"; else bad "$d"; fi
}
eq() { # DESCRIPTION GOT WANT (several lines: the lines that differ)
  if [ "$2" = "$3" ]; then
    ok "$1"
  elif [ "$(printf '%s\n' "$2$3" | wc -l)" -gt 1 ]; then
    bad "$1: got -, want +:"
    printf '%s\n' "$2" >"$tmp/eq.got" && printf '%s\n' "$3" >"$tmp/eq.want"
    diff "$tmp/eq.got" "$tmp/eq.want" | sed -n 's/^</     -/p; s/^>/     +/p'
  else
    bad "$1: got '$2', want '$3'"
  fi
}
same() { # DESCRIPTION FILE_A FILE_B: byte for byte
  if d=$(cmp "$2" "$3" 2>&1); then ok "$1"; else bad "$1: $d"; fi
}
absent() { # DESCRIPTION PATH...
  d=$1; shift
  for p in "$@"; do
    if [ -e "$p" ]; then bad "$d: $p exists"; return; fi
  done
  ok "$d"
}
matches() { # DESCRIPTION STRING PATTERN (grep -E, the whole string)
  if printf '%s\n' "$2" | grep -Eqx -- "$3"; then ok "$1"; else bad "$1: '$2' is not /$3/"; fi
}
has() { # DESCRIPTION FILE PATTERN (grep -E)
  if grep -Eq -- "$3" "$2"; then ok "$1"; else bad "$1: no /$3/ in $2:"; sed 's/^/     | /' "$2" | head -20; fi
}

# Batch reports (cJSON_Print: one field per line). `top R F` is field F of
# the report, `field R JOB F` field F of the job named JOB (fields of its bake
# report, one level deeper, are skipped), `jobs_with R STATUS` the names of
# the jobs with that status, sorted, on one line.
json_fields() { # REPORT: "DEPTH<tab>JOB<tab>FIELD<tab>VALUE" for every field
  awk '
    BEGIN { depth = 0; job = "" }
    {
      s = $0
      gsub(/"([^"\\]|\\.)*"/, "\"\"", s) # brackets inside strings do not nest
      if (match($0, /^[[:space:]]*"[^"]*":/)) {
        f = substr($0, RSTART, RLENGTH); sub(/^[[:space:]]*"/, "", f); sub(/":$/, "", f)
        v = substr($0, RSTART + RLENGTH); sub(/^[[:space:]]*/, "", v); sub(/,$/, "", v)
        if (v ~ /^".*"$/) v = substr(v, 2, length(v) - 2)
        if (depth == 3 && f == "name") job = v
        printf "%d\t%s\t%s\t%s\n", depth, (depth >= 3 ? job : ""), f, v
      }
      depth += gsub(/[[{]/, "", s) - gsub(/[]}]/, "", s)
    }' "$1"
}
top() { json_fields "$1" | awk -F '\t' -v f="$2" '$1 == 1 && $3 == f { print $4 }'; }
field() { json_fields "$1" | awk -F '\t' -v j="$2" -v f="$3" '$1 == 3 && $2 == j && $3 == f { print $4 }'; }
jobs_with() { json_fields "$1" | awk -F '\t' -v s="$2" '$1 == 3 && $3 == "status" && $4 == s { print $2 }' |
  sort | tr '\n' ' ' | sed 's/ $//'; }
counts() { echo "$(top "$1" jobs_baked) baked $(top "$1" jobs_cached) cached $(top "$1" jobs_failed) failed"; }
entry() { echo "$1/v1/$(echo "$2" | cut -c1-2)/$2.meso"; } # CACHE KEY
flip_byte() { # FILE: invert the byte in the middle
  at=$(($(wc -c <"$1") / 2))
  b=$(od -An -tu1 -j "$at" -N 1 "$1" | tr -d ' ')
  printf "$(printf '\\%03o' $((b ^ 255)))" | dd of="$1" bs=1 seek="$at" conv=notrunc 2>/dev/null
}
tmpfiles() { find "$@" -name '.*.tmp.*' 2>/dev/null | head -5; }

# The jobs: NAME COMMAND ("-": the defaults' shell) INPUT ARGS..., each bake
# cheap (small meshes, 64^2 built-ins, 16^3 tiles) so the test stays fast
# under the sanitizers. spot_uv.obj is read by three jobs (two with the same
# key), sphere.obj by two. The defaults add --max-memory to every job.
# shell_envelope has an odd number of args (a bake's argv one slot short
# once overwrote malloc's next header for those: the batch aborted).
defaults_args="--max-memory 1G"
cat >"$tmp/jobs.txt" <<'EOF'
mesh_spot mesh spot_uv.obj
mesh_draco mesh spot_uv.obj --draco
shell_bricks - cube_no_bottom.obj --texture bricks:64 --tiling 2,2
shell_height shell cube_no_bottom.obj --texture height:tex/h.png
shell_interior - sphere.obj --kind interior --texture ribs:32
shell_envelope shell torus.obj --kind envelope --thickness-rel 0.02 --no-repair
cells_sphere cells sphere.obj --tiles 4 --tile-res 16
frusta_skel frusta saguaro.skel --relief bricks:64
frusta_swc frusta neurom_simple.swc
mesh_again mesh spot_uv.obj
EOF
njobs=$(wc -l <"$tmp/jobs.txt" | tr -d ' ')
out_of() { [ "$1" = mesh_again ] && echo out/sub/mesh_again.meso || echo "out/$1.meso"; }
write_manifest() { # JOBS.TXT MANIFEST
  {
    printf '{"$schema": "manifest.schema.json",\n "defaults": {"command": "shell", "args": ["%s"]},\n "jobs": [\n' \
      "$(echo "$defaults_args" | sed 's/ /", "/g')"
    sep=""
    while read -r name cmd input args; do
      printf '%s  {"name": "%s", ' "$sep" "$name"
      [ "$cmd" = - ] || printf '"command": "%s", ' "$cmd"
      printf '"input": "%s", "output": "%s"' "$input" "$(out_of "$name")"
      [ -n "$args" ] && printf ', "args": ["%s"]' "$(echo "$args" | sed 's/ /", "/g')"
      printf '}'
      sep=",
"
    done <"$1"
    printf '\n ]}\n'
  } >"$2"
}
single() { # DIR NAME OUT: the job's single command, run by hand in DIR
  line=$(awk -v n="$2" '$1 == n' "$tmp/jobs.txt")
  set -- "$1" "$3" $line
  dir=$1 out=$2 cmd=$4 input=$5
  shift 5
  [ "$cmd" = - ] && cmd=shell
  # shellcheck disable=SC2086 # the args are words
  (cd "$dir" && "$bake" "$cmd" -i "$input" -o "$out" $defaults_args "$@" >/dev/null 2>&1)
}
batch() { # DIR MANIFEST TAG [OPTIONS...]: run, stderr to $tmp/TAG.err, report $tmp/TAG.json; sets rc
  d=$1 m=$2 t=$3; shift 3
  "$bake" batch "$d/$m" --report "$tmp/$t.json" "$@" >"$tmp/$t.out" 2>"$tmp/$t.err"
  rc=$?
}

# The pristine copy: inputs, a 32^2 height map, the manifest.
orig=$tmp/orig
mkdir -p "$orig/tex"
for f in spot_uv.obj cube_no_bottom.obj sphere.obj torus.obj saguaro.skel neurom_simple.swc neurom_fat_end.swc; do
  cp "$data/$f" "$orig/" || bad "copy $f"
done
"$writepng" "$orig/tex/h.png" 8 32 || bad "write tex/h.png"
write_manifest "$tmp/jobs.txt" "$orig/m.json"
w=$tmp/w cache=$tmp/cache ref=$tmp/ref
cp -R "$orig" "$w"
mkdir -p "$ref"

# The single commands, then the batch: byte for byte the same.
while read -r name rest; do
  single "$w" "$name" "$ref/$name.meso" || bad "single bake $name"
done <"$tmp/jobs.txt"
batch "$w" m.json run1 --cache "$cache" -j 2
eq "run 1: exit 0" "$rc" 0
eq "run 1: jobs_total" "$(top "$tmp/run1.json" jobs_total)" "$njobs"
eq "run 1: all baked but the duplicate key" "$(counts "$tmp/run1.json")" "$((njobs - 1)) baked 1 cached 0 failed"
eq "run 1: the duplicate key is the cached one" "$(jobs_with "$tmp/run1.json" cached)" mesh_again
eq "run 1: duplicates share a key" "$(field "$tmp/run1.json" mesh_again key)" "$(field "$tmp/run1.json" mesh_spot key)"
while read -r name rest; do
  same "run 1: $name = its single command" "$ref/$name.meso" "$w/$(out_of "$name")"
  k=$(field "$tmp/run1.json" "$name" key)
  matches "run 1: $name has a 64-hex key" "$k" '[0-9a-f]{64}'
  [ "$name" = mesh_again ] || same "run 1: $name's cache entry = its output" "$ref/$name.meso" "$(entry "$cache" "$k")"
done <"$tmp/jobs.txt"
eq "run 1: attempts 1 when baked, 0 when cached" \
  "$(field "$tmp/run1.json" mesh_spot attempts) $(field "$tmp/run1.json" mesh_again attempts)" "1 0"
eq "run 1: threads 0 for mesh" "$(field "$tmp/run1.json" mesh_spot threads)" 0
check "run 1: threads >= 1 for shell" test "$(field "$tmp/run1.json" shell_bricks threads)" -ge 1
eq "run 1: the job's bake report (cells tiles)" "$(json_fields "$tmp/run1.json" |
  awk -F '\t' '$1 == 4 && $2 == "cells_sphere" && $3 == "tiles" { print $4 }')" 64
eq "run 1: command from defaults" "$(field "$tmp/run1.json" shell_bricks command)" shell
has "run 1: stderr names a baked job" "$tmp/run1.err" "baked frusta_swc"
has "run 1: stderr sums up" "$tmp/run1.err" "$njobs jobs: $((njobs - 1)) baked, 1 cached, 0 failed"
for f in seconds cpu_seconds cpu_busy; do
  matches "run 1: report has $f" "$(top "$tmp/run1.json" $f)" '[0-9][0-9.e+-]*'
done
eq "run 1: no temporary files left" "$(tmpfiles "$cache" "$w")" ""
# The defaults' args come first, so a job's own args win; both are passed.
mkdir -p "$tmp/d"
cp "$data/cube_no_bottom.obj" "$tmp/d/"
cat >"$tmp/d/defaults.json" <<'EOF'
{"defaults": {"command": "shell", "args": ["--thickness-rel", "0.03", "--texture", "bricks:32"]},
 "jobs": [{"input": "cube_no_bottom.obj", "output": "plain.meso"},
          {"input": "cube_no_bottom.obj", "output": "thick.meso", "args": ["--thickness-rel", "0.06"]}]}
EOF
(cd "$tmp/d" && "$bake" shell -i cube_no_bottom.obj -o ref_plain.meso --thickness-rel 0.03 --texture bricks:32 &&
  "$bake" shell -i cube_no_bottom.obj -o ref_thick.meso --texture bricks:32 --thickness-rel 0.06) >/dev/null 2>&1
batch "$tmp/d" defaults.json defaults --cache "$cache"
eq "defaults: exit 0" "$rc" 0
same "defaults: command and args from defaults" "$tmp/d/ref_plain.meso" "$tmp/d/plain.meso"
same "defaults: the job's args after the defaults'" "$tmp/d/ref_thick.meso" "$tmp/d/thick.meso"
eq "defaults: job named by its output" "$(jobs_with "$tmp/defaults.json" baked)" "plain.meso thick.meso"
# Baked again (an empty cache) into outputs that hold those bytes: not rewritten.
touch -d '2001-02-03 04:05:06' "$tmp/d/plain.meso" "$tmp/d/thick.meso"
before=$(stat -c '%n %Y %i' "$tmp/d/plain.meso" "$tmp/d/thick.meso")
batch "$tmp/d" defaults.json defaults2 --cache "$tmp/cache_d2"
eq "defaults, empty cache: both baked" "$(counts "$tmp/defaults2.json")" "2 baked 0 cached 0 failed"
eq "defaults, empty cache: outputs not rewritten" "$(stat -c '%n %Y %i' "$tmp/d/plain.meso" "$tmp/d/thick.meso")" \
  "$before"

# A re-run is all cached and rewrites nothing: outputs set to an old time
# stamp keep it and their inode.
find "$w/out" -name '*.meso' -exec touch -d '2001-02-03 04:05:06' {} +
stamps() { find "$w/out" -name '*.meso' -exec stat -c '%n %Y %i' {} + | sort; }
before=$(stamps)
batch "$w" m.json run2 --cache "$cache" -j 2
eq "run 2: exit 0" "$rc" 0
eq "run 2: all cached" "$(counts "$tmp/run2.json")" "0 baked $njobs cached 0 failed"
eq "run 2: outputs not rewritten (mtime, inode)" "$(stamps)" "$before"
while read -r name rest; do
  same "run 2: $name unchanged" "$ref/$name.meso" "$w/$(out_of "$name")"
done <"$tmp/jobs.txt"
check "run 2: seconds 0 for a cache hit" test "$(field "$tmp/run2.json" frusta_swc seconds)" = 0
eq "run 2: cached jobs keep their bake report" "$(json_fields "$tmp/run2.json" |
  awk -F '\t' '$1 == 4 && $2 == "cells_sphere" && $3 == "tiles" { print $4 }')" 64
# A damaged output is put right from the cache.
flip_byte "$w/out/frusta_swc.meso"
batch "$w" m.json run2b --cache "$cache" -j 2
eq "damaged output: all cached" "$(counts "$tmp/run2b.json")" "0 baked $njobs cached 0 failed"
same "damaged output: restored" "$ref/frusta_swc.meso" "$w/out/frusta_swc.meso"

# What re-bakes. A touched input (time stamp only), a different
# --max-memory and -v: nothing.
find "$w" -maxdepth 2 -type f ! -name '*.json' -exec touch {} +
batch "$w" m.json touched --cache "$cache" -j 2
eq "touched inputs: still all cached" "$(counts "$tmp/touched.json")" "0 baked $njobs cached 0 failed"
defaults_args="--max-memory 2G -v"
write_manifest "$tmp/jobs.txt" "$w/m.json"
batch "$w" m.json maxmem --cache "$cache" -j 2
eq "--max-memory 2G -v in the defaults: still all cached" "$(counts "$tmp/maxmem.json")" \
  "0 baked $njobs cached 0 failed"
defaults_args="--max-memory 1G"
write_manifest "$tmp/jobs.txt" "$w/m.json"
# A comment line appended to sphere.obj: its two jobs re-bake, to new keys.
echo "# a comment" >>"$w/sphere.obj"
batch "$w" m.json comment --cache "$cache" -j 2
eq "sphere.obj changed: exit 0" "$rc" 0
eq "sphere.obj changed: 2 re-baked" "$(counts "$tmp/comment.json")" "2 baked $((njobs - 2)) cached 0 failed"
eq "sphere.obj changed: exactly its jobs re-baked" "$(jobs_with "$tmp/comment.json" baked)" \
  "cells_sphere shell_interior"
for n in cells_sphere shell_interior; do
  check "sphere.obj changed: $n has a new key" \
    test "$(field "$tmp/comment.json" $n key)" != "$(field "$tmp/run1.json" $n key)"
  single "$w" $n "$tmp/$n.comment.meso"
  same "sphere.obj changed: $n = its single command" "$tmp/$n.comment.meso" "$w/$(out_of $n)"
done
eq "sphere.obj changed: other keys kept" "$(field "$tmp/comment.json" shell_envelope key)" \
  "$(field "$tmp/run1.json" shell_envelope key)"
# One job's option changed in the manifest: that job only.
sed 's/--tiling 2,2/--tiling 3,2/' "$tmp/jobs.txt" >"$tmp/jobs2.txt" && mv "$tmp/jobs2.txt" "$tmp/jobs.txt"
write_manifest "$tmp/jobs.txt" "$w/m.json"
batch "$w" m.json option --cache "$cache" -j 2
eq "--tiling changed: exit 0" "$rc" 0
eq "--tiling changed: only shell_bricks re-baked" "$(jobs_with "$tmp/option.json" baked)" shell_bricks
eq "--tiling changed: the rest cached" "$(counts "$tmp/option.json")" "1 baked $((njobs - 1)) cached 0 failed"
single "$w" shell_bricks "$tmp/shell_bricks.option.meso"
same "--tiling changed: shell_bricks = its single command" "$tmp/shell_bricks.option.meso" "$w/out/shell_bricks.meso"
check "--tiling changed: the bytes did change" sh -c "! cmp -s '$ref/shell_bricks.meso' '$w/out/shell_bricks.meso'"
# Files named by args: a height map with other bytes under the same
# name: a new key for the job reading it, and only that job re-bakes.
"$writepng" "$w/tex/h.png" 8 24 || bad "write tex/h.png (24)"
batch "$w" m.json png --cache "$cache" -j 2
eq "other tex/h.png: only shell_height re-baked" "$(jobs_with "$tmp/png.json" baked)" shell_height
check "other tex/h.png: a new key" \
  test "$(field "$tmp/png.json" shell_height key)" != "$(field "$tmp/option.json" shell_height key)"
single "$w" shell_height "$tmp/shell_height.png.meso"
same "other tex/h.png: shell_height = its single command" "$tmp/shell_height.png.meso" "$w/out/shell_height.meso"
check "other tex/h.png: the bytes did change" sh -c "! cmp -s '$ref/shell_height.meso' '$w/out/shell_height.meso'"

# Failing jobs: a NaN coordinate, a face index out of range, a missing
# file. Each is reported by name (report and stderr), exit 6, no output;
# the other jobs complete. Failures are not cached: a re-run fails again.
printf 'v 0 0 0\nv 1 0 0\nv 0 nan 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n' >"$w/nan.obj"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 9\n' >"$w/range.obj"
cat >"$w/f.json" <<'EOF'
{"jobs": [
  {"name": "good_mesh", "command": "mesh", "input": "spot_uv.obj", "output": "fout/good_mesh.meso"},
  {"name": "nan", "command": "mesh", "input": "nan.obj", "output": "fout/nan.meso"},
  {"name": "range", "command": "shell", "input": "range.obj", "output": "fout/range.meso"},
  {"name": "missing", "command": "frusta", "input": "nothere.swc", "output": "fout/missing.meso"},
  {"name": "good_swc", "command": "frusta", "input": "neurom_fat_end.swc", "output": "fout/good_swc.meso"}
]}
EOF
(cd "$w" && "$bake" mesh -i spot_uv.obj -o "$tmp/good_mesh.meso" && "$bake" frusta -i neurom_fat_end.swc \
  -o "$tmp/good_swc.meso") >/dev/null 2>&1 || bad "single bakes of the good jobs"
for r in 1 2; do
  batch "$w" f.json fail$r --cache "$cache" -j 2
  eq "failing jobs ($r): exit 6" "$rc" 6
  eq "failing jobs ($r): counts" "$(top "$tmp/fail$r.json" jobs_failed) failed" "3 failed"
  eq "failing jobs ($r): the failed ones" "$(jobs_with "$tmp/fail$r.json" failed)" "missing nan range"
  for n in nan range missing; do
    has "failing jobs ($r): stderr names $n" "$tmp/fail$r.err" "FAILED $n "
    check "failing jobs ($r): $n's error in the report" test -n "$(field "$tmp/fail$r.json" $n error)"
    check "failing jobs ($r): $n's exit_code in the report" test "$(field "$tmp/fail$r.json" $n exit_code)" -gt 0
    absent "failing jobs ($r): no output for $n" "$w/fout/$n.meso"
  done
  matches "failing jobs ($r): nan's error names the file" "$(field "$tmp/fail$r.json" nan error)" '.*nan\.obj.*'
  eq "failing jobs ($r): range exits 3 (invalid input)" "$(field "$tmp/fail$r.json" range exit_code)" 3
  eq "failing jobs ($r): missing exits 2 (I/O)" "$(field "$tmp/fail$r.json" missing exit_code)" 2
  eq "failing jobs ($r): missing input, no key" "$(field "$tmp/fail$r.json" missing key)" null
  same "failing jobs ($r): good_mesh right" "$tmp/good_mesh.meso" "$w/fout/good_mesh.meso"
  same "failing jobs ($r): good_swc right" "$tmp/good_swc.meso" "$w/fout/good_swc.meso"
done
eq "failing jobs: good_swc baked, then cached" \
  "$(field "$tmp/fail1.json" good_swc status) $(field "$tmp/fail2.json" good_swc status)" "baked cached"
eq "failing jobs: no temporary files left" "$(tmpfiles "$cache" "$w")" ""

# A damaged cache entry (one byte flipped) is a miss: that job re-bakes.
k=$(field "$tmp/png.json" frusta_skel key)
flip_byte "$(entry "$cache" "$k")"
check "damaged entry: no longer the bake" sh -c "! cmp -s '$ref/frusta_skel.meso' '$(entry "$cache" "$k")'"
batch "$w" m.json damaged --cache "$cache" -j 2
eq "damaged entry: exit 0" "$rc" 0
eq "damaged entry: only frusta_skel re-baked" "$(jobs_with "$tmp/damaged.json" baked)" frusta_skel
same "damaged entry: output right" "$ref/frusta_skel.meso" "$w/out/frusta_skel.meso"
same "damaged entry: entry right again" "$ref/frusta_skel.meso" "$(entry "$cache" "$k")"

# Three batches at once sharing one (empty) cache, each in its own copy of
# the project (the same keys as run 1, wherever the project lives).
shared=$tmp/shared
for i in 1 2 3; do cp -R "$orig" "$tmp/c$i"; done
for i in 1 2 3; do
  "$bake" batch "$tmp/c$i/m.json" --cache "$shared" -j 1 --report "$tmp/c$i.json" >/dev/null 2>"$tmp/c$i.err" &
  eval "pid$i=\$!"
done
for i in 1 2 3; do
  eval "wait \$pid$i"
  eq "concurrent $i: exit 0" "$?" 0
  eq "concurrent $i: no failures" "$(top "$tmp/c$i.json" jobs_failed)" 0
  while read -r name rest; do
    same "concurrent $i: $name" "$ref/$name.meso" "$tmp/c$i/$(out_of "$name")"
  done <"$tmp/jobs.txt"
  eq "concurrent $i: the same keys as run 1 elsewhere" \
    "$(json_fields "$tmp/c$i.json" | awk -F '\t' '$1 == 3 && $3 == "key" { print $2, $4 }')" \
    "$(json_fields "$tmp/run1.json" | awk -F '\t' '$1 == 3 && $3 == "key" { print $2, $4 }')"
done
n=0
for e in "$shared"/v1/*/*.meso; do
  n=$((n + 1))
  "$inspect" validate --full "$e" >"$tmp/validate.out" 2>&1 || { bad "concurrent: $e does not validate"; cat "$tmp/validate.out"; }
done
eq "concurrent: one entry per distinct key" "$n" "$((njobs - 1))"
eq "concurrent: no temporary files left" "$(tmpfiles "$shared" "$tmp/c1" "$tmp/c2" "$tmp/c3")" ""

# Invalid manifests: exit 3, the code, the manifest's name, nothing written.
mkdir -p "$tmp/bad"
cp "$data/sphere.obj" "$tmp/bad/"
job='{"command": "mesh", "input": "sphere.obj", "output": "never/a.meso"}'
printf '{"jobs": [\n  %s\n  %s]}\n' "$job" "$job" >"$tmp/bad/not_json.json"
printf '{"jobs": [{"command": "mesh", "input": "sphere.obj", "ouput": "never/a.meso"}]}\n' >"$tmp/bad/unknown_field.json"
printf '{"jobs": [{"command": "sculpt", "input": "sphere.obj", "output": "never/a.meso"}]}\n' >"$tmp/bad/unknown_command.json"
printf '{"jobs": [{"command": "mesh", "input": "sphere.obj", "output": "never/a.meso", "args": ["--draco", "-o", "x"]}]}\n' \
  >"$tmp/bad/owned_option.json"
printf '{"defaults": {"args": ["--threads", "2"]}, "jobs": [%s]}\n' "$job" >"$tmp/bad/owned_default.json"
printf '{"jobs": [%s, %s]}\n' "$job" "$job" >"$tmp/bad/same_output.json"
printf '{"jobs": [%s, {"command": "cells", "input": "sphere.obj", "output": "never/./a.meso"}]}\n' "$job" \
  >"$tmp/bad/same_output_spelt.json"
printf '{"jobs": [{"command": "mesh", "input": "sphere.obj", "output": "never/a.meso", "output": "never/b.meso"}]}\n' \
  >"$tmp/bad/field_twice.json"
printf '{"jobs": [{"command": "mesh", "input": "sphere.obj", "output": "never/a.meso", "args": ["--help"]}]}\n' \
  >"$tmp/bad/help.json"
printf '{"jobs": []}\n' >"$tmp/bad/empty.json"
printf '{"jobs": [{"command": "mesh", "input": "sphere.obj", "output": "never/a.meso", "args": "--draco"}]}\n' \
  >"$tmp/bad/args_type.json"
refuse() { # MANIFEST WANT_EXIT CODE [PATTERN]
  m=$1 want=$2 code=$3 pat=${4:-}
  "$bake" batch "$tmp/bad/$m" --cache "$tmp/bad/cache" --report "$tmp/bad/report.json" >/dev/null 2>"$tmp/bad/$m.err"
  eq "refuse $m: exit $want" "$?" "$want"
  has "refuse $m: E$code naming the manifest" "$tmp/bad/$m.err" "^mesobake error E$code: [^ ]*$m: "
  [ -n "$pat" ] && has "refuse $m: says '$pat'" "$tmp/bad/$m.err" "$pat"
  absent "refuse $m: nothing written" "$tmp/bad/never" "$tmp/bad/cache" "$tmp/bad/report.json"
  rm -rf "$tmp/bad/never" "$tmp/bad/cache" "$tmp/bad/report.json"
}
refuse not_json.json 3 3451 "line 3"
refuse unknown_field.json 3 3452 "jobs\[0\].*ouput"
refuse unknown_command.json 3 3453 sculpt
refuse owned_option.json 3 3454 "jobs\[0\]\.args\[1\]"
refuse owned_default.json 3 3454 "defaults\.args\[0\]"
refuse field_twice.json 3 3452 '"output" given twice'
refuse help.json 3 3454 "jobs\[0\]\.args\[0\]"
refuse same_output.json 3 3455
refuse same_output_spelt.json 3 3455
refuse empty.json 3 3456
refuse args_type.json 3 3452 "jobs\[0\]\.args"
refuse no_such_manifest.json 2 3450
"$bake" batch >/dev/null 2>&1
eq "no manifest: exit 1" "$?" 1
"$bake" batch "$orig/m.json" -j 0 --cache "$tmp/bad/cache" >/dev/null 2>&1
eq "-j 0: exit 1" "$?" 1
"$bake" batch "$orig/m.json" --no-cache --cache "$tmp/bad/cache" >/dev/null 2>&1
eq "--no-cache with --cache: exit 1" "$?" 1
absent "usage errors: nothing written" "$tmp/bad/cache" "$orig/out"
# --engine slurm where no sbatch is on PATH: exit 5 (not supported here),
# saying what is missing; the jobs are reported failed, none baked.
mkdir -p "$tmp/empty_path"
PATH=$tmp/empty_path "$bake" batch "$orig/m.json" --engine slurm --cache "$tmp/slurm_cache" \
  --report "$tmp/slurm.json" >/dev/null 2>"$tmp/slurm.err"
eq "--engine slurm without sbatch: exit 5" "$?" 5
has "--engine slurm without sbatch: says so" "$tmp/slurm.err" "needs Slurm's sbatch"
eq "--engine slurm without sbatch: all failed" "$(counts "$tmp/slurm.json")" "0 baked 0 cached $njobs failed"
absent "--engine slurm without sbatch: no output" "$orig/out"

# --no-cache: the bakes run straight to their outputs; no cache anywhere.
nc=$tmp/nc
mkdir -p "$nc"
cp "$orig/spot_uv.obj" "$orig/sphere.obj" "$orig/neurom_simple.swc" "$nc/"
grep -E '^(mesh_spot|cells_sphere|frusta_swc) ' "$tmp/jobs.txt" >"$tmp/nc_jobs.txt"
write_manifest "$tmp/nc_jobs.txt" "$nc/m.json"
MESO_CACHE_DIR=$tmp/nc_env XDG_CACHE_HOME=$tmp/nc_xdg HOME=$tmp/nc_home \
  "$bake" batch "$nc/m.json" --no-cache -j 2 --report "$tmp/nc.json" >/dev/null 2>"$tmp/nc.err"
eq "--no-cache: exit 0" "$?" 0
eq "--no-cache: all baked" "$(counts "$tmp/nc.json")" "3 baked 0 cached 0 failed"
eq "--no-cache: report cache null" "$(top "$tmp/nc.json" cache)" null
for n in mesh_spot cells_sphere frusta_swc; do
  same "--no-cache: $n" "$ref/$n.meso" "$nc/out/$n.meso"
done
absent "--no-cache: no cache directory" "$tmp/nc_env" "$tmp/nc_xdg" "$tmp/nc_home"
eq "--no-cache: no temporary files left" "$(tmpfiles "$nc")" ""

# The bakes' logs go to $TMPDIR, of any length (20 to 29 bytes once cut the
# log paths short: every job failed), and are removed.
grep '^frusta_swc ' "$tmp/jobs.txt" >"$tmp/td_jobs.txt"
for len in 24 28 40 300; do
  td=$short/t
  while [ ${#td} -lt $len ]; do [ $((${#td} % 60)) = 0 ] && td=$td/ || td=${td}d; done
  [ ${#td} = $len ] || { bad "TMPDIR of $len bytes: cannot make one from $short"; continue; }
  rm -rf "$nc/out" && mkdir -p "$td" && write_manifest "$tmp/td_jobs.txt" "$nc/m.json"
  TMPDIR=$td "$bake" batch "$nc/m.json" --no-cache >/dev/null 2>"$tmp/td.err"
  eq "TMPDIR of $len bytes: exit 0" "$?" 0
  same "TMPDIR of $len bytes: frusta_swc" "$ref/frusta_swc.meso" "$nc/out/frusta_swc.meso"
  eq "TMPDIR of $len bytes: the logs removed" "$(ls -A "$td")" ""
  rm -rf "$td"
done

# Option values are hashed as values, whatever they look like: --name -v,
# --name --verbose and --name --max-memory are three different bakes.
kv=$tmp/kv && mkdir -p "$kv" && cp "$orig/sphere.obj" "$kv/"
cat >"$kv/m.json" <<'JSON'
{"jobs": [
  {"name": "v", "command": "mesh", "input": "sphere.obj", "output": "v.meso", "args": ["--name", "-v"]},
  {"name": "verbose", "command": "mesh", "input": "sphere.obj", "output": "verbose.meso", "args": ["--name", "--verbose"]},
  {"name": "mm", "command": "mesh", "input": "sphere.obj", "output": "mm.meso", "args": ["--name", "--max-memory", "--draco"]}]}
JSON
"$bake" batch "$kv/m.json" --cache "$kv/cache" --report "$kv/r.json" >/dev/null 2>&1
eq "option values: three different bakes" "$(counts "$kv/r.json")" "3 baked 0 cached 0 failed"
(cd "$kv" && "$bake" mesh -i sphere.obj -o want_v.meso --name -v && "$bake" mesh -i sphere.obj -o want_mm.meso \
  --name --max-memory --draco) >/dev/null 2>&1
same "option values: --name -v" "$kv/want_v.meso" "$kv/v.meso"
same "option values: --name --max-memory --draco" "$kv/want_mm.meso" "$kv/mm.meso"

# A job whose bake cannot even start (its output's directory is a file)
# fails alone: the jobs after it still run, also when it took the only slot.
sf=$tmp/sf && mkdir -p "$sf" && cp "$orig/sphere.obj" "$sf/" && : >"$sf/afile"
cat >"$sf/m.json" <<'JSON'
{"jobs": [
  {"name": "nostart", "command": "mesh", "input": "sphere.obj", "output": "afile/x.meso"},
  {"name": "good1", "command": "mesh", "input": "sphere.obj", "output": "g1.meso"},
  {"name": "good2", "command": "mesh", "input": "sphere.obj", "output": "g2.meso", "args": ["--draco"]}]}
JSON
"$bake" batch "$sf/m.json" --no-cache -j 1 --report "$sf/r.json" >/dev/null 2>&1
eq "a job that cannot start: exit 6" "$?" 6
eq "a job that cannot start: the others run" "$(counts "$sf/r.json")" "2 baked 0 cached 1 failed"
eq "a job that cannot start: its exit code" "$(field "$sf/r.json" nostart exit_code)" 2

# An input saved while its bake runs: job 1 is keyed at the start, job 0 (a
# slow bake) runs first (-j 1), the test replaces p.obj as soon as job 0 has
# started; job 1 then bakes the new bytes, which must not be kept under the
# old bytes' key. Restoring p.obj must then bake again, not serve them.
mc=$tmp/mc && mkdir -p "$mc/tmp" && cp "$orig/spot_uv.obj" "$mc/" && cp "$orig/sphere.obj" "$mc/p.obj"
cat >"$mc/m.json" <<'JSON'
{"jobs": [
  {"name": "slow", "command": "shell", "input": "spot_uv.obj", "output": "slow.meso", "args": ["--texture", "bricks:256", "--tiling", "4", "--dist-res", "64x64x16"]},
  {"name": "p", "command": "mesh", "input": "p.obj", "output": "p.meso"}]}
JSON
TMPDIR=$mc/tmp "$bake" batch "$mc/m.json" --cache "$mc/cache" -j 1 --report "$mc/r1.json" >/dev/null 2>"$mc/err1" &
bpid=$!
i=0
while [ -z "$(find "$mc/tmp" -name 0.log 2>/dev/null)" ] && [ $i -lt 600 ]; do sleep 0.05; i=$((i + 1)); done
cp "$orig/torus.obj" "$mc/p.obj"
wait $bpid
eq "input changed mid-batch: exit 6" "$?" 6
eq "input changed mid-batch: job p failed" "$(field "$mc/r1.json" p status)" failed
has "input changed mid-batch: says why" "$mc/err1" "changed while it was baked"
cp "$orig/sphere.obj" "$mc/p.obj"
"$bake" batch "$mc/m.json" --cache "$mc/cache" -j 1 --report "$mc/r2.json" >/dev/null 2>&1
eq "input restored: p baked again, not served from the cache" "$(field "$mc/r2.json" p status)" baked
(cd "$mc" && "$bake" mesh -i p.obj -o want.meso) >/dev/null 2>&1
same "input restored: p's bytes" "$mc/want.meso" "$mc/p.meso"

exit $fail
