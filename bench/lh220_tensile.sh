#!/usr/bin/env bash
# What sets the LH220 tensile strength (docs/diagnosis.md, "Why the held-out tensile strength
# resists"): the tensile and confined_compression tests of bench/lab_spec.sh (100 particles, the
# settings of examples/lh220_diagnosis_campaign.yaml) for the material bench/materials/lh220.yaml
# changed one way per variant, three seeds each, then a table of mean +- sample sd per variant.
#   bench/lh220_tensile.sh [BUILD_DIR] [OUT] [VARIANTS]     e.g. bench/lh220_tensile.sh build out/t
# Runs already in OUT (a non-empty JSON) are kept; a failed run leaves its .err and counts as
# failed in the table. Not part of ctest.
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$root/build}
OUT=${2:-$root/out/lh220_tensile}
DEMCAL="$BUILD/client/demcal"
[ -x "$DEMCAL" ] || { echo "no $DEMCAL; build the demcal target first" >&2; exit 1; }
export MATERIAL=lh220
source "$root/bench/lab_spec.sh"
mkdir -p "$OUT"

# variant name -> sed program on the material (the example's: A_H 5e-18 J, kc/k1 0.2, r 100 um).
declare -A EDIT=(
  [AH-5e-20]='s/hamaker: 5.0e-18/hamaker: 5.0e-20/'
  [AH-3e-19]='s/hamaker: 5.0e-18/hamaker: 3.0e-19/'
  [AH-1e-18]='s/hamaker: 5.0e-18/hamaker: 1.0e-18/'
  [AH-5e-18]=''
  [kc-0]='s/kc_ratio: 0.2,/kc_ratio: 0.0,/'
  [kc-0.005]='s/kc_ratio: 0.2,/kc_ratio: 0.005,/'
  [kc-0.05]='s/kc_ratio: 0.2,/kc_ratio: 0.05,/'
  # LH220's median radius (d50 13 um, seed 000 Table 2) at the example's Bond number:
  # F_vdW / m g ~ A_H / r^2, so A_H = 5e-18 (6.5 / 100)^2 = 2.1e-20 J.
  [median-kc0.2]='s/hamaker: 5.0e-18/hamaker: 2.1e-20/; s/radius: 1.0e-4/radius: 6.5e-6/'
  [median-kc0.005]='s/hamaker: 5.0e-18/hamaker: 2.1e-20/; s/radius: 1.0e-4/radius: 6.5e-6/; s/kc_ratio: 0.2,/kc_ratio: 0.005,/'
  # The thesis's radius range (Table 8: 10-20 um) at the example's A_H.
  [r-15um]='s/radius: 1.0e-4/radius: 1.5e-5/'
  # Seed 000 Table 14, the thesis's calibrated LH220 set (its own simulation of it: Table 15).
  [table14]='s/youngs_modulus: 3.0e7, k2_ratio: 16, kc_ratio: 0.2, phi_f: 0.02/youngs_modulus: 2.1e7, k2_ratio: 12, kc_ratio: 0.2667, phi_f: 0.0267/; s/radius: 1.0e-4/radius: 1.0e-5/'
)
ORDER="AH-5e-20 AH-3e-19 AH-1e-18 AH-5e-18 kc-0 kc-0.005 kc-0.05 median-kc0.2 median-kc0.005 r-15um table14"
for v in ${3:-$ORDER}; do
  [ -n "${EDIT[$v]+set}" ] || { echo "unknown variant $v (known: $ORDER)" >&2; exit 1; }
  for seed in 1 2 3; do
    for t in tensile confined_compression; do
      f="$OUT/$v-$t-$seed"
      [ -s "$f.json" ] && continue
      lab_spec "$t" 100 1 | sed -e "${EDIT[$v]}" -e "s/^seed: 1/seed: $seed/" > "$f.yaml"
      start=$(date +%s)
      "$DEMCAL" lab run "$f.yaml" > "$f.json" 2> "$f.err"
      echo "$v $t seed $seed: rc $?, $(( $(date +%s) - start )) s" >> "$OUT/times.txt"
    done
  done
done

python3 - "$OUT" ${3:-$ORDER} <<'PY'
import glob, json, os, statistics as st, sys
out, variants = sys.argv[1], sys.argv[2:]
cols = [("tensile", "tensile_strength", "kPa"), ("confined_compression", "compressibility", "%"),
        ("confined_compression", "k_load", "MPa"), ("confined_compression", "k_unload", "MPa"),
        ("confined_compression", "final_solid_fraction", "")]
print("%-15s" % "variant" + "".join("%-22s" % (m + (" " + u if u else "")) for _, m, u in cols)
      + "failed/flagged")
for v in variants:
    cells, bad = [], []
    for test, metric, _ in cols:
        vals = []
        for f in sorted(glob.glob(os.path.join(out, "%s-%s-[0-9].json" % (v, test)))):
            try:
                j = json.load(open(f))
            except ValueError:
                bad.append(os.path.basename(f)[:-5] + " failed")
                continue
            if metric in j.get("flags", {}):
                bad.append(os.path.basename(f)[:-5] + " flagged " + metric)
            vals.append(j["metrics"][metric])
        sd = " +- %.2g" % st.stdev(vals) if len(vals) > 1 else ""
        cells.append("%.3g%s (%d)" % (st.mean(vals), sd, len(vals)) if vals else "-")
    print("%-15s" % v + "".join("%-22s" % c for c in cells) + ", ".join(sorted(set(bad))))
PY
