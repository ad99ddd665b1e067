#!/usr/bin/env bash
# Run time of each lab test (packing, confined_compression, tensile, wall_friction; shear_cell,
# rotating_drum, hopper) at
# 2,000 and 10,000 particles: bench/lab.sh [BUILD_DIR] [COUNTS] [THREADS]
#   e.g. bench/lab.sh build 2000,10000 2
# Soft Luding spheres of 1 mm radius (the material of tests/lab), seed-000 defaults otherwise
# except wall_stiffness_factor 3 and one compression cycle (state them when you quote numbers).
# Not part of ctest: the 10,000-particle runs take long. TESTS="packing tensile" runs a subset.
set -euo pipefail
BUILD=${1:-build}
COUNTS=${2:-2000,10000}
THREADS=${3:-1}
DEMCAL="$BUILD/client/demcal"
[ -x "$DEMCAL" ] || { echo "no $DEMCAL; build the demcal target first" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
material() {
  cat <<YAML
material:
  particle_law:
    normal: {model: luding, youngs_modulus: 1.0e7, k2_ratio: 5, kc_ratio: $1, phi_f: 0.05, restitution: 0.3}
    $2
    tangential: {model: history, mu_s: 0.3}
  sizes: {monodisperse: {radius: 0.001}}
  density: 1500
YAML
}
COH="cohesion: {model: van_der_waals, hamaker: 1.0e-18, d_max: 1.0e-5}"
printf "%-22s %10s %12s  %s\n" test particles wall_time_s metrics
for n in ${COUNTS//,/ }; do
  for test in ${TESTS:-packing confined_compression tensile wall_friction shear_cell rotating_drum hopper}; do
    case $test in
      packing) settings="{particles: $n}"; mat=$(material 0 "") ;;
      confined_compression) settings="{particles: $n, cycles: 1, wall_stiffness_factor: 3}"; mat=$(material 0 "") ;;
      tensile) settings="{particles: $n, wall_stiffness_factor: 3, wall_hamaker_factor: 10, wall_k2_factor: 1, pull_distance: 1}"; mat=$(material 0.5 "$COH") ;;
      wall_friction) settings="{particles: $n, wall_stiffness_factor: 3}"; mat=$(material 0 "") ;;
      # Issue 5 (lab tests II): defaults of each test's settings table.
      shear_cell|rotating_drum|hopper) settings="{particles: $n}"; mat=$(material 0 "") ;;
    esac
    spec="$TMP/$test-$n.yaml"
    printf "test: %s\nsettings: %s\nseed: 1\nthreads: %s\n%s\n" "$test" "$settings" "$THREADS" "$mat" > "$spec"
    start=$(date +%s.%N)
    if out=$("$DEMCAL" lab run "$spec" 2>&1); then status=""; else status=" FAILED"; fi
    end=$(date +%s.%N)
    metrics=$(echo "$out" | python3 -c 'import json,sys
try:
  j=json.load(sys.stdin); print(" ".join("%s=%.4g"%(k,v) for k,v in j["metrics"].items()))
except Exception: print("")' 2>/dev/null || true)
    printf "%-22s %10s %12.1f  %s%s\n" "$test" "$n" "$(echo "$end - $start" | bc)" "$metrics" "$status"
  done
done
