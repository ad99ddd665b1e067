#!/usr/bin/env bash
# Side-by-side throughput of demcal and LIGGGHTS on the pour-and-settle problem of
# bench/liggghts/in.bench_pour (10,000 spheres, Hertz + history + CDT rolling, dt = 1e-5 s,
# 5,000 untimed + 20,000 timed steps): demcal on 1 and on 2 OpenMP threads, LIGGGHTS on 1 and on
# 2 MPI ranks, one after the other in this run. Prints each throughput (particle-steps per second
# of the timed phase), the ratio demcal / LIGGGHTS of the 1-vs-1 case and, last, "ratio: X" of the
# 2-threads-vs-2-ranks case.
# demcal's threads wait passively at barriers (OMP_WAIT_POLICY=passive) unless the caller sets
# OMP_WAIT_POLICY: on a shared machine GOMP's default spinning lets a waiting thread hold a core
# that the thread it waits for needs (the pour on 2 threads measured 9x slower in wall time with
# spinning than with passive waiting while other jobs ran). LIGGGHTS runs with Open MPI's defaults.
# Usage: bench/pour_vs_liggghts.sh [nbench]   (default 20000 timed steps)
set -euo pipefail
wait_policy=${OMP_WAIT_POLICY:-passive}
root=$(cd "$(dirname "$0")/.." && pwd)
demcal=${DEMCAL:-$root/build/client/demcal}
nbench=${1:-20000}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

[ -x "$demcal" ] || { echo "build demcal first (scripts/build)" >&2; exit 1; }
command -v liggghts >/dev/null || { echo "liggghts not installed (scripts/setup)" >&2; exit 1; }

sed "s/steps: 20000/steps: $nbench/" "$root/bench/pour.yaml" > "$work/pour.yaml"
cp "$root/bench/liggghts/in.bench_pour" "$work/"

# demcal_rate THREADS: particle-steps per second of the timed phase.
demcal_rate() {
  OMP_WAIT_POLICY=$wait_policy "$demcal" simulate "$work/pour.yaml" --threads "$1" |
    python3 -c 'import json,sys; r=json.load(sys.stdin); print([p for p in r["phases"] if p["name"]=="timed"][0]["particle_steps_per_second"])'
}

# liggghts_rate RANKS: particle-steps per second of the timed run, from its
# "Loop time of T on P procs for S steps with N atoms" line.
liggghts_rate() {
  (cd "$work" && script -qc "mpirun --allow-run-as-root --oversubscribe -np $1 liggghts -in in.bench_pour -var cdt 1 -var nbench $nbench" /dev/null > "liggghts-$1.log" 2>&1)
  local last loop natoms
  last=$(grep "Loop time of" "$work/liggghts-$1.log" | tail -n 1)
  loop=$(sed -E 's/.*Loop time of ([0-9.eE+-]+) on .*/\1/' <<<"$last")
  natoms=$(sed -E 's/.* with ([0-9]+) atoms.*/\1/' <<<"$last")
  if [ -z "$loop" ]; then
    echo "LIGGGHTS run on $1 ranks failed:" >&2
    tail -20 "$work/liggghts-$1.log" >&2
    exit 1
  fi
  python3 -c "print($natoms * $nbench / $loop)"
}

echo "demcal OMP_WAIT_POLICY=$wait_policy, $nbench timed steps"
d1=$(demcal_rate 1)
l1=$(liggghts_rate 1)
d2=$(demcal_rate 2)
l2=$(liggghts_rate 2)
printf 'demcal   (1 thread) : %.4g particle-steps/s\n' "$d1"
printf 'LIGGGHTS (1 rank)   : %.4g particle-steps/s\n' "$l1"
python3 -c "print('ratio 1 thread vs 1 rank: %.3f' % ($d1 / $l1))"
printf 'demcal   (2 threads): %.4g particle-steps/s\n' "$d2"
printf 'LIGGGHTS (2 ranks)  : %.4g particle-steps/s\n' "$l2"
python3 -c "print('ratio: %.3f' % ($d2 / $l2))"
