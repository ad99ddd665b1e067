#!/usr/bin/env bash
# Cost of rigid clumps against spheres: the same lab test (default rotating_drum, 300 bodies)
# of one material, once with spheres and once with rods of aspect ratio 2 (rigid multisphere
# clumps), run one after the other. Prints both run times and, last, "ratio: X" = rods / spheres.
# The body count, the material and the seed are the same; only material.shape differs.
# Usage: bench/clumps_vs_spheres.sh [test] [bodies] [threads]   (default rotating_drum 300 1)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
demcal=${DEMCAL:-$root/build/client/demcal}
test=${1:-rotating_drum}
bodies=${2:-300}
threads=${3:-1}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
[ -x "$demcal" ] || { echo "build demcal first (scripts/build)" >&2; exit 1; }

# The drum is sized by its geometry: D x 0.44 D at 43 % fill holds N spheres of 1 mm radius when
# N (4/3 pi) 1e-9 = 0.43 (pi D^2 / 4) 0.44 D 0.6.
if [ "$test" = rotating_drum ]; then
  settings=$(python3 -c "import math; d = ($bodies * 4e-9 / 3 / (0.43 / 4 * 0.44 * 0.6)) ** (1 / 3); print('{diameter: %.2f, length: %.2f}' % (1e3 * d, 0.44e3 * d))")
else
  settings="{particles: $bodies}"
fi
# spec SHAPE_LINE: the lab spec, with the given shape line in the material (or none).
spec() {
  cat <<YAML
test: $test
settings: $settings
seed: 1
threads: $threads
material:
  particle_law:
    normal: {model: hertz, youngs_modulus: 5.0e6, poisson_ratio: 0.3, restitution: 0.3}
    tangential: {model: history, mu_s: 0.5}
  sizes: {monodisperse: {radius: 0.001}}
  density: 2500
$1
YAML
}
spec "" > "$work/spheres.yaml"
spec "  shape: {kind: rod, aspect_ratio: 2}" > "$work/rods.yaml"

# seconds SPEC: wall time of one `demcal lab run`.
seconds() {
  local t0 t1
  t0=$(date +%s.%N)
  "$demcal" lab run "$1" > "$1.json"
  t1=$(date +%s.%N)
  python3 -c "print($t1 - $t0)"
}

t_spheres=$(seconds "$work/spheres.yaml")
t_rods=$(seconds "$work/rods.yaml")
printf '%s, %s bodies, %s thread(s)\n' "$test" "$bodies" "$threads"
printf 'spheres: %.2f s\n' "$t_spheres"
printf 'rods (aspect ratio 2): %.2f s\n' "$t_rods"
python3 -c "print('ratio: %.2f' % ($t_rods / $t_spheres))"
