#!/usr/bin/env bash
# The Slurm job array of deploy/slurm/demcal-workers.sbatch, run for real on a one-node Slurm
# made for the test: a munge key (created when missing), munged, a slurm.conf for this host
# (2 CPUs, its own spool, state and log directories under a temporary directory), slurmctld and
# slurmd; a demcal-server on loopback with a tiny packing campaign (4 jobs of 150 particles);
# the sbatch script submitted as an array of two one-CPU workers; the campaign awaited (bounded);
# every job checked done, with metrics, by a worker of the array. Everything started is stopped
# and the directory removed on any exit (trap); logs are kept and printed on failure.
#   deploy/slurm/local-test.sh [BUILD_DIR]      (ctest: slurm_local, label slurm)
# Needs Debian's slurm-wlm and munge (scripts/setup) and root (slurmd starts job steps as the
# submitting user, which needs root unless everything runs as that one user: here, root).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=$(cd "${1:-$root/build}" && pwd)
TIMEOUT=${SLURM_TEST_TIMEOUT:-100}  # seconds for the campaign, once the array is submitted
TMP=$(mktemp -d /tmp/demcal-slurm.XXXXXX)
pids=()
failed=1

fail() {
  echo "slurm local test: $*" >&2
  exit 1
}

# Stops process $1: SIGTERM, then SIGKILL if it is still there after 5 s.
stop() {
  kill "$1" 2> /dev/null || return 0
  for ((t = 0; t < 25; ++t)); do
    kill -0 "$1" 2> /dev/null || return 0
    sleep 0.2
  done
  kill -9 "$1" 2> /dev/null || true
}

teardown() {
  # The array first, while slurmctld and slurmd can still end its steps (a worker otherwise
  # waits for work until its --idle-exit).
  if [ -n "${job:-}" ]; then
    scancel "$job" 2> /dev/null || true
    for ((t = 0; t < 100; ++t)); do
      [ -z "$(squeue -h -j "$job" 2> /dev/null)" ] && break
      sleep 0.2
    done
  fi
  for ((i = ${#pids[@]} - 1; i >= 0; --i)); do stop "${pids[i]}"; done
  if ((failed)); then
    for log in "$TMP"/log/*; do
      [ -f "$log" ] && { echo "--- $log" >&2; tail -n 30 "$log" >&2; }
    done
  fi
  rm -rf "$TMP"
}
trap teardown EXIT

# Polls `$@` every 0.2 s for up to $1 seconds (first argument); false when it never succeeded.
wait_for() {
  local seconds=$1
  shift
  for ((t = 0; t < seconds * 5; ++t)); do
    "$@" > /dev/null 2>&1 && return 0
    sleep 0.2
  done
  return 1
}

# A free TCP port on loopback (bound and released; Slurm's daemons bind it right after).
free_port() { python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }

for tool in munged mungekey slurmctld slurmd sbatch sinfo squeue scancel python3; do
  command -v "$tool" > /dev/null || fail "$tool is missing: run scripts/setup (Debian's slurm-wlm and munge)"
done
[ "$(id -u)" -eq 0 ] || fail "needs root: slurmd runs job steps as the submitting user"
for bin in server/demcal-server worker/demcal-worker client/demcal; do
  [ -x "$BUILD/$bin" ] || fail "$BUILD/$bin is missing: build first"
done
mkdir -p "$TMP"/{log,munge,state,spool,home/.demcal,db}
chmod 700 "$TMP/munge"

# munge: Slurm's authentication between slurmctld, slurmd and the commands. A key of its own
# (DEMCAL_MUNGE_KEY may name a kept one; created when missing), a socket of its own.
key=${DEMCAL_MUNGE_KEY:-$TMP/munge/munge.key}
[ -f "$key" ] || mungekey --create --keyfile="$key"
socket=$TMP/munge/munge.socket
munged --force --key-file="$key" --socket="$socket" --pid-file="$TMP/munge/munged.pid" \
  --seed-file="$TMP/munge/munged.seed" --log-file="$TMP/log/munged.log"
pids+=("$(cat "$TMP/munge/munged.pid")")
wait_for 10 test -S "$socket" || fail "munged did not start (log/munged.log)"

# slurm.conf: one node, this host under its short name on loopback, 2 CPUs.
node=$(hostname -s)
export SLURM_CONF=$TMP/slurm.conf
cat > "$SLURM_CONF" << CONF
ClusterName=demcal-local
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
SlurmUser=$(id -un)
SlurmdUser=$(id -un)
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
StateSaveLocation=$TMP/state
SlurmdSpoolDir=$TMP/spool
SlurmctldPidFile=$TMP/slurmctld.pid
SlurmdPidFile=$TMP/slurmd.pid
SlurmctldLogFile=$TMP/log/slurmctld.log
SlurmdLogFile=$TMP/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
SchedulerParameters=sched_interval=1
NodeName=$node NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN
PartitionName=local Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld -D -i > "$TMP/log/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -N "$node" > "$TMP/log/slurmd.out" 2>&1 &
pids+=($!)
node_idle() { [ "$(sinfo -h -n "$node" -o %t 2> /dev/null)" = idle ]; }
wait_for 30 node_idle || fail "node $node did not become idle: $(sinfo -h -N -o '%N %t %E' 2>&1)"

# The coordinator, a token of its own, the tiny campaign.
token=$(head -c 16 /dev/urandom | od -An -tx1 | tr -d ' \n')
printf '%s\n' "$token" > "$TMP/home/.demcal/token"
chmod 600 "$TMP/home/.demcal/token"
"$BUILD/server/demcal-server" --listen 127.0.0.1:0 --db "$TMP/db/c.db" --token-file \
  "$TMP/home/.demcal/token" --port-file "$TMP/port" > "$TMP/log/demcal-server.log" 2>&1 &
pids+=($!)
wait_for 20 test -s "$TMP/port" || fail "demcal-server did not start"
coordinator=127.0.0.1:$(cat "$TMP/port")
cat > "$TMP/tiny.yaml" << 'SPEC'
name: slurm-tiny
material:
  particle_law:
    normal: {model: hertz, youngs_modulus: 2.0e6, restitution: 0.3}
    tangential: {model: history, mu_s: 0.3}
  sizes: {monodisperse: {radius: 0.0005}}
  density: 2500
tests:
  - test: packing
    settings: {particles: 150}
factors:
  - {path: particle_law.tangential.mu_s, low: 0.1, high: 0.5}
  - {path: particle_law.normal.restitution, low: 0.2, high: 0.6}
design: {type: full_factorial, centre_points: 0}
SPEC
cli() { "$BUILD/client/demcal" "$@" --coordinator "$coordinator" --token-file "$TMP/home/.demcal/token"; }
id=$(cli submit "$TMP/tiny.yaml" | sed -n 's/^campaign \([0-9]*\) submitted$/\1/p')
[ -n "$id" ] || fail "the campaign was not submitted"

# The array as a user submits it (two one-CPU workers on the two CPUs); the script finds
# demcal-worker on PATH and the token under HOME, both passed to the job by sbatch.
job=$(cd "$TMP" && HOME=$TMP/home PATH="$BUILD/worker:$PATH" \
  sbatch --parsable --array=1-2 --cpus-per-task=1 --output="$TMP/log/worker-%A_%a.log" \
  "$root/deploy/slurm/demcal-workers.sbatch" "$coordinator")
[ -n "$job" ] || fail "sbatch returned no job id"
campaign_over() { [ "$(cli status "$id" --format json | python3 -c 'import json, sys; print(json.load(sys.stdin)["state"])')" != RUNNING ]; }
wait_for "$TIMEOUT" campaign_over ||
  fail "campaign $id still running after $TIMEOUT s: $(squeue -h -o '%i %T %R' 2>&1 | tr '\n' ';')"

# Every job done, with metrics, by a worker of this array.
cli status "$id" --jobs --format json > "$TMP/status.json"
python3 - "$TMP/status.json" "$job" << 'PY'
import json, sys
doc, array = json.load(open(sys.argv[1])), sys.argv[2]
jobs = doc.get("jobs", [])
bad = [j for j in jobs if j.get("state") != "done" or not j.get("metrics")
       or not j.get("worker", "").startswith("slurm-" + array + "-")]
print(f"slurm local test: campaign {doc['id']} {doc['state']}, {len(jobs)} jobs, "
      f"workers {sorted({j.get('worker') for j in jobs})}")
if len(jobs) != 4 or bad:
    sys.exit(f"slurm local test: expected 4 jobs done by array {array}, not: {bad or jobs}")
PY
failed=0
echo "slurm local test: passed"
