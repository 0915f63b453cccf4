#!/bin/sh
# cluster.sh — a private one-node Slurm cluster for tests, benchmarks and CI
# (the scale-out recipe of shared/notes/scale-out.md, made safe to run twice).
#
#   cluster.sh start DIR   start munged, slurmctld and slurmd with every file in
#                          DIR; wait until the node is idle; print
#                          "export SLURM_CONF=DIR/slurm.conf" and exit 0.
#                          Use: eval "$(tools/slurm/cluster.sh start "$D")"
#   cluster.sh stop DIR    cancel the cluster's jobs, stop its daemons by the
#                          pids in DIR's pid files, wait until they are gone.
#                          Already-dead daemons and a missing DIR are fine.
#
# Nothing is shared with a system munged/Slurm or with another cluster.sh
# cluster: the munge key, socket, pid, log and seed files are in DIR/munge, the
# two TCP ports are picked free at start, and the state and spool directories
# are DIR/state and DIR/spool (wiped at each start). DIR stays after stop (logs).
# Needs root (slurmd launches jobs; SlurmUser=root) and Debian 12's
# slurmctld slurmd slurm-client munge (Slurm 22.05). No systemd needed.
# No accounting: read per-task exit codes with `scontrol show job -o JOBID`
# soon after `sbatch --wait` returns: finished records are purged MinJobAge
# (MESO_SLURM_MIN_JOB_AGE, default 4 s) and a few seconds more after the end.
# MESO_SLURM_MAX_ARRAY_SIZE sets MaxArraySize (default 100001; arrays then hold
# indices 0..N-1), small to test how a client splits a large array.
set -eu

me=cluster.sh
die() { echo "$me: $*" >&2; exit 1; }
usage() { echo "usage: $me start DIR | $me stop DIR" >&2; exit 2; }

[ $# -eq 2 ] || usage
cmd=$1
DIR=$2

# pid_alive PID NAME: PID runs the executable NAME (not a zombie, not a reused pid).
pid_alive() {
  [ -n "$1" ] && [ -r "/proc/$1/stat" ] || return 1
  case $(readlink "/proc/$1/exe" 2>/dev/null) in
    */"$2" | */"$2"-*) ;;  # Debian: /usr/sbin/slurmd -> slurmd-wlm
    *) return 1 ;;
  esac
  # Field 3 of /proc/PID/stat is the state; a zombie is dead but still kill -0-able.
  st=$(sed 's/^.*) //' "/proc/$1/stat" 2>/dev/null | cut -d' ' -f1) || return 1
  [ "$st" != Z ]
}

# stop_daemon PIDFILE NAME: TERM, wait up to 15 s, then KILL and wait up to 5 s.
stop_daemon() {
  [ -f "$1" ] || return 0
  pid=$(cat "$1" 2>/dev/null || true)
  pid_alive "$pid" "$2" || { rm -f "$1"; return 0; }
  kill -TERM "$pid" 2>/dev/null || true
  i=0
  while pid_alive "$pid" "$2"; do
    i=$((i + 1))
    if [ $i -eq 150 ]; then
      echo "$me: $2 ($pid) ignored SIGTERM for 15 s; sending SIGKILL" >&2
      kill -KILL "$pid" 2>/dev/null || true
    fi
    [ $i -lt 200 ] || { echo "$me: $2 ($pid) will not die" >&2; return 1; }
    sleep 0.1
  done
  rm -f "$1"
}

do_stop() {
  [ -d "$DIR" ] || return 0
  rc=0
  if [ -f "$DIR/slurm.conf" ] && [ -f "$DIR/slurmctld.pid" ] &&
     pid_alive "$(cat "$DIR/slurmctld.pid" 2>/dev/null)" slurmctld; then
    # Jobs still running would leave slurmstepd processes behind slurmd.
    SLURM_CONF=$DIR/slurm.conf scancel --quiet --user=root >/dev/null 2>&1 || true
    i=0
    while [ $i -lt 100 ] && [ -n "$(SLURM_CONF=$DIR/slurm.conf squeue -h -t running,completing -o %i 2>/dev/null)" ]; do
      i=$((i + 1)); sleep 0.1
    done
  fi
  stop_daemon "$DIR/slurmd.pid" slurmd || rc=1
  stop_daemon "$DIR/slurmctld.pid" slurmctld || rc=1
  stop_daemon "$DIR/munge/munged.pid" munged || rc=1
  return $rc
}

# port_free PORT: nothing listens on PORT (IPv4 or IPv6).
port_free() {
  hex=$(printf '%04X' "$1")
  ! cat /proc/net/tcp /proc/net/tcp6 2>/dev/null |
    awk -v p=":$hex" 'substr($2, length($2) - 4) == p && $4 == "0A" { f = 1 } END { exit !f }'
}

# Prints the log tails, stops what started, exits 1. Never writes to stdout.
fail() {
  echo "$me: $*" >&2
  for f in "$DIR/munge/munged.log" "$DIR/log/slurmctld.log" "$DIR/log/slurmd.log" \
           "$DIR/log/munged.out" "$DIR/log/slurmctld.out" "$DIR/log/slurmd.out"; do
    [ -s "$f" ] || continue
    echo "==> $f <==" >&2
    tail -n 15 "$f" >&2
  done
  do_stop >&2 || true
  exit 1
}

do_start() {
  [ "$(id -u)" -eq 0 ] || die "must run as root (slurmd starts the jobs; SlurmUser=root)"
  for b in munged mungekey munge slurmctld slurmd sinfo scancel squeue; do
    command -v "$b" >/dev/null 2>&1 ||
      die "$b not found; install Debian's slurmctld slurmd slurm-client munge (.ci/install-deps)"
  done
  mkdir -p "$DIR"
  DIR=$(cd "$DIR" && pwd -P)
  case $DIR in
    *[!A-Za-z0-9._/+-]*) die "DIR '$DIR' has characters slurm.conf cannot hold" ;;
  esac
  for p in "$DIR/slurmd.pid:slurmd" "$DIR/slurmctld.pid:slurmctld" "$DIR/munge/munged.pid:munged"; do
    f=${p%:*}
    [ -f "$f" ] && pid_alive "$(cat "$f" 2>/dev/null)" "${p##*:}" &&
      die "a cluster already runs in $DIR ($f); run '$me stop $DIR' first"
  done

  rm -rf "$DIR/state" "$DIR/spool" "$DIR/log" "$DIR/munge"
  mkdir -p "$DIR/state" "$DIR/spool" "$DIR/log" "$DIR/munge"
  chmod 700 "$DIR/munge"

  # slurmctld accepts SlurmctldHost only if it is its own short host name.
  host=$(uname -n)
  host=${host%%.*}
  cpus=$(nproc)
  # Two consecutive free ports, starting from a place derived from our pid so
  # that clusters started at the same time look in different places.
  port=$((20000 + ($$ * 37 % 5000) * 2))
  tries=0
  until port_free $port && port_free $((port + 1)); do
    tries=$((tries + 1))
    [ $tries -lt 200 ] || die "no two free consecutive TCP ports near $port"
    port=$((port + 2))
    [ $port -lt 30000 ] || port=20000
  done

  min_job_age=${MESO_SLURM_MIN_JOB_AGE:-4}
  case $min_job_age in
    '' | *[!0-9]*) die "MESO_SLURM_MIN_JOB_AGE must be a number of seconds (2..65533)" ;;
  esac
  max_array_size=${MESO_SLURM_MAX_ARRAY_SIZE:-100001}
  case $max_array_size in
    '' | *[!0-9]*) die "MESO_SLURM_MAX_ARRAY_SIZE must be a number (1..4000001)" ;;
  esac
  mungekey --create --keyfile="$DIR/munge/munge.key" >/dev/null 2>&1 ||
    fail "mungekey could not create $DIR/munge/munge.key"
  cat >"$DIR/slurm.conf" <<EOF
# Written by tools/slurm/cluster.sh: a private one-node cluster; every file is in $DIR.
ClusterName=meso
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
AuthInfo=socket=$DIR/munge/munged.sock
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0,sched_interval=1
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
# sbatch --wait polls every 2 s only while MinJobAge <= 4 (it backs off to
# 8 and 32 s otherwise); finished job records then last only seconds.
MinJobAge=$min_job_age
MaxJobCount=200000
MaxArraySize=$max_array_size
KillWait=5
SlurmctldPidFile=$DIR/slurmctld.pid
SlurmdPidFile=$DIR/slurmd.pid
SlurmdSpoolDir=$DIR/spool
StateSaveLocation=$DIR/state
SlurmctldLogFile=$DIR/log/slurmctld.log
SlurmdLogFile=$DIR/log/slurmd.log
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=main Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
  SLURM_CONF=$DIR/slurm.conf
  export SLURM_CONF

  # munged insists that every directory above its socket is searchable by all;
  # --force turns that (e.g. a 0700 mktemp -d) into a warning in its log.
  munged --force --socket="$DIR/munge/munged.sock" --key-file="$DIR/munge/munge.key" \
    --pid-file="$DIR/munge/munged.pid" --log-file="$DIR/munge/munged.log" \
    --seed-file="$DIR/munge/munged.seed" </dev/null >"$DIR/log/munged.out" 2>&1 ||
    fail "munged did not start"
  i=0
  until munge -n -S "$DIR/munge/munged.sock" 2>/dev/null | unmunge -S "$DIR/munge/munged.sock" >/dev/null 2>&1; do
    i=$((i + 1)); [ $i -lt 100 ] || fail "munged does not answer on $DIR/munge/munged.sock"
    sleep 0.1
  done

  # The daemons fork away from us; their stdio must not hold our stdout (eval "$(...)").
  slurmctld -f "$SLURM_CONF" </dev/null >"$DIR/log/slurmctld.out" 2>&1 || fail "slurmctld did not start"
  slurmd -f "$SLURM_CONF" -N "$host" </dev/null >"$DIR/log/slurmd.out" 2>&1 || fail "slurmd did not start"

  i=0
  while :; do
    state=$(sinfo -h -N -n "$host" -o %t 2>/dev/null || true)
    [ "$state" = idle ] && break
    i=$((i + 1)); [ $i -lt 300 ] || fail "node $host not idle after 30 s (state '$state')"
    # After 2 s both pid files must name a live daemon.
    [ $i -lt 20 ] || for p in "$DIR/slurmctld.pid:slurmctld" "$DIR/slurmd.pid:slurmd"; do
      pid_alive "$(cat "${p%:*}" 2>/dev/null)" "${p##*:}" || fail "${p##*:} died while starting"
    done
    sleep 0.1
  done
  echo "export SLURM_CONF=$DIR/slurm.conf"
}

case $cmd in
  start) do_start ;;
  stop) do_stop ;;
  *) usage ;;
esac
