#!/usr/bin/env bash
# Campaign benchmark for issue 13: how `groove run aggregate` (ingest → fit → aggregate) scales
# with the number of recordings. Prints, never asserts.
#
# Usage: tests/bench/campaign.sh [--100k] [--sizes "1000 10000"] [--no-scipy] [--parquet]
#   --sizes "N …"  campaign sizes in runs (default "1000 10000"); each is half 316, half 440c
#   --100k         also the 100,000-run campaign (≈ 2.6 GB of CSV, minutes, several GB of disk)
#   --no-scipy     skip the SciPy least_squares comparison (needs python3 with numpy + scipy)
#   --stage S      run `groove run S` instead of `groove run aggregate` (e.g. `fit`: ingest and
#                  the fits only, where aggregate's Theil–Sen bootstrap, O(runs²), dominates)
#   --parquet      also write each campaign as trajectories.parquet (`groove synth --format
#                  parquet`, the same values) and time `groove run ingest` on a fresh store for
#                  the CSV and the Parquet form, alternated, each round; prints Parquet's speed-up
#   --repeat R     measure each size below 100,000 R times (default 3; 100,000 once): each
#                  round a fresh project, cold, edit, no-op; the table gives each row's median
#                  over the rounds with its range (a shared host varies by 10–15 % run to run)
# Environment:
#   GROOVE_BIN            the binary (default target/release/groove if built, else target/debug/groove)
#   GROOVE_CAMPAIGN_DIR   scratch folder (default target/campaign); datasets are kept and reused
#   GROOVE_SCIPY_RUNS     how many runs SciPy fits for its per-core rate (default 200)
#   GROOVE_BENCH_CARGO_ARGS  passed to `cargo bench --bench fit` for the SciPy dump, e.g.
#                         "--profile dev" where a release build of polars is too costly
#
# For each size N:
#   1. `groove synth` writes an N-run single-sphere dataset in the interchange format from a truth
#      file made of `data/truth/truth.toml` (same physics, camera: 10 kHz, 0.06 s = 600 frames per
#      run) with `count = N/2` per material. Kept under $GROOVE_CAMPAIGN_DIR/data-N.
#   2. A fresh project (a copy of pipeline.toml, empty store) and three measured runs of
#      `groove run aggregate`: cold; after editing one z value of one recording; and a no-op.
#      Wall, CPU (user+sys) and peak RSS come from the kernel's rusage of that one child
#      (os.wait4, the same numbers `/usr/bin/time -v` prints); the per-stage times are the lines
#      groove appends to .groove/run.log. The 1-minute load average is printed beside each row
#      (the machine may be shared).
#   3. Bytes stored per run: size of .groove/ (and of .groove/objects) after the cold run / N.
# On 1,000 runs, the SciPy ratio: tests/bench/fit_vs_scipy.sh's approach, reused rather than
# copied — `cargo bench --bench fit -- --runs 1000 --dump …` (before the campaigns) writes the
# runs and groove's start values, and the SciPy program embedded in fit_vs_scipy.sh (its
# `<<'PY'` block, extracted at run time) fits them with least_squares on the same closed-form
# model, right after each 1,000-run cold round (a shared host's speed drifts over minutes). SciPy
# seconds for 1,000 runs (per core) / groove's cold wall time of the same round = the issue's
# "× SciPy"; the median over the rounds is printed with each round's ratio.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
sizes="1000 10000"
scipy=1
stage=aggregate
repeat=3
parquet=0
while [ $# -gt 0 ]; do
    case "$1" in
        --100k) sizes="$sizes 100000" ;;
        --sizes) sizes="$2"; shift ;;
        --no-scipy) scipy=0 ;;
        --stage) stage="$2"; shift ;;
        --repeat) repeat="$2"; shift ;;
        --parquet) parquet=1 ;;
        -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d'; exit 0 ;;
        *) echo "campaign.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
    esac
    shift
done
if [ -z "${GROOVE_BIN:-}" ]; then
    if [ -x "$root/target/release/groove" ]; then GROOVE_BIN=$root/target/release/groove
    else GROOVE_BIN=$root/target/debug/groove; fi
fi
[ -x "$GROOVE_BIN" ] || { echo "campaign.sh: no binary at $GROOVE_BIN; build it (cargo build --locked --tests) or set GROOVE_BIN" >&2; exit 2; }
work=${GROOVE_CAMPAIGN_DIR:-$root/target/campaign}
scipy_runs=${GROOVE_SCIPY_RUNS:-200}
mkdir -p "$work"
table=$work/table.tsv
: > "$table"
export GROOVE_CAMPAIGN_LOG=$work/groove.log  # groove's own output
: > "$GROOVE_CAMPAIGN_LOG"
echo "binary: $GROOVE_BIN ($(stat -c %y "$GROOVE_BIN" | cut -d. -f1))"
echo "machine: $(nproc) cores, $(awk '/MemTotal/ {printf "%.1f GiB", $2/1048576}' /proc/meminfo), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"

# Run one command as a child; append "label wall cpu rss_mb load" to the table; print its stages.
measure() { # label store_dir cmd...
    local label=$1 store=$2; shift 2
    local before=0
    [ -f "$store/run.log" ] && before=$(wc -l < "$store/run.log")
    # the script's own writes (an edit of the dataset, a deleted store) flushed first, so that
    # the kernel's writeback of them does not share the cores with the run measured
    sync
    python3 - "$label" "$table" "$@" <<'PY'
import os, sys, time
label, table, cmd = sys.argv[1], sys.argv[2], sys.argv[3:]
load0 = open("/proc/loadavg").read().split()[0]
t0 = time.perf_counter()
log = os.open(os.environ["GROOVE_CAMPAIGN_LOG"], os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
pid = os.fork()
if pid == 0:  # the child: groove, its chatter to the log
    os.dup2(log, 1)
    os.dup2(log, 2)
    os.execvp(cmd[0], cmd)
_, status, ru = os.wait4(pid, 0)
wall = time.perf_counter() - t0
load1 = open("/proc/loadavg").read().split()[0]
code = os.waitstatus_to_exitcode(status)
if code != 0:
    sys.exit(f"campaign.sh: {label}: groove exited with {code}; see {os.environ['GROOVE_CAMPAIGN_LOG']}")
cpu = ru.ru_utime + ru.ru_stime
rss_mb = ru.ru_maxrss / 1024  # KiB on Linux
with open(table, "a") as f:
    f.write(f"{label}\t{wall:.3f}\t{cpu:.3f}\t{ru.ru_utime:.3f}\t{ru.ru_stime:.3f}\t{rss_mb:.0f}\t{load0}/{load1}\n")
print(f"  {label}: wall {wall:.2f} s, cpu {cpu:.2f} s (user {ru.ru_utime:.2f} + sys {ru.ru_stime:.2f}), "
      f"peak rss {rss_mb:.0f} MB, load {load0} → {load1}")
PY
    [ -f "$store/run.log" ] && tail -n +$((before + 1)) "$store/run.log" | sed 's/^/    /'
    return 0
}

# Change one z value of one recording (the middle run's 100th row) by 1 µm, in place; the
# original line is kept in DIR/.edit-undo.json for restore_edit.
edit_one() { # dataset_dir
    python3 - "$1" <<'PY'
import json, sys
d = sys.argv[1]
runs = [l.split(",")[0] for l in open(f"{d}/runs.csv").read().splitlines()[1:]]
target = runs[len(runs) // 2]
path = f"{d}/trajectories.csv"
data = open(path, "rb").read()
key = ("\n" + target + ",").encode()
at = data.index(key)
for _ in range(100):  # the 100th row of that run (rows of a run are contiguous in synth output)
    nxt = data.index(b"\n", at + 1)
    if not data.startswith(key, nxt):
        break
    at = nxt
end = data.index(b"\n", at + 1)
old = data[at + 1:end].decode()
fields = old.split(",")
fields[-1] = f"{float(fields[-1]) + 1e-6:.9f}"
new = ",".join(fields)
json.dump({"offset": at + 1, "old": old, "new": new}, open(f"{d}/.edit-undo.json", "w"))
data = data[:at + 1] + new.encode() + data[end:]
open(path, "wb").write(data)
print(f"  edited run {target}: z_m of frame {fields[2]} += 1 µm")
PY
}

# Undo edit_one, so the dataset is the synthesized one again and can be reused.
restore_edit() { # dataset_dir
    python3 - "$1" <<'PY'
import json, os, sys
d = sys.argv[1]
u = json.load(open(f"{d}/.edit-undo.json"))
path = f"{d}/trajectories.csv"
data = open(path, "rb").read()
at, old, new = u["offset"], u["old"].encode(), u["new"].encode()
assert data[at:at + len(new)] == new, "the edited line moved; delete the dataset folder"
open(path, "wb").write(data[:at] + old + data[at + len(new):])
os.remove(f"{d}/.edit-undo.json")
PY
}

# SciPy's runs and program, prepared before the campaigns so that SciPy can be timed right after
# each 1,000-run cold round: the host's speed drifts over minutes, and a ratio of two times
# taken ten minutes apart measures the drift as much as groove.
if [ "$scipy" = 1 ]; then
    dump=$work/scipy
    mkdir -p "$dump"
    echo "scipy: groove's fit bench dumps 1000 runs and its start values (cargo bench ${GROOVE_BENCH_CARGO_ARGS:-} --bench fit)"
    (cd "$root" && cargo bench --locked ${GROOVE_BENCH_CARGO_ARGS:-} --bench fit -- --runs 1000 --dump "$dump" --dump-count "$scipy_runs") | sed 's/^/  /'
    # The SciPy program of fit_vs_scipy.sh, taken from that file so the model lives in one place.
    sed -n "/<<'PY'$/,/^PY$/p" "$root/tests/bench/fit_vs_scipy.sh" | sed '1d;$d' > "$dump/scipy_fit.py"
fi

# Time SciPy least_squares on the dumped runs (one core) and add its seconds per 1,000 runs to
# the table.
scipy_round() {
    python3 "$dump/scipy_fit.py" "$dump" "$scipy_runs" | tee "$dump/scipy.txt" | sed 's/^/    /'
    local rate
    rate=$(sed -n 's/.* = \([0-9.]*\) runs\/s per core.*/\1/p' "$dump/scipy.txt")
    printf '1000\tscipy\t%s\n' "$(python3 -c "print(f'{1000 / $rate:.2f}')")" >> "$table"
}

for n in $sizes; do
    data=$work/data-$n
    if [ ! -f "$data/runs.csv" ] || [ "$(($(wc -l < "$data/runs.csv") - 1))" != "$n" ] || [ -f "$data/.edit-undo.json" ] || [ -f "$data/.edited" ] || [ ! -f "$work/truth-$n.toml" ]; then
        rm -rf "$data"
        truth=$work/truth-$n.toml
        python3 - "$root/data/truth/truth.toml" "$truth" "$n" <<'PY'
import sys
src, out, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
head = open(src).read().split("[[runs]]")[0]
runs = "".join(f'''
[[runs]]
experiment = "single"
material = "{m}"
count = {c}
v0_mps = [0.005, 0.1]
directions = "both"
duration_s = 0.06
''' for m, c in (("316", n // 2), ("440c", n - n // 2)))
open(out, "w").write(head + runs)
PY
        t0=$(date +%s.%N)
        "$GROOVE_BIN" synth --truth "$truth" --out "$data" > /dev/null
        echo "campaign $n: synthesized in $(python3 -c "print(f'{$(date +%s.%N) - $t0:.1f}')") s"
    fi
    rows=$(($(wc -l < "$data/trajectories.csv") - 1))
    echo "campaign $n: $rows rows, $(du -b "$data/trajectories.csv" | cut -f1) bytes of trajectories.csv"
    proj=$work/proj-$n
    rounds=$repeat
    [ "$n" -ge 100000 ] && rounds=1
    for round in $(seq 1 "$rounds"); do
        [ "$rounds" -gt 1 ] && echo "  round $round of $rounds"
        rm -rf "$proj"
        mkdir -p "$proj"
        cp "$root/pipeline.toml" "$proj/"
        run=("$GROOVE_BIN" run "$stage" --config "$proj/pipeline.toml" --data "$data" --out "$proj/reports")
        measure "$n cold" "$proj/.groove" "${run[@]}"
        if [ "$scipy" = 1 ] && [ "$n" = 1000 ]; then
            scipy_round
        fi
        if [ "$round" = 1 ]; then
            store=$(du -sb "$proj/.groove" | cut -f1)
            objects=$(du -sb "$proj/.groove/objects" | cut -f1)
            files=$(find "$proj/.groove" -type f | wc -l)
            echo "  store after cold run: $store bytes ($((store / n)) per run; objects $((objects / n)) per run), $files files"
            printf '%s\tstore\t%s\t%s\t%s\n' "$n" "$((store / n))" "$((objects / n))" "$files" >> "$table"
        fi
        edit_one "$data"
        measure "$n edit" "$proj/.groove" "${run[@]}"
        measure "$n no-op" "$proj/.groove" "${run[@]}"
        restore_edit "$data"
    done
    if [ "$parquet" = 1 ]; then
        pq=$work/data-$n-parquet
        if [ ! -f "$pq/trajectories.parquet" ] || ! cmp -s "$pq/runs.csv" "$data/runs.csv"; then
            rm -rf "$pq"
            "$GROOVE_BIN" synth --truth "$work/truth-$n.toml" --out "$pq" --format parquet > /dev/null
        fi
        echo "campaign $n: $(du -b "$pq/trajectories.parquet" | cut -f1) bytes of trajectories.parquet (the same values)"
        for round in $(seq 1 "$rounds"); do
            for form in csv parquet; do
                from=$data
                [ "$form" = parquet ] && from=$pq
                rm -rf "$proj"
                mkdir -p "$proj"
                cp "$root/pipeline.toml" "$proj/"
                measure "$n ingest $form" "$proj/.groove" "$GROOVE_BIN" run ingest --config "$proj/pipeline.toml" --data "$from" --out "$proj/reports"
            done
        done
    fi
done

python3 - "$table" <<'PY'
import sys
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1])]
print()
import os
load = os.getloadavg()[0]
if load > os.cpu_count():
    print(f"note: load average {load:.1f} on {os.cpu_count()} cores: wall times are inflated by waiting for a core; compare CPU times")
print("| campaign | rounds | wall s (median, range) | cpu s (user+sys) of that round | peak RSS MB, max | load 1-min (before/after), first round |")
print("| --- | --- | --- | --- | --- | --- |")
from statistics import median
labels = []
for r in rows:
    if r[1] not in ("store", "scipy") and r[0] not in labels:
        labels.append(r[0])
def summary(label):
    rs = [r for r in rows if r[0] == label]
    walls = sorted(float(r[1]) for r in rs)
    mid = min(rs, key=lambda r: abs(float(r[1]) - median(walls)))  # the round of median wall
    return rs, walls, mid
for label in labels:
    rs, walls, mid = summary(label)
    spread = f" ({walls[0]:.2f}–{walls[-1]:.2f})" if len(walls) > 1 else ""
    print(f"| {label} | {len(rs)} | {median(walls):.2f}{spread} | {float(mid[2]):.2f} ({float(mid[3]):.2f}+{float(mid[4]):.2f}) "
          f"| {max(int(r[5]) for r in rs)} | {rs[0][6]} |")
print()
for r in rows:
    if r[1] == "store":
        print(f"{r[0]} runs: {r[2]} bytes stored per run (.groove/), {r[3]} in objects/, {r[4]} files")
for label in labels:
    if label.endswith(" ingest csv") and label.replace("csv", "parquet") in labels:
        csv = [r for r in rows if r[0] == label]
        pq = [r for r in rows if r[0] == label.replace("csv", "parquet")]
        wall = lambda rs: median(float(r[1]) for r in rs)
        cpu = lambda rs: median(float(r[2]) for r in rs)
        print(f"{label.split()[0]} runs, `groove run ingest` on a fresh store: Parquet {wall(csv) / wall(pq):.1f}x faster "
              f"than CSV by wall ({wall(pq):.2f} against {wall(csv):.2f} s, medians), {cpu(csv) / cpu(pq):.1f}x by CPU; issue 13's target 3x")
scipy = [float(r[2]) for r in rows if r[1] == "scipy"]
if scipy and "1000 cold" in labels:
    colds = [float(r[1]) for r in rows if r[0] == "1000 cold"]
    ratios = sorted(s / w for s, w in zip(scipy, colds))
    print(f"scipy least_squares, 1000 runs on one core, timed right after each 1000-run cold round: "
          f"{median(scipy):.1f} s ({min(scipy):.1f}–{max(scipy):.1f}); groove's cold run against the SciPy of its round: "
          f"{', '.join(f'{r:.1f}x' for r in ratios)} → median {median(ratios):.1f}x by wall time; target >= 50x")
PY
