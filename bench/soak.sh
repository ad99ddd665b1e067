#!/usr/bin/env bash
# Chaos soak: a campaign of small simulations run twice against a real coordinator with real
# workers on loopback: once undisturbed, once while a chaos loop SIGKILLs workers (restarted by
# their supervisor loops) and the coordinator (restarted on the same port and file) at random
# moments. Prints jobs, results, duplicates, lost, attempts, the kills, and whether the effect
# tables of the two runs are bitwise equal. Fails on a duplicate, a lost job, unequal tables, a
# job over the attempt cap (MAX_ATTEMPTS), or attempts the kills do not explain (beyond one per
# job, at most one per worker kill and one per worker for each coordinator kill).
#   bench/soak.sh [BUILD_DIR] [WORKER_KILLS] [COORDINATOR_KILLS] [REPLICATES]
# Defaults: 20 worker kills, 3 coordinator kills, 4 replicates (100 jobs: 4 runs + 21 centre
# points, x 4). SOAK_SHORT=1: 8 worker kills, 1 coordinator kill, 1 replicate (25 jobs).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$root/build}
if [ "${SOAK_SHORT:-0}" = 1 ]; then WK=${2:-8}; CK=${3:-1}; REPL=${4:-1}; else
  WK=${2:-20}; CK=${3:-3}; REPL=${4:-4}; fi
SERVER=$BUILD/server/demcal-server WORKER=$BUILD/worker/demcal-worker CLI=$BUILD/client/demcal
for b in "$SERVER" "$WORKER" "$CLI"; do [ -x "$b" ] || { echo "no $b" >&2; exit 1; }; done
# Leases per job before it fails (the coordinator's --max-attempts), and the supervised workers.
MAX_ATTEMPTS=5 WORKERS=4
TMP=$(mktemp -d)
# Every process is ended by its id: the coordinator's in SERVER_PID, each worker's in its pid file.
cleanup() {
  touch "$TMP"/*/stop 2>/dev/null || true
  for f in "$TMP"/*/w*.pid; do [ -e "$f" ] && kill -9 "$(cat "$f")" 2>/dev/null || true; done
  [ -n "${SERVER_PID:-}" ] && kill -9 "$SERVER_PID" 2>/dev/null || true
  rm -rf "$TMP"
}
trap cleanup EXIT
od -An -tx1 -N16 /dev/urandom | tr -d " \n" > "$TMP/token"
cat > "$TMP/spec.yaml" <<YAML
name: soak
material:
  particle_law:
    normal: {model: hertz, youngs_modulus: 2.0e6, restitution: 0.3}
    tangential: {model: history, mu_s: 0.3}
  sizes: {monodisperse: {radius: 0.0005}}
  density: 2500
tests:
  - test: packing
    settings: {particles: 200}
factors:
  - {path: particle_law.tangential.mu_s, low: 0.1, high: 0.5}
  - {path: particle_law.normal.restitution, low: 0.2, high: 0.6}
design: {type: full_factorial, centre_points: 21, replicates: $REPL}
YAML

# start_server DIR PORT: a coordinator on 127.0.0.1:PORT (0: any) with DIR/c.db; sets SERVER_PID.
start_server() {
  rm -f "$1/port"
  "$SERVER" --listen "127.0.0.1:$2" --db "$1/c.db" --token-file "$TMP/token" --lease 2 \
    --heartbeat 0.3 --reaper-interval 0.2 --grace 5 --max-attempts "$MAX_ATTEMPTS" --port-file "$1/port" \
    >> "$1/server.log" 2>&1 &
  SERVER_PID=$!
  for _ in $(seq 200); do [ -s "$1/port" ] && return 0; sleep 0.05; done
  echo "coordinator did not start" >&2; exit 1
}
# supervise DIR N PORT: worker N restarted whenever it exits, until DIR/stop exists; its
# process id in DIR/wN.pid.
supervise() {
  while [ ! -e "$1/stop" ]; do
    "$WORKER" --coordinator "127.0.0.1:$3" --token-file "$TMP/token" --threads 1 --id "w$2" \
      --max-backoff 0.5 >> "$1/w$2.log" 2>&1 &
    echo $! > "$1/w$2.pid"
    wait $! 2>/dev/null || true
  done
}
state() { sqlite3 -readonly "$1/c.db" "SELECT state FROM campaigns WHERE id = 1" 2>/dev/null || echo "?"; }

# run DIR CHAOS: one campaign to its end; with CHAOS=1, the kills.
run() {
  local dir=$1 chaos=$2 wk=0 ck=0
  mkdir -p "$dir"
  start_server "$dir" 0
  local port; port=$(cat "$dir/port")
  "$CLI" submit "$TMP/spec.yaml" --coordinator "127.0.0.1:$port" --token-file "$TMP/token" \
    > "$dir/submit.log"
  local sup=()
  for n in $(seq "$WORKERS"); do supervise "$dir" "$n" "$port" & sup+=($!); done
  local start=$SECONDS
  # The kills, spread out: one coordinator kill after every WK / (CK + 1) worker kills.
  local every=$(( WK / (CK + 1) > 0 ? WK / (CK + 1) : 1 ))
  while [ "$(state "$dir")" != done ]; do
    if [ "$chaos" = 1 ] && { [ $wk -lt "$WK" ] || [ $ck -lt "$CK" ]; }; then
      sleep "0.$((RANDOM % 5 + 1))"
      if [ $ck -lt "$CK" ] && { [ $wk -ge "$WK" ] || [ $((wk % every)) = $((every - 1)) ]; } &&
         [ "${last_ck_at:-x}" != "$wk" ]; then
        last_ck_at=$wk
        kill -9 "$SERVER_PID"; wait "$SERVER_PID" 2>/dev/null || true; ck=$((ck + 1))
        sleep "0.$((RANDOM % 9 + 1))"
        start_server "$dir" "$port"
      elif [ $wk -lt "$WK" ]; then
        local victim; victim=$(cat "$dir"/w$((RANDOM % WORKERS + 1)).pid 2>/dev/null || true)
        [ -n "$victim" ] && kill -9 "$victim" 2>/dev/null && wk=$((wk + 1))
      fi
    else
      sleep 0.5
    fi
    [ $((SECONDS - start)) -gt 1800 ] && { echo "campaign not done after 30 min" >&2; exit 1; }
  done
  touch "$dir/stop"
  for n in $(seq "$WORKERS"); do kill "$(cat "$dir/w$n.pid")" 2>/dev/null || true; done
  for p in "${sup[@]}"; do wait "$p" 2>/dev/null || true; done
  "$CLI" effects 1 --format json --coordinator "127.0.0.1:$port" --token-file "$TMP/token" \
    > "$dir/effects.json"
  kill "$SERVER_PID"; wait "$SERVER_PID" 2>/dev/null || true
  echo "$wk $ck $((SECONDS - start))"
}

read -r _ _ calm_s < <(run "$TMP/calm" 0)
read -r wk ck chaos_s < <(run "$TMP/chaos" 1)
q() { sqlite3 -readonly "$TMP/chaos/c.db" "$1"; }
jobs=$(q "SELECT COUNT(*) FROM jobs")
results=$(q "SELECT COUNT(*) FROM results")
dups=$(q "SELECT COUNT(*) - COUNT(DISTINCT job_id) FROM results")
lost=$(q "SELECT COUNT(*) FROM jobs WHERE state <> 'done' OR id NOT IN (SELECT job_id FROM results)")
attempts=$(q "SELECT SUM(attempt) FROM jobs")
counted=$(q "SELECT SUM(counted) FROM jobs") most=$(q "SELECT MAX(counted) FROM jobs")
explained=$((jobs + wk + WORKERS * ck))
equal=no; cmp -s "$TMP/calm/effects.json" "$TMP/chaos/effects.json" && equal=yes
echo "undisturbed: $calm_s s; chaos: $chaos_s s with $wk worker SIGKILLs and $ck coordinator SIGKILLs"
echo "jobs $jobs, results $results, duplicates $dups, lost $lost, attempts $attempts"
echo "attempts counted against the cap $counted (the kills explain at most $explained), at most $most of one job (cap $MAX_ATTEMPTS)"
echo "effect tables bitwise equal to the undisturbed run: $equal"
[ "$dups" = 0 ] && [ "$lost" = 0 ] && [ "$equal" = yes ] && [ "$most" -le "$MAX_ATTEMPTS" ] &&
  [ "$counted" -le "$explained" ]
