#!/usr/bin/env bash
# No-op `groove run` on a large DAG of trivial `command` stages, timed for one binary and, side by
# side, for a baseline binary (an older build) on the same project and store:
#
#     bash tests/bench/noop.sh [STAGES] [GROOVE_BINARY] [BASELINE_BINARY] [ROUNDS]
#
# (default 10,000 stages, target/debug/groove, no baseline, 5 rounds). The stages form 10
# independent chains (stage i reads stage i-10's output). The project is built once with
# GROOVE_BINARY (one `sh` per stage: minutes at 10,000), then each binary's no-op run is timed
# ROUNDS times, alternating; the lines give the median wall time, user+system CPU time and peak
# memory (GNU time), and the ratio baseline / groove. Prints; asserts nothing (the target, a
# 10,000-stage no-op within 1 s, is read off the line). Runnable by hand, not part of CI.
set -u
STAGES=${1:-10000}
REPO=$(cd "$(dirname "$0")/../.." && pwd)
GROOVE=${2:-$REPO/target/debug/groove}
BASELINE=${3:-}
ROUNDS=${4:-5}
# absolute paths: the timed runs happen inside the scratch project
GROOVE=$(realpath "$GROOVE" 2>/dev/null || echo "$GROOVE")
[ -z "$BASELINE" ] || BASELINE=$(realpath "$BASELINE" 2>/dev/null || echo "$BASELINE")
[ -x "$GROOVE" ] || { echo "noop: no groove binary at $GROOVE; run cargo build first" >&2; exit 2; }
[ -z "$BASELINE" ] || [ -x "$BASELINE" ] || { echo "noop: no baseline binary at $BASELINE" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "noop: needs GNU time at /usr/bin/time" >&2; exit 2; }
WORK=$(mktemp -d /tmp/groove-noop.XXXXXX)
trap 'rm -rf "$WORK"' EXIT

python3 - "$WORK" "$STAGES" <<'EOF'
import sys
work, n = sys.argv[1], int(sys.argv[2])
lines = ["[project]", "seed = 1"]
for i in range(n):
    source = '"seed.txt"' if i < 10 else f'"s{i - 10}:o"'
    lines += [
        "", f"[stages.s{i}]", 'kind = "command"',
        f'cmd = "cat {{in.x}} > {{out.o}}; echo {i} >> {{out.o}}"',
        f"inputs = {{ x = {source} }}", f'outputs = {{ o = "reports/s{i}.txt" }}',
    ]
open(f"{work}/pipeline.toml", "w").write("\n".join(lines) + "\n")
open(f"{work}/seed.txt", "w").write("seed\n")
EOF
cd "$WORK" || exit 2
echo "noop: building $STAGES stages once with $GROOVE"
start=$(date +%s.%N)
"$GROOVE" run >/dev/null 2>&1 || { echo "noop: the first run failed" >&2; exit 2; }
echo "noop: first run $(python3 -c "print(f'{$(date +%s.%N) - $start:.1f}')") s"

# one no-op run: "wall cpu maxrss_kb"; a run that is not a no-op (it ran a stage) is an error
time_noop() {
  local out
  out=$( { /usr/bin/time -o "$WORK/.time" -f "%e %U %S %M" "$1" run >"$WORK/.err" 2>&1; } 2>&1; cat "$WORK/.time")
  grep -q " 0 stages run" "$WORK/.err" || { echo "noop: $1 ran stages: $(tail -c 300 "$WORK/.err")" >&2; exit 2; }
  tail -n 1 <<<"$out" | awk '{printf "%s %.3f %s\n", $1, $2 + $3, $4}'
}

: >"$WORK/.groove.times" ; : >"$WORK/.baseline.times"
for _ in $(seq 1 "$ROUNDS"); do
  time_noop "$GROOVE" >>"$WORK/.groove.times"
  [ -z "$BASELINE" ] || time_noop "$BASELINE" >>"$WORK/.baseline.times"
done
median() { sort -n -k"$2" "$1" | awk -v k="$2" '{v[NR]=$k} END {print v[int((NR+1)/2)]}'; }
g_wall=$(median "$WORK/.groove.times" 1); g_cpu=$(median "$WORK/.groove.times" 2); g_mem=$(median "$WORK/.groove.times" 3)
echo "noop: load average $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
printf "noop: %s stages, nothing changed: groove   %6.2f s wall, %6.2f s cpu, %5d MB (%s)\n" \
  "$STAGES" "$g_wall" "$g_cpu" $((g_mem / 1024)) "$GROOVE"
if [ -n "$BASELINE" ]; then
  b_wall=$(median "$WORK/.baseline.times" 1); b_cpu=$(median "$WORK/.baseline.times" 2); b_mem=$(median "$WORK/.baseline.times" 3)
  printf "noop: %s stages, nothing changed: baseline %6.2f s wall, %6.2f s cpu, %5d MB (%s)\n" \
    "$STAGES" "$b_wall" "$b_cpu" $((b_mem / 1024)) "$BASELINE"
  python3 -c "print(f'noop: baseline / groove: {$b_wall / $g_wall:.1f}x wall, {$b_cpu / max($g_cpu, 0.001):.1f}x cpu')"
fi
