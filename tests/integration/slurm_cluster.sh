#!/bin/sh
# slurm_cluster.sh CLUSTER_SH — tools/slurm/cluster.sh, the private one-node
# Slurm cluster that the batch tests, the benchmark and CI start (issue 17):
# two clusters run side by side without a clash (own munged, own ports), a job
# array with a throttle runs every listed task on the right cluster,
# `sbatch --wait` exits non-zero when one task exits 3, `scontrol show job -o`
# tells each task's exit code without accounting, and stop leaves no daemon.
# Fails (not skips) unless root with slurmctld slurmd slurm-client munge: CI runs
# as root after .ci/install-deps, and a skipped test would hide a missing install.
set -u

CL=$1

. "$(dirname "$0")/check_lib.sh" # $T, run, expect_*, fail, ok

if [ "$(id -u)" -ne 0 ] || ! command -v slurmctld >/dev/null 2>&1 ||
   ! command -v munged >/dev/null 2>&1 || ! command -v sbatch >/dev/null 2>&1; then
    echo "FAIL: needs root and slurmctld slurmd slurm-client munge (sh .ci/install-deps as root)" >&2
    exit 1
fi

A=$T/a
B=$T/b
trap '"$CL" stop "$A" >/dev/null 2>&1; "$CL" stop "$B" >/dev/null 2>&1; rm -rf "$T"' EXIT

# pids DIR: the daemons' pids, read before stop removes the pid files.
pids() { cat "$1/slurmd.pid" "$1/slurmctld.pid" "$1/munge/munged.pid" 2>/dev/null; }

run "$CL" start "$A"
expect_rc 0 "start A"
expect_out "^export SLURM_CONF=$A/slurm.conf\$" "start A prints the SLURM_CONF line"
run "$CL" start "$B"
expect_rc 0 "start B beside A"
expect_out "^export SLURM_CONF=$B/slurm.conf\$" "start B prints the SLURM_CONF line"
run "$CL" start "$A"
expect_rc 1 "a second start in A"
expect_err 'already runs' "a second start in A is refused"
pa=$(grep '^SlurmctldPort=' "$A/slurm.conf")
pb=$(grep '^SlurmctldPort=' "$B/slurm.conf")
[ "$pa" != "$pb" ] && ok || fail "A and B share $pa"

cat >"$T/job.sh" <<'EOF'
#!/bin/sh
echo "$SLURM_CONF $SLURM_CPUS_PER_TASK" >"$OUT/task.$SLURM_ARRAY_TASK_ID"
[ "$SLURM_ARRAY_TASK_ID" = "${FAIL_TASK-}" ] && exit 3
exit 0
EOF
chmod +x "$T/job.sh"

for d in "$A" "$B"; do
    mkdir "$d/out"
    run env OUT="$d/out" SLURM_CONF="$d/slurm.conf" sbatch --wait --parsable -c 1 --array=0,2,5%2 \
        -o "$d/log.%a" "$T/job.sh"
    expect_rc 0 "array in $d"
    for i in 0 2 5; do
        expect_eq "$(cat "$d/out/task.$i" 2>/dev/null)" "$d/slurm.conf 1" "task $i ran in $d with 1 CPU"
    done
    expect_eq "$(ls "$d/out" | wc -l)" 3 "only the listed tasks ran in $d"
done

run env OUT="$A/out" FAIL_TASK=2 SLURM_CONF="$A/slurm.conf" sbatch --wait --parsable --array=0-2 \
    -o "$A/log.%a" "$T/job.sh"
expect_rc 3 "sbatch --wait exits with the failed task's code"
job=$(cat "$T/out")
codes=$(SLURM_CONF=$A/slurm.conf scontrol show job -o "$job" |
    sed -n 's/.* ArrayTaskId=\([0-9]*\) .* ExitCode=\([0-9:]*\) .*/\1=\2/p' | sort | tr '\n' ' ')
expect_eq "$codes" "0=0:0 1=0:0 2=3:0 " "per-task exit codes from scontrol show job -o"

all="$(pids "$A") $(pids "$B")"
run "$CL" stop "$A"
expect_rc 0 "stop A"
run "$CL" stop "$B"
expect_rc 0 "stop B"
for p in $all; do
    st=$(sed 's/^.*) //' "/proc/$p/stat" 2>/dev/null | cut -d' ' -f1)
    [ -z "$st" ] || [ "$st" = Z ] && ok || fail "daemon $p still runs after stop"
done
run "$CL" stop "$A"
expect_rc 0 "stop of a stopped cluster"

echo "$checks checks passed, $failures failed"
[ $failures -eq 0 ]
