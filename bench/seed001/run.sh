#!/usr/bin/env bash
# Seed 001 (Tiscar et al. 2019) with its calibrated set, measured with demcal (docs/seed-001.md):
#   bench/seed001/run.sh [BUILD_DIR] [OUT_DIR] [PART]
# PART study: the dynamic angle of the granule-coated drum (Table 3) against D/d, by the scale
#   factor lambda at the seed's 100 x 44 mm drum (App. B: the drum stays, the granules grow);
#   `demcal lab study --scale` (LAMBDAS, default 30000,20000,10000).
# PART scales: the same, one `demcal lab run` per lambda (results kept as each run ends).
# PART pairs: the three (mu_s, mu_r) pairs of §4.2 that all give 34.6 deg in the seed, and the
#   polymer wall (PTFE = PP, Table 3: mu_s 0.9, mu_r 1e-4), at lambda = LAMBDA (default 30000).
# PART area: the area method (§3.2.3, eq. 20) for the three pairs, 1 s per speed (the seed: 6 s
#   at 4-80 rpm, 3 s at 105 and 116 rpm), at lambda = LAMBDA.
# PART compression: the confined modulus of the Table 3 stiffness (bench/seed001/
#   compression_table3.yaml, 1,000 particles: the size its confined modulus converged from, lambda 27).
# PART pairs takes SEED=2 (3, ...) for a replicate of each run with another bed.
# Each run prints its wall time; results are JSON in OUT_DIR. Not part of ctest (minutes each).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${1:-$root/build}
OUT=${2:-$root/out/seed001}
PART=${3:-study}
demcal="$BUILD/client/demcal"
spec="$root/bench/seed001/drum_table3.yaml"
mkdir -p "$OUT"

# timed NAME CMD...: runs CMD with its output in OUT/NAME.json and prints the wall time.
timed() {
  local name=$1 t0 t1
  shift
  t0=$(date +%s.%N)
  nice -n 10 "$@" > "$OUT/$name.json"
  t1=$(date +%s.%N)
  printf "%-28s wall %7.1f s\n" "$name" "$(echo "$t1 - $t0" | bc)"
}

# variant NAME SED: the drum spec at lambda LAMBDA and seed SEED (default 1) with the sed script
# applied; NAME gets the suffix _sSEED for SEED > 1.
# The three pairs of §4.2; the coated wall has the granule law (§4.2), so the wall pair follows.
pairs=("s/mu_s: 0.8,/mu_s: 0.8,/" "s/mu_s: 0.8,/mu_s: 0.33,/; s/mu_r: 0.2,/mu_r: 0.3,/"
       "s/mu_s: 0.8,/mu_s: 0.27,/; s/mu_r: 0.2,/mu_r: 0.5,/")
names=(0.8_0.2 0.33_0.3 0.27_0.5)
variant() {
  sed -e "s/factor: 100000/factor: ${LAMBDA:-30000}/" -e "s/^seed: 1$/seed: ${SEED:-1}/" -e "$2" \
    "$spec" > "$OUT/$1$(suffix).yaml"
}

suffix() {
  [ "${SEED:-1}" = 1 ] || echo "_s$SEED"
}

case $PART in
  study)
    timed study "$demcal" lab study "$spec" --scale "${LAMBDAS:-30000,20000,10000}" ;;
  scales)
    list=${LAMBDAS:-30000,20000,10000}
    for l in ${list//,/ }; do
      LAMBDA=$l variant "lambda_$l" ""
      timed "lambda_$l" "$demcal" lab run "$OUT/lambda_$l.yaml"
    done ;;
  pairs)
    for i in 0 1 2; do variant "pair_${names[$i]}" "${pairs[$i]}"; done
    variant polymer_wall '/granule-aluminium/,/rolling/{s/mu_s: 0.8,/mu_s: 0.9,/; s/mu_r: 0.2,/mu_r: 0.0001,/}'
    for v in pair_0.8_0.2 pair_0.33_0.3 pair_0.27_0.5 polymer_wall; do
      timed "$v$(suffix)" "$demcal" lab run "$OUT/$v$(suffix).yaml"
    done ;;
  area)
    for i in 0 1 2; do
      variant "area_${names[$i]}" "${pairs[$i]}; s/angle_time: 1.0/angle_time: 0.2/; s/area_time: 0.02/area_time: 1.0/"
      timed "area_${names[$i]}" "$demcal" lab run "$OUT/area_${names[$i]}.yaml"
    done ;;
  compression)
    timed compression "$demcal" lab run "$root/bench/seed001/compression_table3.yaml" ;;
  *) echo "PART is study, pairs, area or compression" >&2; exit 2 ;;
esac
