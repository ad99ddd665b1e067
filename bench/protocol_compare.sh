#!/usr/bin/env bash
# Two builds of demcal side by side on the same lab test: the metrics of each over several seeds
# (mean +- sample std), whether their means differ by less than the combined seed-to-seed
# spread, and the steps and wall time of each. Used to show that a faster protocol changes no
# metric beyond the seed-to-seed spread.
# Usage: bench/protocol_compare.sh DEMCAL_A DEMCAL_B [TEST] [PARTICLES] [SEEDS] [MATERIALS] [SETTINGS]
#   e.g. bench/protocol_compare.sh old/demcal build/client/demcal confined_compression 200 1,2,3 \
#          "hertz lh100 lh220"
# Materials are bench/materials/NAME.yaml; SETTINGS is a YAML flow mapping added to particles
# (default "wall_stiffness_factor: 3"). The runs of A and B go two at a time, one thread each.
# KEEP=DIR keeps the specs and results there. PREP_A / PREP_B (YAML flow mappings, e.g. PREP_B="{method: growth}") give side A or B the
# material's preparation, so that one build compares two preparations:
#   PREP_B="{method: growth}" bench/protocol_compare.sh build/client/demcal build/client/demcal
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
A=$(realpath "$1"); B=$(realpath "$2")
TEST=${3:-confined_compression}
N=${4:-200}
SEEDS=${5:-1,2,3}
MATERIALS=${6:-hertz lh100 lh220}
EXTRA=${7:-"wall_stiffness_factor: 3"}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for mat in $MATERIALS; do
  for seed in ${SEEDS//,/ }; do
    for side in A B; do
      prep_var="PREP_$side"
      { printf "test: %s\nsettings: {particles: %s, %s}\nseed: %s\nthreads: 1\n" "$TEST" "$N" "$EXTRA" "$seed"
        grep -v '^#' "$root/bench/materials/$mat.yaml"
        [ -z "${!prep_var:-}" ] || printf "  preparation: %s\n" "${!prep_var}"; } > "$work/$side-$mat-$seed.yaml"
    done
    "$A" lab run "$work/A-$mat-$seed.yaml" > "$work/A-$mat-$seed.json" 2> "$work/A-$mat-$seed.err" &
    "$B" lab run "$work/B-$mat-$seed.yaml" > "$work/B-$mat-$seed.json" 2> "$work/B-$mat-$seed.err" &
    wait
  done
done
python3 - "$work" "$MATERIALS" "$SEEDS" <<'PY'
import json, os, statistics as st, sys
work, materials, seeds = sys.argv[1], sys.argv[2].split(), sys.argv[3].split(',')
def load(tag, mat, seed):
    p = os.path.join(work, f"{tag}-{mat}-{seed}.json")
    try:
        return json.load(open(p))
    except Exception:
        err = open(p[:-5] + ".err").read().strip().splitlines()
        print(f"  {tag} {mat} seed {seed}: FAILED {err[-1] if err else ''}")
        return None
for mat in materials:
    runs = {t: [r for r in (load(t, mat, s) for s in seeds) if r] for t in "AB"}
    print(f"== {mat} ({len(runs['A'])} + {len(runs['B'])} runs)")
    if not runs["A"] or not runs["B"]:
        continue
    for m in sorted(runs["A"][0]["metrics"]):
        va = [r["metrics"][m] for r in runs["A"]]; vb = [r["metrics"][m] for r in runs["B"]]
        sa = st.stdev(va) if len(va) > 1 else 0.0; sb = st.stdev(vb) if len(vb) > 1 else 0.0
        diff = st.mean(vb) - st.mean(va); spread = (sa * sa + sb * sb) ** 0.5
        ok = "within spread" if abs(diff) <= spread else "OUTSIDE spread"
        print(f"  {m:22s} A {st.mean(va):10.4g} +- {sa:<9.3g} B {st.mean(vb):10.4g} +- {sb:<9.3g} {ok}")
    for t in "AB":
        steps = [r.get("cost", {}).get("steps") for r in runs[t]]
        wall = [r.get("cost", {}).get("wall_seconds") for r in runs[t]]
        unreached = sum(1 for r in runs[t] for p in r.get("cost", {}).get("phases", []) if not p["reached"])
        flagged = sum(1 for r in runs[t] if r.get("flags"))
        print(f"  {t}: steps {steps}, wall s {[round(w, 1) for w in wall if w]}, phases short of target {unreached}, runs with flags {flagged}")
        for s, r in zip(seeds, runs[t]):
            phases = ", ".join(f"{p['name']} {p['steps']}" for p in r["cost"]["phases"] if p["name"] in ("fill", "settle") or p["name"].startswith("prepare") or p["name"] == "load 1")
            bed = r.get("series", {}).get("settled_bed", {}).get("rows", [[]])[0]
            bed = f", settled bed phi {bed[1]:.4f} Z {bed[2]:.2f}" if len(bed) == 3 else ""
            print(f"     seed {s}: {phases}{bed}")
PY
[ -z "${KEEP:-}" ] || cp -r "$work/." "$KEEP/"
