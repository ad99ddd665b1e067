#!/usr/bin/env bash
# The bed size by the seeds' rule for one lab test and material (docs/lab-tests.md, "Bed size by
# the seeds' rule"): `demcal lab study --particles COUNTS --seeds SEEDS` of bench/lab_spec.sh's
# spec, its study.json, runs.csv and summary.csv written to OUT, and a table printed.
#   bench/bed_size.sh [BUILD_DIR] TEST [COUNTS] [SEEDS] [OUT] [THREADS]
#   e.g. MATERIAL=lh220 bench/bed_size.sh build confined_compression 250,500,1000,2000 3 out/cc
# Not part of ctest.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$root/build}
TEST=${2:?lab test name}
COUNTS=${3:-250,500,1000,2000}
SEEDS=${4:-3}
MATERIAL=${MATERIAL:-lh220}
OUT=${5:-$root/out/bed_size/$MATERIAL-$TEST}
THREADS=${6:-1}
DEMCAL="$BUILD/client/demcal"
[ -x "$DEMCAL" ] || { echo "no $DEMCAL; build the demcal target first" >&2; exit 1; }
source "$root/bench/lab_spec.sh"
mkdir -p "$OUT"
lab_spec "$TEST" "${COUNTS%%,*}" "$THREADS" > "$OUT/spec.yaml"
start=$(date +%s)
"$DEMCAL" lab study "$OUT/spec.yaml" --particles "$COUNTS" --seeds "$SEEDS" --out "$OUT" > /dev/null
echo "material $MATERIAL, $TEST, particles $COUNTS, $SEEDS seeds: $(( $(date +%s) - start )) s"
python3 - "$OUT/study.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
names = sorted(j["converged_from"])
print("%-9s %8s  %s" % ("particles", "wall_s", "  ".join("%-24s" % n for n in names)))
for run in j["runs"]:
    wall = sum(r["wall_seconds"] for r in run["replicates"])
    cells = []
    for n in names:
        flag = "!" if n in run["flagged"] else ""
        cells.append("%-24s" % ("%.4g +- %.2g%s" % (run["metrics"][n], run["spread"][n], flag)))
    print("%-9d %8.0f  %s" % (run["particles"], wall, "  ".join(cells)))
print("converged from: " + ", ".join("%s %s" % (n, j["converged_from"][n]) for n in names))
print("chosen: %s" % j["chosen"])
PY
