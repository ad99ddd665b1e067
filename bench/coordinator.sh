#!/usr/bin/env bash
# Coordinator throughput, no physics: lease + complete per second with N in-process fake
# workers on loopback (real gRPC, real SQLite, synchronous=NORMAL) while 50 clients hold
# Watch streams on the campaign ((2^FACTORS + CENTRE) x REPLICATES jobs; by default 1,088: 4 runs +
# 64 centre points, 16 replicates), and the start of a coordinator on the submitted file.
#   bench/coordinator.sh [BUILD_DIR] [WORKERS] [WATCHERS] [FACTORS] [CENTRE] [REPLICATES] [waiting]
#   e.g. bench/coordinator.sh build 8 0 9 0 16   (8,192 jobs, the most a campaign may have)
#   `waiting`: each run is a confined compression and the tensile test that waits for it, so half
#   the queue waits (bench/coordinator.sh build 8 0 9 0 8 waiting: 8,192 jobs, 4,096 waiting)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$root/build}
WORKERS=${2:-8}
WATCHERS=${3:-50}
FACTORS=${4:-2}
CENTRE=${5:-64}
REPLICATES=${6:-16}
WAITING=${7:-}
[ -z "$WAITING" ] || [ "$WAITING" = waiting ] || { echo "$0: the 7th argument is 'waiting' or none" >&2; exit 2; }
nice -n 10 ninja -C "$BUILD" demcal-coordinator-bench >/dev/null
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
"$BUILD/bench/demcal-coordinator-bench" --workers "$WORKERS" --watchers "$WATCHERS" --factors "$FACTORS" \
  --centre-points "$CENTRE" --replicates "$REPLICATES" --dir "$TMP/db" ${WAITING:+--waiting}
