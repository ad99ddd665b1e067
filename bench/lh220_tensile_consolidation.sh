#!/usr/bin/env bash
# The LH220 tensile strength against the stress that consolidated its bed (docs/seed-000.md,
# "The tensile strength against the bed's consolidation"): the committed tensile spec of the
# calibrated set (docs/data/seed000/lh220/tensile.yaml) with its bed conditioned at each
# consolidation stress S (the confined compression's five cycles to S / 30, as 15 kPa to 0.5 kPa
# in seed 000 §2.7.2), at PARTICLES particles, on SEEDS seeds (the spec's and the next ones).
# With WALL_FACTOR, piston and bottom get A_H,wall / A_H = WALL_FACTOR x S / 15 kPa (the same
# ratio of their pull-off force to the consolidation's as eq. 34's factor at 15 kPa; eq. 34 gives
# 40 at this set's 20 um); without it, eq. 34 at every S.
#   bench/lh220_tensile_consolidation.sh [BUILD_DIR] [OUT] [STRESSES] [PARTICLES] [SEEDS] [WALL_FACTOR]
#   e.g. bench/lh220_tensile_consolidation.sh build out/consolidation "15000 4500 1500 500" 300 2 40
# PULL_DISTANCE=D (mean diameters) pulls further than the spec's default: a bed conditioned at a
# low stress stretches before it breaks. The conditioned beds are kept in the stage cache
# STAGE_CACHE (default OUT/stages): runs in another OUT (another pull distance or wall factor)
# given the same STAGE_CACHE start from the beds of the same stress, particles and seed. A run
# already in OUT (its metrics.json) is kept.
# Prints per stress, over the runs not flagged,
# the tensile strength and the weight of the particles stuck to the piston (mean +- sample sd),
# the solid fraction of the conditioned bed (the settled bed's, times its height over the
# conditioned height; of the runs that conditioned their own bed), the settle's steps, and the
# runs that ended, were flagged or failed (no metrics.json; their exit status is in
# OUT/times.txt). Not part of ctest.
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$root/build}
OUT=${2:-$root/out/lh220_tensile_consolidation}
STRESSES=${3:-15000 4500 1500 500}
PARTICLES=${4:-300}
SEEDS=${5:-2}
WALL_FACTOR=${6:-}
DEMCAL=${DEMCAL:-$BUILD/client/demcal}
STAGE_CACHE=${STAGE_CACHE:-$OUT/stages}
SPEC="$root/docs/data/seed000/lh220/tensile.yaml"
[ -x "$DEMCAL" ] || { echo "no $DEMCAL; build the demcal target first" >&2; exit 1; }
mkdir -p "$OUT" "$STAGE_CACHE"
base_seed=$(sed -n 's/^seed: //p' "$SPEC")

for s in $STRESSES; do
  for k in $(seq 0 $((SEEDS - 1))); do
    run="$OUT/c$s-s$k"
    [ -s "$run/metrics.json" ] && continue
    settings="particles: $PARTICLES, consolidation_stress: $s, min_stress: $(python3 -c "print(repr($s / 30))")"
    [ -n "$WALL_FACTOR" ] &&
      settings+=", wall_hamaker_factor: $(python3 -c "print(repr($WALL_FACTOR * $s / 15000))")"
    [ -n "${PULL_DISTANCE:-}" ] && settings+=", pull_distance: $PULL_DISTANCE"
    sed -e "s/^settings: .*/settings: {$settings}/" \
        -e "s/^seed: .*/seed: $((base_seed + k))/" -e '/^expected:/d' -e '/^#/d' "$SPEC" > "$run.yaml"
    start=$(date +%s)
    "$DEMCAL" lab run "$run.yaml" --out "$run" --stage-cache "$STAGE_CACHE" > "$run.log" 2>&1
    echo "c$s seed $((base_seed + k)): rc $?, $(( $(date +%s) - start )) s" >> "$OUT/times.txt"
  done
done

python3 - "$OUT" $STRESSES <<'PY'
import csv, glob, json, os, statistics as st, sys
out, stresses = sys.argv[1], sys.argv[2:]
def row(path):
    with open(path) as f:
        return next(csv.DictReader(f))
def mean_sd(xs):
    if not xs: return "-"
    return "%.3f" % xs[0] if len(xs) == 1 else "%.3f +- %.3f" % (st.mean(xs), st.stdev(xs))
print("%-10s %-20s %-20s %-20s %-18s %s" % ("stress Pa", "tensile kPa", "stuck weight kPa",
                                             "solid fraction", "settle steps (M)",
                                             "ended / flagged / failed"))
for s in stresses:
    strength, stuck, phi, settle, runs, flagged, failed = [], [], [], [], 0, 0, 0
    for spec in sorted(glob.glob(os.path.join(out, "c%s-s*.yaml" % s))):
        d = spec[:-len(".yaml")]
        m = os.path.join(d, "metrics.json")
        if not os.path.exists(m):
            failed += 1
            continue
        runs += 1
        r = json.load(open(m))
        if r["flags"]:
            flagged += 1
            continue
        strength.append(r["metrics"]["tensile_strength"])
        fracture = row(os.path.join(d, "fracture.csv"))
        stuck.append(float(fracture["stuck_weight_stress_kPa"]))
        settled = os.path.join(d, "settled_bed.csv")  # absent when the bed came from the cache
        if os.path.exists(settled):
            bed = row(settled)
            phi.append(float(bed["solid_fraction"]) * float(bed["h0_m"])
                       / float(fracture["conditioned_height_m"]))
        settle += [p["steps"] / 1e6 for p in r["cost"]["phases"] if p["name"] == "settle"]
    print("%-10s %-20s %-20s %-20s %-18s %d / %d / %d" % (
        s, mean_sd(strength), mean_sd(stuck), mean_sd(phi), ", ".join("%.2f" % x for x in settle),
        runs, flagged, failed))
PY
