#!/usr/bin/env bash
# Side-by-side throughput of demcal and LIGGGHTS on the pour-and-settle problem of
# ../shared/peers/liggghts/in.bench_pour (10,000 spheres, Hertz + history + CDT rolling,
# dt = 1e-5 s, 5,000 untimed + 20,000 timed steps): demcal on 2 OpenMP threads, LIGGGHTS on
# 2 MPI ranks, one after the other in this run. Prints both throughputs (particle-steps per
# second of the timed phase) and, last, "ratio: X" = demcal / LIGGGHTS.
# Usage: bench/pour_vs_liggghts.sh [nbench]   (default 20000 timed steps)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
demcal=${DEMCAL:-$root/build/client/demcal}
peers=${DEMCAL_PEERS:-$root/../shared/peers/liggghts}
nbench=${1:-20000}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

[ -x "$demcal" ] || { echo "build demcal first (scripts/build)" >&2; exit 1; }
command -v liggghts >/dev/null || { echo "liggghts not installed (scripts/setup)" >&2; exit 1; }

sed "s/steps: 20000/steps: $nbench/" "$root/bench/pour.yaml" > "$work/pour.yaml"
demcal_rate=$("$demcal" simulate "$work/pour.yaml" --threads 2 |
  python3 -c 'import json,sys; r=json.load(sys.stdin); print([p for p in r["phases"] if p["name"]=="timed"][0]["particle_steps_per_second"])')

cp "$peers/in.bench_pour" "$work/"
(cd "$work" && script -qc "mpirun --allow-run-as-root --oversubscribe -np 2 liggghts -in in.bench_pour -var cdt 1 -var nbench $nbench" /dev/null > liggghts.log 2>&1)
# "Loop time of T on P procs for S steps with N atoms[, finish time ...]" of the timed run
last=$(grep "Loop time of" "$work/liggghts.log" | tail -n 1)
loop=$(sed -E 's/.*Loop time of ([0-9.eE+-]+) on .*/\1/' <<<"$last")
natoms=$(sed -E 's/.* with ([0-9]+) atoms.*/\1/' <<<"$last")
[ -n "$loop" ] || { echo "LIGGGHTS run failed:"; tail -20 "$work/liggghts.log"; exit 1; }
liggghts_rate=$(python3 -c "print($natoms * $nbench / $loop)")

printf 'demcal   (2 threads): %.4g particle-steps/s\n' "$demcal_rate"
printf 'LIGGGHTS (2 ranks)  : %.4g particle-steps/s (%s atoms, loop time %s s)\n' "$liggghts_rate" "$natoms" "$loop"
python3 -c "print('ratio: %.3f' % ($demcal_rate / $liggghts_rate))"
