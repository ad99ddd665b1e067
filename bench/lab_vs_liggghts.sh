#!/usr/bin/env bash
# Confined compression of a die bed by a strain-controlled piston, in demcal and in LIGGGHTS 3.8,
# from the same beds. For each seed (1, 2, 3):
#   1. demcal settles bench/lab_die_bed.yaml (1,000 spheres, radii 0.9/1.0/1.1 mm, in a die of
#      radius 10 mm; h0, the top of the highest sphere, about 25 mm) and writes the bed at rest as a LIGGGHTS data file
#      (--bed) and the piston, an STL disk covering the die at the bed top h0 (--piston-stl);
#   2. demcal (bench/lab_compression.yaml, 2 threads) and LIGGGHTS (bench/liggghts/
#      in.lab_compression, 2 MPI ranks) push that piston down at v = 10 mm/s to 10 % of h0,
#      recording the force on it every 50 steps; one code after the other; then, for the
#      timing only, the same on 1 thread and 1 rank.
# Same contact law everywhere, particle-wall included: Hertz (Y = 1e7 Pa, nu = 0.3, e = 0.5) +
# tangential history (mu = 0.5, kt = 8 G* sqrt(R* delta), no tangential damping); gravity on;
# dt = 1e-5 s (1/8 of the Rayleigh time of the smallest sphere, 7.8e-5 s) and skin 0.2 mm in both.
# Quasi-static: the inertial number I = (v/h0) d sqrt(rho/sigma) is printed per strain point; at
# 10 mm/s it was 1.1e-2 in the first 1 % band, where the piston touches only the top spheres
# (tens of Pa), and 9e-3 down to 3e-4 after (docs/lab-tests.md); the bench takes minutes.
# Prints, per strain point (the centre of each 1 % band of strain, stress = mean piston force
# over the band / die area), the mean +- std over the seeds per code and whether the two means
# agree within the combined spread sqrt(s_demcal^2 + s_liggghts^2), and the mean +- std of the
# per-bed difference demcal - LIGGGHTS (the same bed in both); then the wall times of the
# compressions (whole processes, summed over the seeds; 2 threads vs 2 ranks, then 1 vs 1) and,
# last, "ratio: X" = LIGGGHTS wall time / demcal wall time, 2 threads vs 2 ranks. The
# environment passes through (e.g. OMP_WAIT_POLICY for demcal's OpenMP threads).
# With DEMCAL_STEP=own, demcal takes its own time step instead of LIGGGHTS's: 0.2 of the
# Rayleigh time of the smallest sphere (`time_step_safety: 0.2`, docs/engine.md), and as many
# steps as that step needs for the same piston path; LIGGGHTS keeps dt = 1e-5 s, the step its
# users take. The stress-strain agreement stays the referee.
# Usage: bench/lab_vs_liggghts.sh [seeds...]   (default 1 2 3; a spread needs 2 or more);
#        DEMCAL=path/to/demcal DEMCAL_STEP=fixed|own
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
demcal=${DEMCAL:-$root/build/client/demcal}
seeds=("$@")
[ $# -gt 0 ] || seeds=(1 2 3)
speed=0.01      # piston speed (m/s)
strain=0.10     # final strain of the bed height
dt=1.0e-5       # time step (s), as in both scene files
own_safety=0.2  # DEMCAL_STEP=own: demcal's step, this fraction of the Rayleigh time
step_rule=${DEMCAL_STEP:-fixed}
case $step_rule in fixed|own) ;; *) echo "DEMCAL_STEP must be fixed or own" >&2; exit 2 ;; esac
every=50        # steps between force records
die=0.01        # die radius (m), as in bench/lab_die_bed.yaml
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

[ -x "$demcal" ] || { echo "build demcal first (scripts/build)" >&2; exit 1; }
command -v liggghts >/dev/null || { echo "liggghts not installed (scripts/setup)" >&2; exit 1; }

now() { date +%s.%N; }
json_field() { python3 -c "import json,sys; print(eval('json.load(sys.stdin)' + sys.argv[1]))" "$1"; }

# run_demcal DIR THREADS TAG: compresses DIR's bed; force series DIR/TAG.csv, report DIR/TAG.json.
run_demcal() {
  "$demcal" simulate "$1/compression.yaml" --threads "$2" --walls-csv "$1/$3.csv" > "$1/$3.json"
}
# run_liggghts DIR RANKS STEPS TAG: the same in LIGGGHTS; force series DIR/TAG.txt, log DIR/TAG.log.
# LIGGGHTS loses its messages when stdout is not a terminal: run it under script(1).
run_liggghts() {
  (cd "$1" && script -qc "mpirun --allow-run-as-root --oversubscribe -np $2 liggghts \
    -in in.lab_compression -var die $die -var speed $speed -var nsteps $3 -var every $every \
    -var dt $dt -var out $4.txt" /dev/null > "$4.log" 2>&1)
  grep -q "Loop time of" "$1/$4.log" || { echo "LIGGGHTS run failed:"; tail -20 "$1/$4.log"; exit 1; } >&2
}
# timed COMMAND...: runs it and prints its wall time (s).
timed() {
  local t0
  t0=$(now)
  "$@"
  python3 -c "print($(now) - $t0)"
}

for seed in "${seeds[@]}"; do
  d=$work/seed$seed
  mkdir -p "$d"
  sed "s/^seed: .*/seed: $seed/" "$root/bench/lab_die_bed.yaml" > "$d/die_bed.yaml"
  "$demcal" simulate "$d/die_bed.yaml" --bed "$d/bed.data" --piston-stl "$d/piston.stl" > "$d/settle.json"
  h0=$(json_field '["metrics"]["bed_top"]' < "$d/settle.json")
  steps=$(python3 -c "import math; print(math.ceil($strain * $h0 / ($speed * $dt)))")
  demcal_dt=$dt
  time_step_line="time_step: $dt"
  if [ "$step_rule" = own ]; then
    demcal_dt=$(python3 -c "import json; print($own_safety * json.load(open('$d/settle.json'))['critical_time_step'])")
    time_step_line="time_step_safety: $own_safety"
  fi
  demcal_steps=$(python3 -c "import math; print(math.ceil($strain * $h0 / ($speed * $demcal_dt)))")
  sed -e "s/velocity: \[0, 0, -0.01\]/velocity: [0, 0, -$speed]/" \
      -e "s/steps: [0-9]*, record_every: [0-9]*/steps: $demcal_steps, record_every: $every/" \
      -e "s/^time_step: .*/$time_step_line/" \
      "$root/bench/lab_compression.yaml" > "$d/compression.yaml"
  cp "$root/bench/liggghts/in.lab_compression" "$d/"
  {
    timed run_demcal "$d" 2 demcal
    timed run_liggghts "$d" 2 "$steps" liggghts
    timed run_demcal "$d" 1 demcal_serial
    timed run_liggghts "$d" 1 "$steps" liggghts_serial
  } | tr '\n' ' ' > "$d/wall_times"
  ran_dt=$(json_field '["time_step"]' < "$d/demcal.json")
  python3 -c "import sys; sys.exit(abs($ran_dt / $demcal_dt - 1) > 1e-9)" ||
    { echo "demcal ran at dt $ran_dt s, not the $demcal_dt s its steps were counted for" >&2; exit 1; }
  echo "seed $seed: h0 = $h0 m, demcal $demcal_steps steps of $demcal_dt s, LIGGGHTS $steps steps" \
    "of $dt s; wall times (s) demcal 2 threads, LIGGGHTS 2 ranks," \
    "demcal 1 thread, LIGGGHTS 1 rank: $(cat "$d/wall_times")" >&2
done

python3 - "$work" "$speed" "$dt" "$die" "${seeds[@]}" <<'PY'
import csv, json, math, re, statistics, sys
work, speed, dt, die = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
seeds = sys.argv[5:]
area = math.pi * die * die
bands = 10          # 1 % bands of strain from 0 to 10 %
rho, d_mean = 2500.0, 2.0e-3

def band_means(samples):
    """Mean stress (kPa) of (strain, stress) samples per 1 % band of strain."""
    sums, counts = [0.0] * bands, [0] * bands
    for eps, sigma in samples:
        k = math.ceil(eps * 100.0) - 1
        if 0 <= k < bands:
            sums[k] += sigma
            counts[k] += 1
    return [s / c / 1e3 for s, c in zip(sums, counts)]

def demcal_samples(d, h0):
    rows = [r for r in csv.DictReader(open(f"{d}/demcal.csv")) if int(float(r["wall"])) == 2]
    return [(-float(r["dz"]) / h0, float(r["fz"]) / area) for r in rows]

def liggghts_samples(d, h0):
    out = []
    for line in open(f"{d}/liggghts.txt"):
        if line.startswith("#"):
            continue
        step, fz = line.split()
        out.append((int(step) * dt * speed / h0, float(fz) / area))
    return out

curves = {"demcal": [], "LIGGGHTS": []}
times = {"demcal": 0.0, "LIGGGHTS": 0.0}
serial = {"demcal": 0.0, "LIGGGHTS": 0.0}
loops = {"demcal": 0.0, "LIGGGHTS": 0.0}
h0s = []
for s in seeds:
    d = f"{work}/seed{s}"
    h0 = json.load(open(f"{d}/settle.json"))["metrics"]["bed_top"]
    h0s.append(h0)
    curves["demcal"].append(band_means(demcal_samples(d, h0)))
    curves["LIGGGHTS"].append(band_means(liggghts_samples(d, h0)))
    td, tl, td1, tl1 = map(float, open(f"{d}/wall_times").read().split())
    times["demcal"] += td
    times["LIGGGHTS"] += tl
    serial["demcal"] += td1
    serial["LIGGGHTS"] += tl1
    loops["demcal"] += json.load(open(f"{d}/demcal.json"))["phases"][0]["wall_seconds"]
    loops["LIGGGHTS"] += float(re.findall(r"Loop time of ([0-9.eE+-]+)", open(f"{d}/liggghts.log").read())[-1])

def mean_std(values):
    return statistics.mean(values), (statistics.stdev(values) if len(values) > 1 else 0.0)

h0 = statistics.mean(h0s)
print(f"confined compression, {len(seeds)} beds (seeds {' '.join(seeds)}), h0 = {h0 * 1e3:.2f} mm, "
      f"piston {speed * 1e3:g} mm/s, LIGGGHTS dt {dt:g} s; stress in kPa, mean +- std over the beds")
print(f"{'strain %':>8} {'demcal':>16} {'LIGGGHTS':>16} {'diff':>8} {'spread':>8} {'agree':>6} "
      f"{'paired diff':>17} {'I':>8}")
agreed = 0
for k in range(bands):
    demcal, liggghts = [c[k] for c in curves["demcal"]], [c[k] for c in curves["LIGGGHTS"]]
    md, sd = mean_std(demcal)
    ml, sl = mean_std(liggghts)
    spread = math.hypot(sd, sl)
    agree = abs(md - ml) <= spread
    agreed += agree
    # The same bed in both codes: the per-bed difference, free of the bed-to-bed scatter.
    mp, sp = mean_std([a - b for a, b in zip(demcal, liggghts)])
    inertial = speed / h0 * d_mean * math.sqrt(rho / (0.5 * (md + ml) * 1e3))
    print(f"{k + 0.5:8.1f} {md:8.3f} +- {sd:5.3f} {ml:8.3f} +- {sl:5.3f} {md - ml:8.3f} {spread:8.3f} "
          f"{'yes' if agree else 'no':>6} {mp:8.3f} +- {sp:5.3f} {inertial:8.1e}")
print(f"agree at {agreed} of {bands} strain points")
print(f"loop time, summed over the beds: demcal {loops['demcal']:.2f} s (2 threads), "
      f"LIGGGHTS {loops['LIGGGHTS']:.2f} s (2 ranks)")
print(f"wall time, summed over the beds: demcal {times['demcal']:.2f} s (2 threads), "
      f"LIGGGHTS {times['LIGGGHTS']:.2f} s (2 ranks)")
print(f"wall time, summed over the beds: demcal {serial['demcal']:.2f} s (1 thread), "
      f"LIGGGHTS {serial['LIGGGHTS']:.2f} s (1 rank); ratio 1 vs 1: "
      f"{serial['LIGGGHTS'] / serial['demcal']:.3f}")
print(f"ratio: {times['LIGGGHTS'] / times['demcal']:.3f}")
PY
