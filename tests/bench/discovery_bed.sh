#!/usr/bin/env bash
# The randomized discovery bench on the release build: datasets drawn by the independent
# simulator (tests/support/indsim), 150 with effects in every place and 50 nulls over every noise
# model, each through `groove run`, scored against its truth; prints the tables per place, shape
# and noise model and its own time. Results are appended one line per dataset, so a later call
# resumes where the last one stopped.
#
# Usage: tests/bench/discovery_bed.sh                  # the full set (hours with today's discovery)
#        tests/bench/discovery_bed.sh --quick          # three small datasets (minutes)
#        tests/bench/discovery_bed.sh --from 0 --to 40 # a chunk; rerun to resume
#        tests/bench/discovery_bed.sh --table          # the tables of the results so far
#        tests/bench/discovery_bed.sh --from 200 --to 264 --results fresh.jsonl
#                                                      # draws beyond the set: never tuned on
# Options: --results FILE (default $CARGO_TARGET_DIR/discovery_bed/results[-quick].jsonl),
#          --work DIR (scratch folders), --keep (keep each dataset and its reports).
#          GROOVE_BIN=path skips the release build.
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
cd "$repo"
if [ -z "${GROOVE_BIN:-}" ]; then
  echo "building the release binary..." >&2
  cargo build --release --locked --quiet --bin groove
  GROOVE_BIN="${CARGO_TARGET_DIR:-$repo/target}/release/groove"
fi
export GROOVE_BIN
exec cargo bench --locked --quiet --bench discovery_bed -- "$@"
