#!/usr/bin/env bash
# The discover stage's time on a quiet host: each dataset the randomized bench kept (its --work
# folder, run with --keep) copied to a scratch folder and run through `groove run --force
# discover` alone, one at a time, with the accepted findings compared against the kept ones
# (effect, form, each parameter to 4 decimals). One line per dataset is appended to OUT:
# "index seconds same" or "index seconds DIFF <old> -> <new>"; then the median and largest time
# and the datasets over 10 s. Run nothing else beside it: the bench's own times are taken two
# streams at a time and are not comparable.
#
# Usage: tests/bench/discover_quiet.sh WORK_DIR OUT [index...]   # default: every kept case
#        GROOVE_BIN=path skips the release build.
set -euo pipefail
work=$1
out=$2
shift 2
repo="$(cd "$(dirname "$0")/../.." && pwd)"
if [ -z "${GROOVE_BIN:-}" ]; then
  (cd "$repo" && cargo build --release --locked --quiet --bin groove)
  GROOVE_BIN="${CARGO_TARGET_DIR:-$repo/target}/release/groove"
fi
if [ $# -eq 0 ]; then
  set -- $(ls "$work" | sed -n 's/^case-0*\([0-9][0-9]*\)$/\1/p' | sort -n)
fi
scratch=$(mktemp -d /tmp/groove-quiet.XXXXXX)
trap 'rm -rf "$scratch"' EXIT
for i in "$@"; do
  kept="$work/case-$(printf %03d "$i")"
  if [ ! -d "$kept" ]; then
    echo "no kept case $kept (run the bench with --keep; two streams keep two folders): skipped" >&2
    continue
  fi
  rm -rf "$scratch/case"
  cp -r "$kept" "$scratch/case"
  t=$(cd "$scratch/case" && "$GROOVE_BIN" run --force discover 2>&1 |
    sed -n 's/.*discover: ran in \([0-9.]*\) s.*/\1/p' || true)
  verdict=$(python3 - "$kept/reports/diagnosis.json" "$scratch/case/reports/diagnosis.json" <<'PY'
import json, sys
def accepted(path):
    d = json.load(open(path))
    return [(f["effect"], f["form"],
             sorted((k, round(v["value"], 4)) for k, v in f["parameters"].items()))
            for f in d["findings"] if f.get("accepted")]
a, b = accepted(sys.argv[1]), accepted(sys.argv[2])
print("same" if a == b else "DIFF %r -> %r" % ([x[:2] for x in a], [x[:2] for x in b]))
PY
  )
  echo "$i ${t:-failed} $verdict" >>"$out"
done
python3 - "$out" <<'PY'
import statistics, sys
rows = [l.split(maxsplit=2) for l in open(sys.argv[1]) if l[:1].isdigit()]
times = sorted((float(r[1]), r[0]) for r in rows if r[1] != "failed")
if times:
    print("%d datasets: median %.1f s, largest %.1f s (%s); over 10 s: %s" % (
        len(times), statistics.median(t for t, _ in times), times[-1][0], times[-1][1],
        " ".join(i for t, i in times if t > 10) or "none"))
print("findings differ in %d" % sum(r[2].startswith("DIFF") for r in rows if len(r) > 2))
PY
