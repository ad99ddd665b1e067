#!/usr/bin/env bash
# The hopper against the published rate at realistic size: discharge of cohesionless Hertz spheres
# (bench/materials/hertz.yaml) from the wedge hopper at each half angle, and the ratio of the
# measured rate to Beverloo's slot law with Rose and Tanaka's wall factor (docs/lab-tests.md,
# "hopper"); a ratio within 1 +- 0.15 passes. Not part of ctest (minutes per run).
#   bench/hopper.sh [BUILD_DIR] [PARTICLES] [HALF_ANGLES]     e.g. bench/hopper.sh build 1600 20,45
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$root/build}
PARTICLES=${2:-1600}
ANGLES=${3:-20,45}
DEMCAL="$BUILD/client/demcal"
[ -x "$DEMCAL" ] || { echo "no $DEMCAL; build the demcal target first" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
printf "%-10s %9s %8s %12s %12s %8s %s\n" half_angle particles wall_s rate_kg_s beverloo_kg_s ratio verdict
for angle in ${ANGLES//,/ }; do
  spec="$TMP/hopper-$angle.yaml"
  { printf "test: hopper\nsettings: {particles: %s, half_angle: %s}\nseed: 1\nthreads: 1\n" "$PARTICLES" "$angle"
    grep -v '^#' "$root/bench/materials/hertz.yaml"; } > "$spec"
  start=$(date +%s.%N)
  "$DEMCAL" lab run "$spec" > "$TMP/out.json"
  end=$(date +%s.%N)
  python3 - "$TMP/out.json" "$angle" "$PARTICLES" "$(echo "$end - $start" | bc)" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))["metrics"]
ratio = m["beverloo_ratio"]
verdict = "within 15 %" if abs(ratio - 1.0) <= 0.15 else "OUTSIDE 15 %"
print("%-10s %9s %8.1f %12.4g %12.4g %8.3f %s" % (sys.argv[2], sys.argv[3], float(sys.argv[4]),
      m["discharge_rate"], m["beverloo_rate"], ratio, verdict))
PY
done
