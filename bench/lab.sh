#!/usr/bin/env bash
# Run time and cost of each lab test at given particle counts for one material:
#   bench/lab.sh [BUILD_DIR] [COUNTS] [THREADS]      e.g. bench/lab.sh build 1000 2
# MATERIAL=lh220 (default; bench/materials/NAME.yaml: lh220, lh100, hertz) and
# TESTS="packing confined_compression ..." (default: all seven) select what runs.
# STAGE_CACHE=DIR passes --stage-cache DIR, so that a tensile test after a confined compression
# of the same material and size starts from the bed it conditioned (docs/lab-tests.md, "Work
# done once"): TESTS="confined_compression tensile" STAGE_CACHE=$(mktemp -d) bench/lab.sh ...
# The specs are bench/lab_spec.sh's (five compression cycles included). Prints per test: wall
# time, steps, particle-steps/s, phases short of their target, flagged metrics, and the metrics.
# Not part of ctest.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$root/build}
COUNTS=${2:-1000}
THREADS=${3:-2}
MATERIAL=${MATERIAL:-lh220}
DEMCAL="$BUILD/client/demcal"
[ -x "$DEMCAL" ] || { echo "no $DEMCAL; build the demcal target first" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
source "$root/bench/lab_spec.sh"
echo "material $MATERIAL ($root/bench/materials/$MATERIAL.yaml), $THREADS threads, OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}"
printf "%-22s %9s %8s %10s %12s %7s  %s\n" test particles wall_s steps p-steps/s short metrics
for n in ${COUNTS//,/ }; do
  for test in ${TESTS:-packing confined_compression tensile wall_friction shear_cell rotating_drum hopper}; do
    spec="$TMP/$test-$n.yaml"
    lab_spec "$test" "$n" "$THREADS" > "$spec"
    start=$(date +%s.%N)
    if "$DEMCAL" lab run "$spec" ${STAGE_CACHE:+--stage-cache "$STAGE_CACHE"} > "$TMP/out.json" 2> "$TMP/err"; then status=""; else status=" FAILED: $(tail -1 "$TMP/err")"; fi
    end=$(date +%s.%N)
    line=$(python3 - "$TMP/out.json" <<'PY' 2>/dev/null || true
import json, sys
try:
    j = json.load(open(sys.argv[1]))
except Exception:
    sys.exit(0)
c = j["cost"]
short = sum(1 for p in c["phases"] if not p["reached"])
m = " ".join("%s=%.4g" % (k, v) for k, v in j["metrics"].items())
flags = (" flagged: " + ",".join(j["flags"])) if j.get("flags") else ""
print("%10d %12.4g %7d  %s%s" % (c["steps"], c["particle_steps_per_second"], short, m, flags))
PY
)
    printf "%-22s %9s %8.1f %s%s\n" "$test" "$n" "$(echo "$end - $start" | bc)" "$line" "$status"
  done
done
