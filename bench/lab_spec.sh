# Sourced by bench/lab.sh and bench/bed_size.sh: `lab_spec TEST N THREADS` prints the lab-run
# spec of TEST at N particles for the material bench/materials/$MATERIAL.yaml (seed 1). Piston
# tests use wall_stiffness_factor 3 and the tensile test wall_k2_factor 1, as
# examples/lh220_diagnosis_campaign.yaml; everything else is each test's default. The rotating
# drum is sized by its geometry: it gets the drum (D x 0.44 D, 43 % fill) that holds about N of
# the material's simulated spheres (monodisperse radius x the kottlan2018 factor). PREP (a YAML
# flow mapping, e.g. PREP="{method: growth}") gives the material that preparation.
lab_spec_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

# drum_mm N: the diameter and length (mm) of the seed-shaped drum that holds N of the material's
# spheres: N (4/3 pi r^3) = 0.43 (pi D^2 / 4) (0.44 D) 0.6 (rotating_drum's defaults).
drum_mm() {
  python3 - "$1" "$lab_spec_root/bench/materials/$MATERIAL.yaml" <<'PY'
import math, re, sys
text = open(sys.argv[2]).read()
r = float(re.search(r"radius:\s*([0-9.eE+-]+)", text).group(1))
f = re.search(r"kottlan2018, factor:\s*([0-9.eE+-]+)", text)
r *= float(f.group(1)) if f else 1.0
d = (int(sys.argv[1]) * 4 / 3 * math.pi * r**3 / (0.43 * math.pi / 4 * 0.44 * 0.6)) ** (1 / 3)
print("%.2f %.2f" % (1e3 * d, 0.44e3 * d))
PY
}

lab_spec() {
  local test=$1 n=$2 threads=$3 settings dmm wmm
  case $test in
    confined_compression|wall_friction) settings="{particles: $n, wall_stiffness_factor: 3}" ;;
    tensile) settings="{particles: $n, wall_stiffness_factor: 3, wall_k2_factor: 1}" ;;
    rotating_drum) read -r dmm wmm < <(drum_mm "$n"); settings="{diameter: $dmm, length: $wmm}" ;;
    *) settings="{particles: $n}" ;;
  esac
  printf "test: %s\nsettings: %s\nseed: 1\nthreads: %s\n" "$test" "$settings" "$threads"
  grep -v '^#' "$lab_spec_root/bench/materials/$MATERIAL.yaml"
  [ -z "${PREP:-}" ] || printf "  preparation: %s\n" "$PREP"
}
