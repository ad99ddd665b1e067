#!/usr/bin/env bash
# The shear cell against the Coulomb limit of a cohesionless material: cohesionless frictional
# Hertz spheres (bench/materials/hertz.yaml) sheared at the seed's five normal stresses after
# pre-shear at 3 kPa, over several seeds; a cohesionless material's yield locus passes through
# the origin, so the intercept must lie within its noise of 0 (|mean| <= 2 standard errors of
# the seeds' intercepts) with mohr_consistent 1 in every run. Prints each run's yield points,
# slope, intercept and flags, then the verdict. Not part of ctest (minutes per run).
#   bench/shear_cohesionless.sh [BUILD_DIR] [PARTICLES] [SEEDS]   e.g. bench/shear_cohesionless.sh build 1000 1,2,3
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$root/build}
PARTICLES=${2:-1000}
SEEDS=${3:-1,2,3}
DEMCAL="$BUILD/client/demcal"
[ -x "$DEMCAL" ] || { echo "no $DEMCAL; build the demcal target first" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
for seed in ${SEEDS//,/ }; do
  spec="$TMP/shear-$seed.yaml"
  { printf "test: shear_cell\nsettings: {particles: %s}\nseed: %s\nthreads: 1\n" "$PARTICLES" "$seed"
    grep -v '^#' "$root/bench/materials/hertz.yaml"; } > "$spec"
  "$DEMCAL" lab run "$spec" --out "$TMP/run-$seed" > "$TMP/out-$seed.json" &
done
wait
python3 - "$TMP" "$SEEDS" <<'PY'
import csv, json, math, os, statistics as st, sys
tmp, seeds = sys.argv[1], sys.argv[2].split(",")
icpt, consistent = [], True
for s in seeds:
    j = json.load(open(os.path.join(tmp, f"out-{s}.json")))
    m = j["metrics"]
    rows = list(csv.reader(open(os.path.join(tmp, f"run-{s}", "yield_points.csv"))))[1:]
    pts = " ".join("(%.3g, %.3g)" % (float(r[1]), float(r[2])) for r in rows)
    icpt.append(m["yield_locus_intercept"])
    consistent &= m["mohr_consistent"] == 1.0
    print("seed %s: slope %.4f intercept %.4f kPa mohr_consistent %d wall %.0f s flags %s points (sigma, tau) kPa: %s"
          % (s, m["yield_locus_slope"], m["yield_locus_intercept"], m["mohr_consistent"],
             j["cost"]["wall_seconds"], ",".join(j.get("flags", {})) or "none", pts))
mean = st.mean(icpt)
se = st.stdev(icpt) / math.sqrt(len(icpt)) if len(icpt) > 1 else float("inf")
ok = abs(mean) <= 2 * se and consistent
print("intercept %.4f +- %.4f kPa (standard error of %d seeds); mohr_consistent in every run: %s; %s"
      % (mean, se, len(icpt), "yes" if consistent else "no",
         "cohesionless within noise" if ok else "NOT within noise of 0"))
PY
