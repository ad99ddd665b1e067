#!/usr/bin/env bash
# libFuzzer with AddressSanitizer and UndefinedBehaviorSanitizer on the readers of untrusted input:
# the STL reader (io::read_stl), the CSV table reader of `analyze` (io::read_csv), the YAML scene
# parser (io::read_scene), the CLI's campaign spec parser (cli::parse_campaign_spec) and the
# coordinator's Submit on a store with its oracle (fuzz_submit); HARNESSES="..." picks some. Builds
# the harnesses of tests/fuzz with clang in BUILD_DIR (-DDEMCAL_FUZZ=ON: the harnesses and what
# they link only), replays the regression inputs, runs each harness for RUNS executions from its
# seed corpus (tests/fuzz/corpus; the campaign harnesses start from examples/*campaign*.yaml, as
# text and as the SubmitRequest the CLI sends) (a run stops at its first finding, which libFuzzer writes to a
# crash-/leak-/timeout-/oom- file), and prints per harness: executions, crashes (crash-*, leak-*),
# timeouts and out-of-memory inputs. Exit status 1 if any harness crashed.
#   bench/fuzz.sh [BUILD_DIR] [RUNS]     e.g. bench/fuzz.sh build-fuzz 1000000
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$root/build-fuzz}
RUNS=${2:-1000000}
"$root/scripts/setup" > /dev/null
cmake -S "$root" -B "$BUILD" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DDEMCAL_FUZZ=ON -DDEMCAL_BUILD_TESTS=OFF -DDEMCAL_BUILD_BENCH=OFF > /dev/null
ninja -C "$BUILD" fuzz_stl_reader fuzz_scene_yaml fuzz_csv_reader fuzz_campaign_yaml fuzz_submit \
  submit_seeds > /dev/null
# Copies the seed corpus of harness $1 into directory $2.
seed() {
  case $1 in
    campaign_yaml) cp "$root"/examples/*campaign*.yaml "$2/" ;;
    submit) "$BUILD/tests/fuzz/submit_seeds" "$2" "$root"/examples/*campaign*.yaml ;;
    *) cp "$root/tests/fuzz/corpus/${1%%_*}"/* "$2/" ;;
  esac
}
status=0
printf "%-18s %10s %8s %9s %5s\n" harness executions crashes timeouts ooms
for h in ${HARNESSES:-stl_reader csv_reader scene_yaml campaign_yaml submit}; do
  out="$BUILD/fuzz-$h"; rm -rf "$out"; mkdir -p "$out/corpus"
  seed "$h" "$out/corpus"
  regressions="$root/tests/fuzz/regressions/$h"
  if [ -n "$(find "$regressions" -type f 2> /dev/null)" ]; then
    (cd "$out" && "$BUILD/tests/fuzz/fuzz_$h" "$regressions"/* > replay.log 2>&1) ||
      { echo "$h: a regression input fails again ($out/replay.log)"; status=1; }
  fi
  (cd "$out" && "$BUILD/tests/fuzz/fuzz_$h" -runs="$RUNS" -timeout=10 -rss_limit_mb=4096 \
     -max_len=65536 -print_final_stats=1 corpus \
     > run.log 2>&1) || true
  execs=$(grep -o "stat::number_of_executed_units: *[0-9]*" "$out/run.log" | tail -1 | grep -o "[0-9]*$" ||
          grep -o "#[0-9]*" "$out/run.log" | tail -1 | tr -d '#')
  found() { find "$out" -maxdepth 1 -name "$1-*" | wc -l; }
  crashes=$(($(found crash) + $(found leak)))
  timeouts=$(found timeout)
  ooms=$(found oom)
  printf "%-18s %10s %8s %9s %5s\n" "$h" "${execs:-?}" "$crashes" "$timeouts" "$ooms"
  [ "$crashes" -eq 0 ] || status=1
done
exit $status
