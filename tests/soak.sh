#!/usr/bin/env bash
# kill -9 soak: groove is killed at random moments during every verb that writes (`run`,
# `run --remote`, a `run --data` onto another dataset (`switch`), `gc`, `clean`, `verify`,
# `publish`, `push`, `pull`) and the read-only ones
# (`status`, `dag`); after each kill the store, the reports folder and the bundle are checked,
# then the project must recover with one ordinary command. Runnable by hand, not part of CI:
#
#     bash tests/soak.sh [KILLS_PER_VERB] [GROOVE_BINARY] [VERBS]
#
# (default 20 kills per verb, target/debug/groove — build it first with `cargo build`; VERBS a
# space-separated subset, default all). It prints one line per kill and, at the end, the counts
# that must be 0:
#   corrupt entries  – store entries that do not parse or name a missing or damaged object
#   partial outputs  – files in reports/ that are neither the old nor the new content, temp
#                      leftovers (.NAME.groove-*) still there after the next run or publish, and
#                      bundles that fail `sha256sum -c`
#   failed recoveries – a next `groove run` (or publish) that does not exit 0 with every stage
#                       fresh, or one that says it reused every stage while the store lacks
#                       an object it names (what a killed `clean` must never leave)
set -u
KILLS=${1:-20}
REPO=$(cd "$(dirname "$0")/.." && pwd)
GROOVE=${2:-$REPO/target/debug/groove}
VERBS=${3:-run remote switch gc clean verify publish push pull status dag}
[ -x "$GROOVE" ] || { echo "soak: no groove binary at $GROOVE; run cargo build first" >&2; exit 2; }
WORK=$(mktemp -d /tmp/groove-soak.XXXXXX)
trap 'rm -rf "$WORK"' EXIT
cd "$WORK" || exit 2

"$GROOVE" synth --truth "$REPO/tests/fixtures/truths/e2e_small.toml" --out dataset >/dev/null || exit 2
# the other dataset of `switch`: the same truth with another seed (every stage's result differs)
sed 's/^seed = .*/seed = 8/' "$REPO/tests/fixtures/truths/e2e_small.toml" > other_truth.toml
"$GROOVE" synth --truth other_truth.toml --out other >/dev/null || exit 2
mkdir -p project/data
cp dataset/*.csv project/data/
cp "$REPO/pipeline.toml" project/
cd project || exit 2
echo "soak: reference run (this takes a while)"
"$GROOVE" run >/dev/null 2>&1 || { echo "soak: the reference run failed" >&2; exit 2; }
mkdir -p ../remote
REMOTE="file://$WORK/remote"

# sha256 of every file under reports/ (relative path, hash) but staged leftovers (.NAME.groove-*,
# files or folders), as the reference
snapshot() { (cd reports && find . -type f ! -path '*/.*' -print0 | sort -z | xargs -0 sha256sum); }
snapshot > ../reference.sums

corrupt=0 partial=0 failed=0 mid=0

# entries that do not parse or reference a missing or damaged object
check_store() {
  python3 - "$PWD/.groove" <<'EOF'
import hashlib, json, os, sys
store = sys.argv[1]
bad = 0
entries = os.path.join(store, "entries")
for name in sorted(os.listdir(entries)) if os.path.isdir(entries) else []:
    try:
        entry = json.load(open(os.path.join(entries, name)))
        hashes = []
        for out in entry["outputs"].values():
            hashes += [out["sha256"]] if out["type"] == "file" else list(out["items"].values())
        for h in hashes:
            data = open(os.path.join(store, "objects", h[:2], h[2:]), "rb").read()
            if hashlib.sha256(data).hexdigest() != h:
                raise ValueError("damaged object " + h)
    except Exception as e:
        print("  corrupt entry", name, e, file=sys.stderr)
        bad += 1
print(bad)
EOF
}

# files in reports/ that differ from the reference (torn or mixed), and temp leftovers
check_reports() {
  local torn leftovers
  torn=$( (cd reports && sha256sum --quiet -c ../../reference.sums 2>/dev/null) | wc -l)
  leftovers=$(find reports -name '.*.groove-*' | wc -l)
  echo $((torn + leftovers))
}

recover() {
  local out missing
  missing=$(check_store)
  if ! out=$("$GROOVE" run 2>&1); then echo "  recovery run failed" >&2; return 1; fi
  if [ "$missing" -gt 0 ] && echo "$out" | grep -q "0 stages run"; then
    echo "  recovery run reused every stage over $missing broken entries" >&2; return 1
  fi
  if "$GROOVE" status --json | grep -q '"stale"'; then echo "  stale after recovery" >&2; return 1; fi
  return 0
}

# $@: the command; kills it after 1 ms – 1.5 s, drawn evenly in the logarithm so that commands
# of a few milliseconds are hit as often as long ones (or lets it finish). Sets `landed` to 1
# when the kill found the command still running.
landed=0
kill_at_random() {
  local delay pid
  delay=$(python3 -c 'import random; print(round(10 ** random.uniform(-3, 0.176), 4))')
  "$@" >/dev/null 2>&1 &
  pid=$!
  sleep "$delay"
  if kill -9 "$pid" 2>/dev/null; then landed=1; else landed=0; fi
  wait "$pid" 2>/dev/null
}

random_stage() {
  python3 -c 'import random; print(random.choice(["ingest","fit","aggregate","simulate","figures","report"]))'
}

nverbs=0
for verb in $VERBS; do
  nverbs=$((nverbs + 1))
  for i in $(seq 1 "$KILLS"); do
    case $verb in
      run)
        kill_at_random "$GROOVE" run --force "$(random_stage)" ;;
      remote)
        kill_at_random "$GROOVE" run --remote "$REMOTE" --force "$(random_stage)" ;;
      clean)
        kill_at_random "$GROOVE" clean ;;
      verify)
        kill_at_random "$GROOVE" verify ;;
      push)
        # a fresh remote now and then, so that there is something to upload
        [ $((i % 3)) -eq 0 ] && rm -rf ../remote && mkdir -p ../remote
        kill_at_random "$GROOVE" push --remote "$REMOTE" ;;
      pull)
        "$GROOVE" push --remote "$REMOTE" >/dev/null 2>&1
        [ $((i % 2)) -eq 0 ] && "$GROOVE" clean >/dev/null 2>&1
        kill_at_random "$GROOVE" pull --remote "$REMOTE" ;;
      switch)
        # the reports of another dataset, killed while they replace these: its results are in
        # the store (one whole run first), so the killed run spends its time writing reports/
        if [ "$i" -eq 1 ]; then
          "$GROOVE" run --data ../other >/dev/null 2>&1; snapshot > ../other.sums
          "$GROOVE" run >/dev/null 2>&1
        fi
        kill_at_random "$GROOVE" run --data ../other ;;
      status | dag)
        kill_at_random "$GROOVE" "$verb" ;;
      gc)
        # leave something for gc to drop: a run with another seed
        sed -i 's/^seed = .*/seed = '"$RANDOM"'/' pipeline.toml
        "$GROOVE" run --force ingest >/dev/null 2>&1
        cp "$REPO/pipeline.toml" pipeline.toml
        "$GROOVE" run >/dev/null 2>&1
        kill_at_random "$GROOVE" gc ;;
      publish)
        kill_at_random "$GROOVE" publish --to ../bundle ;;
    esac
    c=$(check_store); p=0; switched=
    # right after the kill the reports may lack nothing and hold no torn file (after a killed
    # `switch`, each file is this dataset's or the other's: a mix until the next run)
    if [ "$verb" = switch ]; then
      snapshot > ../now.sums
      t=$(( $(grep -cvxF -f <(cat ../reference.sums ../other.sums) ../now.sums) + \
            $(comm -23 <(cut -c67- ../reference.sums | sort) <(cut -c67- ../now.sums | sort) | wc -l) ))
      # how far the killed run got: files already the other dataset's (those that differ)
      switched=$(grep -cxF -f <(grep -vxF -f ../reference.sums ../other.sums) ../now.sums)
    else
      t=$( (cd reports && sha256sum --quiet -c ../../reference.sums 2>/dev/null) | wc -l)
    fi
    p=$((p + t))
    if ! recover; then failed=$((failed + 1)); fi
    p=$((p + $(check_reports)))
    if [ "$verb" = publish ]; then
      if ! "$GROOVE" publish --to ../bundle >/dev/null 2>&1; then failed=$((failed + 1)); echo "  publish after kill failed" >&2; fi
      (cd ../bundle && sha256sum --quiet -c SHA256SUMS >/dev/null 2>&1) || p=$((p + 1))
      p=$((p + $(find .. -maxdepth 1 -name '.bundle.groove-*' | wc -l)))
    fi
    corrupt=$((corrupt + c)); partial=$((partial + p))
    mid=$((mid + landed))
    echo "soak: $verb kill $i ($([ "$landed" = 1 ] && echo "killed mid-command" || echo "it had finished")): corrupt entries $c, partial outputs $p${switched:+, $switched files switched before the kill}"
  done
done
echo "soak: $((nverbs * KILLS)) kills ($mid mid-command): corrupt entries $corrupt, partial outputs $partial, failed recoveries $failed"
[ "$corrupt" -eq 0 ] && [ "$partial" -eq 0 ] && [ "$failed" -eq 0 ]
