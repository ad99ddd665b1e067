#!/usr/bin/env bash
# Run time and cost of each lab test at given particle counts for one material:
#   bench/lab.sh [BUILD_DIR] [COUNTS] [THREADS]      e.g. bench/lab.sh build 1000 2
# MATERIAL=lh220 (default; bench/materials/NAME.yaml: lh220, lh100, hertz) and
# TESTS="packing confined_compression ..." (default: all seven) select what runs.
# Piston tests use wall_stiffness_factor 3 and the tensile test wall_k2_factor 1, as
# examples/lh220_diagnosis_campaign.yaml; everything else is each test's default (five
# compression cycles included). The rotating drum is sized by its geometry: it gets the drum
# (D x 0.44 D, 43 % fill) that holds about the given count of the material's simulated spheres
# (monodisperse radius x the kottlan2018 factor). Prints per test: wall time, steps, particle-steps/s, phases
# short of their target, flagged metrics, and the metrics. Not part of ctest.
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
# drum_mm N: the diameter (mm) of the seed-shaped drum that holds N of the material's spheres:
# N (4/3 pi r^3) = 0.43 (pi D^2 / 4) (0.44 D) 0.6 (rotating_drum's defaults).
drum_mm() {
  python3 - "$1" "$root/bench/materials/$MATERIAL.yaml" <<'PY'
import math, re, sys
text = open(sys.argv[2]).read()
r = float(re.search(r"radius:\s*([0-9.eE+-]+)", text).group(1))
f = re.search(r"kottlan2018, factor:\s*([0-9.eE+-]+)", text)
r *= float(f.group(1)) if f else 1.0
d = (int(sys.argv[1]) * 4 / 3 * math.pi * r**3 / (0.43 * math.pi / 4 * 0.44 * 0.6)) ** (1 / 3)
print("%.2f %.2f" % (1e3 * d, 0.44e3 * d))
PY
}
echo "material $MATERIAL ($root/bench/materials/$MATERIAL.yaml), $THREADS threads"
printf "%-22s %9s %8s %10s %12s %7s  %s\n" test particles wall_s steps p-steps/s short metrics
for n in ${COUNTS//,/ }; do
  for test in ${TESTS:-packing confined_compression tensile wall_friction shear_cell rotating_drum hopper}; do
    case $test in
      confined_compression|wall_friction) settings="{particles: $n, wall_stiffness_factor: 3}" ;;
      tensile) settings="{particles: $n, wall_stiffness_factor: 3, wall_k2_factor: 1}" ;;
      rotating_drum) read -r dmm wmm < <(drum_mm "$n"); settings="{diameter: $dmm, length: $wmm}" ;;
      *) settings="{particles: $n}" ;;
    esac
    spec="$TMP/$test-$n.yaml"
    { printf "test: %s\nsettings: %s\nseed: 1\nthreads: %s\n" "$test" "$settings" "$THREADS"
      grep -v '^#' "$root/bench/materials/$MATERIAL.yaml"; } > "$spec"
    start=$(date +%s.%N)
    if "$DEMCAL" lab run "$spec" > "$TMP/out.json" 2> "$TMP/err"; then status=""; else status=" FAILED: $(tail -1 "$TMP/err")"; fi
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
