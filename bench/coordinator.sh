#!/usr/bin/env bash
# Coordinator throughput, no physics: lease + complete per second with N in-process fake
# workers on loopback (real gRPC, real SQLite, synchronous=NORMAL) while 50 clients hold
# Watch streams on the campaign ((2^FACTORS + CENTRE) x REPLICATES jobs; by default 1,088: 4 runs +
# 64 centre points, 16 replicates), and the start of a coordinator on the submitted file.
#   bench/coordinator.sh [BUILD_DIR] [WORKERS] [WATCHERS] [FACTORS] [CENTRE] [REPLICATES]
#   e.g. bench/coordinator.sh build 8 0 9 0 16   (8,192 jobs, the most a campaign may have)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$root/build}
WORKERS=${2:-8}
WATCHERS=${3:-50}
FACTORS=${4:-2}
CENTRE=${5:-64}
REPLICATES=${6:-16}
nice -n 10 ninja -C "$BUILD" demcal-coordinator-bench >/dev/null
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
"$BUILD/bench/demcal-coordinator-bench" --workers "$WORKERS" --watchers "$WATCHERS" --factors "$FACTORS" \
  --centre-points "$CENTRE" --replicates "$REPLICATES" --dir "$TMP/db"
