#!/bin/sh
# batch_slurm.sh MESOBAKE CLUSTER_SH DATA — `mesobake batch --engine slurm`
# (issue 17) on a private one-node Slurm cluster started from the repo's own
# script (tools/slurm/cluster.sh: munged, slurmctld, slurmd, stopped by their
# pids): the uncached jobs go out as one job array and come back through the
# cache byte-identical to the single-command bakes; a resubmission is all
# cache hits and submits nothing; a job with a bad input fails by name after
# one attempt, one that failed for another reason (exit 2) is retried
# --retries times, and the others complete; without sbatch the engine is
# refused (exit 5) while a fully cached batch still needs no Slurm. On a
# second start of the cluster with MaxArraySize=4, a batch of 8 uncached jobs
# goes out as 3 arrays (at most 3 tasks each) through an `sbatch` that says
# something on stderr before the job id, into a cache whose path holds '%'
# (a Slurm filename pattern character): the outputs are byte-identical and
# the failed task's log is where the error says; and when sbatch returns
# while the tasks still run, they are waited for in the queue, not resubmitted.
# Fails (not skips) unless root with slurmctld slurmd slurm-client munge.
set -u
abs() { case $1 in /*) echo "$1" ;; *) echo "$PWD/$1" ;; esac; }
B=$(abs "$1") CL=$(abs "$2") DATA=$(abs "$3")

. "$(dirname "$0")/check_lib.sh" # $T, run, expect_*, fail, ok

if [ "$(id -u)" -ne 0 ] || ! command -v sbatch >/dev/null 2>&1 || ! command -v slurmctld >/dev/null 2>&1; then
    echo "FAIL: needs root and slurmctld slurmd slurm-client munge (sh .ci/install-deps as root)" >&2
    exit 1
fi
trap '"$CL" stop "$T/cluster" >/dev/null 2>&1; rm -rf "$T"' EXIT

# field REPORT NAME: a top-level number of a batch report.
field() { sed -n "s/^\t\"$2\":\t\\([0-9.e+-]*\\),*\$/\\1/p" "$1" | head -n 1; }
# job_field REPORT JOBNAME FIELD: a field of one job's entry (3 tabs deep).
job_field() {
    awk -v want="$2" -v f="$3" -F'\t' '
        /^\t\t\t"name":/ { name = $NF; gsub(/[",]/, "", name) }
        $0 ~ "^\t\t\t\"" f "\":" && name == want { v = $NF; gsub(/[",]/, "", v); print v; exit }' "$1"
}

mkdir "$T/w" && cd "$T/w" || exit 1 # ($T/out and $T/err are check_lib's)
mkdir data
for f in torus.obj sphere.obj spot_uv.obj saguaro.skel neurom_simple.swc; do cp "$DATA/$f" data/ || exit 1; done

# The single-command bakes the batch must reproduce byte for byte.
mkdir ref
"$B" mesh -i data/torus.obj -o ref/mesh.meso &&
"$B" mesh -i data/torus.obj -o ref/draco.meso --draco &&
"$B" shell -i data/spot_uv.obj -o ref/bricks.meso --texture bricks:64 --tiling 4 &&
"$B" shell -i data/sphere.obj -o ref/sphere.meso &&
"$B" cells -i data/torus.obj -o ref/cells.meso --tiles 4 --tile-res 16 &&
"$B" frusta -i data/saguaro.skel -o ref/relief.meso --relief bricks:64 &&
"$B" frusta -i data/neurom_simple.swc -o ref/neuron.meso || { echo "FAIL: a reference bake failed" >&2; exit 1; }

cat >good.json <<'JSON'
{"jobs": [
  {"name": "mesh", "command": "mesh", "input": "data/torus.obj", "output": "out/mesh.meso"},
  {"name": "draco", "command": "mesh", "input": "data/torus.obj", "output": "out/draco.meso", "args": ["--draco"]},
  {"name": "bricks", "command": "shell", "input": "data/spot_uv.obj", "output": "out/bricks.meso",
   "args": ["--texture", "bricks:64", "--tiling", "4"]},
  {"name": "cells", "command": "cells", "input": "data/torus.obj", "output": "out/cells.meso",
   "args": ["--tiles", "4", "--tile-res", "16"]},
  {"name": "relief", "command": "frusta", "input": "data/saguaro.skel", "output": "out/relief.meso",
   "args": ["--relief", "bricks:64"]},
  {"name": "neuron", "command": "frusta", "input": "data/neurom_simple.swc", "output": "out/neuron.meso"},
  {"name": "mesh-again", "command": "mesh", "input": "data/torus.obj", "output": "out/mesh-again.meso"}
]}
JSON

run "$CL" start "$T/cluster"
expect_rc 0 "cluster.sh start"
[ "$rc" -eq 0 ] || exit 1
eval "$(cat "$T/out")"
export SLURM_CONF

# An sbatch that records its arguments in sbatch.calls; while the file
# chatter exists it says something on stderr before the job id (as a site's
# job_submit plugin may): the engine must still see the array submitted;
# while nowait exists it drops --wait and returns at once, as an sbatch killed
# while the tasks run would: the engine must wait for them in the queue.
mkdir bin
REAL_SBATCH=$(command -v sbatch) WRAP_DIR=$PWD
export REAL_SBATCH WRAP_DIR
cat >bin/sbatch <<'EOF'
#!/bin/sh
echo "$*" >>"$WRAP_DIR/sbatch.calls"
[ ! -e "$WRAP_DIR/chatter" ] || echo "NOTICE: job_submit: your jobs are welcome" >&2
if [ -e "$WRAP_DIR/nowait" ]; then
    for a; do shift; [ "$a" = --wait ] || set -- "$@" "$a"; done
fi
exec "$REAL_SBATCH" "$@"
EOF
chmod +x bin/sbatch
PATH_WRAPPED="$PWD/bin:$PATH"

# 1. Everything uncached goes out as one array and comes back byte-identical,
#    though sbatch wrote to stderr before the job id.
touch chatter
run env PATH="$PATH_WRAPPED" "$B" batch good.json --engine slurm --cache cache --max-parallel 2 --report r1.json
rm chatter
expect_rc 0 "slurm batch (sbatch with a notice on stderr)"
expect_eq "$(grep -c -- --array=0-5%2 sbatch.calls)" 1 "one array of the 6 uncached jobs"
expect_eq "$(field r1.json jobs_baked)/$(field r1.json jobs_cached)/$(field r1.json jobs_failed)" "6/1/0" \
    "baked/cached/failed (mesh-again has mesh's key: copied, not baked twice)"
for f in mesh draco bricks cells relief neuron; do
    same_bytes "out/$f.meso" "ref/$f.meso" "slurm output $f equals the single command's"
done
same_bytes out/mesh-again.meso ref/mesh.meso "the duplicate job's output"
expect_eq "$(job_field r1.json bricks attempts)" 1 "one attempt for a job that succeeded"
[ -e cache/slurm ] && fail "the work directory (and cache/slurm) is removed after a batch without failures" || ok

# 2. Resubmitted: all cache hits, nothing submitted (no attempts), outputs untouched.
touch -d '2001-01-01' out/bricks.meso
run "$B" batch good.json --engine slurm --cache cache --report r2.json
expect_rc 0 "resubmission"
expect_eq "$(field r2.json jobs_baked)/$(field r2.json jobs_cached)" "0/7" "resubmission: all cached"
expect_eq "$(job_field r2.json bricks attempts)" 0 "nothing submitted for a cached job"
expect_eq "$(date -r out/bricks.meso +%Y)" 2001 "an output already holding the bytes is not rewritten"

# 3. Without sbatch: a fully cached batch still works, an uncached one is refused (exit 5).
run env PATH=/nonexistent "$B" batch good.json --engine slurm --cache cache
expect_rc 0 "all cached: no Slurm needed"
run env PATH=/nonexistent "$B" batch good.json --engine slurm --cache cache2
expect_rc 5 "uncached jobs without sbatch"
expect_err "needs Slurm's sbatch" "the message says what is missing"

# 4. Failures: bad input fails once, an I/O failure (a missing file, exit 2)
#    is retried, the good job completes; the cache's path holds '%' (a Slurm
#    filename pattern character) and the logs are where the errors say.
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n' >data/bad.obj
cat >bad.json <<'JSON'
{"jobs": [
  {"name": "sphere", "command": "shell", "input": "data/sphere.obj", "output": "out2/sphere.meso"},
  {"name": "invalid", "command": "mesh", "input": "data/bad.obj", "output": "out2/invalid.meso"},
  {"name": "missing", "command": "mesh", "input": "data/missing.obj", "output": "out2/missing.meso"}
]}
JSON
run "$B" batch bad.json --engine slurm --cache 'c%a%%j%x' --retries 1 --report r3.json
expect_rc 6 "a batch with failed jobs exits 6"
same_bytes out2/sphere.meso ref/sphere.meso "the good job completes beside the failures"
expect_eq "$(field r3.json jobs_baked)/$(field r3.json jobs_failed)" "1/2" "baked/failed"
expect_eq "$(job_field r3.json invalid exit_code)/$(job_field r3.json invalid attempts)" "3/1" \
    "invalid input: exit 3, not retried"
expect_eq "$(job_field r3.json missing exit_code)/$(job_field r3.json missing attempts)" "2/2" \
    "I/O failure: exit 2, retried once (--retries 1)"
expect_err "FAILED invalid \\(exit 3\\): .*E32" "stderr names the failed job and its code"
[ -e out2/invalid.meso ] && fail "a failed job wrote its output" || ok
log=$(job_field r3.json invalid error | sed -n 's/.*(log: \(.*\))$/\1/p')
[ -n "$log" ] && [ -f "$log" ] && ok || fail "the failed task's log is kept and named ($log)"
case $log in "$PWD/c%a%%j%x/slurm/"*) ok ;; *) fail "the log is in the cache whose path holds '%' ($log)" ;; esac
grep -q "job 1 exit 3" "$log" && ok || fail "the log at the literal '%' path is the task's ($log)"

# 5. MaxArraySize=4: arrays of at most 3 tasks, submitted side by side.
"$CL" stop "$T/cluster" >/dev/null 2>&1 || fail "cluster.sh stop"
run env MESO_SLURM_MAX_ARRAY_SIZE=4 "$CL" start "$T/cluster"
expect_rc 0 "cluster.sh start with MESO_SLURM_MAX_ARRAY_SIZE=4"
[ "$rc" -eq 0 ] || exit 1
eval "$(cat "$T/out")"
expect_eq "$(scontrol show config | sed -n 's/^MaxArraySize *= *//p')" 4 "MaxArraySize set from the environment"
{ sed '$d' good.json | sed '$s/$/,/'
  cat <<'JSON'
  {"name": "sphere", "command": "shell", "input": "data/sphere.obj", "output": "out/sphere.meso"},
  {"name": "invalid", "command": "mesh", "input": "data/bad.obj", "output": "out/invalid.meso"}
]}
JSON
} >big.json
rm -rf out sbatch.calls
run env PATH="$PATH_WRAPPED" "$B" batch big.json --engine slurm --cache cache3 --max-parallel 4 --report r5.json
expect_rc 6 "8 uncached jobs, one invalid, MaxArraySize 4"
expect_eq "$(field r5.json jobs_baked)/$(field r5.json jobs_cached)/$(field r5.json jobs_failed)" "7/1/1" \
    "chunked: baked/cached/failed"
for f in mesh draco bricks cells relief neuron sphere; do
    same_bytes "out/$f.meso" "ref/$f.meso" "chunked slurm output $f equals the single command's"
done
expect_eq "$(grep -c -- --array= sbatch.calls)" 3 "8 uncached jobs went out as 3 arrays"
expect_eq "$(grep -o -- '--array=[^ ]*' sbatch.calls | sort | tr '\n' ' ')" \
    "--array=0-1%1 --array=0-2%1 --array=0-2%2 " "3+3+2 tasks, --max-parallel 4 shared out as 2+1+1"
expect_eq "$(ls cache3/slurm/*/attempt1.c*.jobs | wc -l)" 3 "one job list per array"
expect_eq "$(cat cache3/slurm/*/attempt1.c*.jobs | grep -cvE '^[0-9]+ [0-9a-f]{64}$')/$(cat cache3/slurm/*/attempt1.c*.jobs | wc -l)" \
    0/8 "the job lists hold lines INDEX KEY (the task passes --expect-key KEY)"
log=$(job_field r5.json invalid error | sed -n 's/.*(log: \(.*\))$/\1/p')
[ -f "$log" ] && grep -q "exit 3" "$log" && ok || fail "the failed task's log in a chunk is named ($log)"

# 6. sbatch returns while the tasks still run: waited for in the queue, not
#    judged failed, not submitted again.
touch nowait
run env PATH="$PATH_WRAPPED" "$B" batch bad.json --engine slurm --cache cache4 --retries 2 --report r6.json
rm nowait
expect_eq "$(job_field r6.json sphere attempts)/$(job_field r6.json invalid attempts)" "1/1" \
    "sbatch gone early: the tasks are waited for, not resubmitted"
expect_eq "$(field r6.json jobs_baked)/$(job_field r6.json invalid exit_code)" "1/3" \
    "sbatch gone early: judged by the tasks' own results"
same_bytes out2/sphere.meso ref/sphere.meso "sbatch gone early: the good job's output"

"$CL" stop "$T/cluster" >/dev/null 2>&1 || fail "cluster.sh stop"
echo "batch_slurm: $checks checks, $failures failures"
[ "$failures" -eq 0 ]
