#!/usr/bin/env bash
# Coordinator throughput, no physics: lease + complete per second with N in-process fake
# workers on loopback (real gRPC, real SQLite, synchronous=NORMAL) while 50 clients hold
# Watch streams on the campaign (1,088 jobs: 4 runs + 64 centre points, 16 replicates).
#   bench/coordinator.sh [BUILD_DIR] [WORKERS] [WATCHERS]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$root/build}
WORKERS=${2:-8}
WATCHERS=${3:-50}
nice -n 10 ninja -C "$BUILD" demcal-coordinator-bench >/dev/null
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
"$BUILD/bench/demcal-coordinator-bench" --workers "$WORKERS" --watchers "$WATCHERS" --dir "$TMP/db"
