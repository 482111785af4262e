#!/usr/bin/env bash
# Discovery power, measured the way a judge would: for each truth fixture in
# tests/fixtures/truths/ and several seeds, synthesize a dataset, run the whole pipeline through
# the release binary (`groove run --config --data --out`), read diagnosis.json and score it.
#
# Prints one table: effect, seeds, named-correctly rate (the accepted findings are exactly the
# expected effects, each with its form), size-recovered rate (every expected parameter within
# 15 % of the truth), and for the null fixtures the false-accept rate (any accepted finding). Not
# run in CI (minutes of CPU).
#
# Usage: tests/bench/discovery_power.sh            # 5 seeds per effect, 20 seeds per null
#        EFFECTS= NULLS=null tests/bench/discovery_power.sh   # only the null, 20 seeds (empty = none)
#        SEEDS="1 2" NULL_SEEDS="1 2 3 4" EFFECTS="groove_tilt" NULLS="null" tests/bench/discovery_power.sh
#        GROOVE_BIN=target/debug/groove tests/bench/discovery_power.sh   # skip the release build
# Needs: cargo, python3 (standard library only).
set -euo pipefail

repo="$(cd "$(dirname "$0")/../.." && pwd)"
seeds="${SEEDS:-1 2 3 4 5}"
null_seeds="${NULL_SEEDS:-$(seq -s ' ' 1 20)}"
effects="${EFFECTS-quadratic_drag saturating_drag rolling_resistance groove_tilt velocity_dependent_friction position_force waviness_0p5mm waviness_0p8mm waviness_3mm waviness_5mm localized_force time_force two_effects resistance_and_waviness runs_that_stop waviness_trapped}"
nulls="${NULLS-null null_quantized null_small}"
work="$(mktemp -d "${TMPDIR:-/tmp}/groove-power.XXXXXX")"
trap 'rm -rf "$work"' EXIT

# What each fixture should give, one accepted finding a line: the diagnosis.json effect id, a
# fragment of its form, then parameter=truth pairs.
expect() {
  case "$1" in
    quadratic_drag) echo "velocity_dependent_drag quadratic c_per_m=40.0" ;;
    saturating_drag) echo "velocity_dependent_drag saturating tp_s_per_mps=1.1" ;;
    rolling_resistance) echo "rolling_resistance resistance deceleration_mps2=0.03924" ;; # c g, c = 0.004
    groove_tilt) echo "groove_tilt tilt alpha_deg=0.2" ;;
    velocity_dependent_friction) echo "velocity_dependent_friction mu(u) v_c_mps_316=0.004 v_c_mps_440c=0.004" ;;
    position_force) echo "position_dependent_force periodic amplitude_mps2=0.1 wavelength_m=8.0e-3" ;;
    waviness_0p5mm) echo "position_dependent_force periodic amplitude_mps2=0.06 wavelength_m=0.5e-3" ;;
    waviness_0p8mm) echo "position_dependent_force periodic amplitude_mps2=0.06 wavelength_m=0.8e-3" ;;
    waviness_3mm | waviness_trapped) echo "position_dependent_force periodic amplitude_mps2=0.05 wavelength_m=3.0e-3" ;;
    waviness_5mm) echo "position_dependent_force periodic amplitude_mps2=0.05 wavelength_m=5.0e-3" ;;
    localized_force) echo "position_dependent_force localized amplitude_mps2=0.3 centre_m=2.0e-3 width_m=0.3e-3" ;;
    time_force) echo "time_dependent_force periodic amplitude_mps2=0.3 frequency_hz=150" ;;
    two_effects)
      echo "groove_tilt tilt alpha_deg=0.05"
      echo "position_dependent_force periodic amplitude_mps2=0.05 wavelength_m=2.0e-3"
      ;;
    runs_that_stop) echo "rolling_resistance resistance coefficient=0.004" ;;
    resistance_and_waviness)
      echo "rolling_resistance resistance coefficient=0.004"
      echo "position_dependent_force periodic amplitude_mps2=0.05 wavelength_m=3.0e-3"
      ;;
    null | null_quantized | null_small) ;;
    *) echo "unknown fixture $1" >&2; exit 2 ;;
  esac
}

if [ -n "${GROOVE_BIN:-}" ]; then
  groove="$GROOVE_BIN" # an already built binary (e.g. to try the script on a dev build)
else
  echo "building the release binary..." >&2
  (cd "$repo" && cargo build --release --quiet --bin groove)
  groove="${CARGO_TARGET_DIR:-$repo/target}/release/groove"
fi

# One dataset and one pipeline run; prints "<named 0|1> <sized 0|1> <accepted ids> <seconds>".
score() {
  local fixture="$1" seed="$2" dir="$work/$1-$2"
  mkdir -p "$dir"
  expect "$fixture" >"$dir/expect.txt"
  sed "s/^seed = .*/seed = $seed/" "$repo/tests/fixtures/truths/$fixture.toml" >"$dir/truth.toml"
  cp "$repo/pipeline.toml" "$dir/pipeline.toml"
  "$groove" synth --truth "$dir/truth.toml" --out "$dir/data" >/dev/null
  local start end
  start=$(date +%s.%N)
  if ! "$groove" run --config "$dir/pipeline.toml" --data "$dir/data" --out "$dir/reports" \
    >"$dir/run.log" 2>&1; then
    echo "  $fixture seed $seed: groove run failed:" >&2
    tail -5 "$dir/run.log" >&2
    echo "0 0 FAILED 0"
    return
  fi
  end=$(date +%s.%N)
  python3 - "$dir/reports/diagnosis.json" "$dir/expect.txt" "$start" "$end" <<'PY'
import json, sys
path, expect, start, end = sys.argv[1:]
d = json.load(open(path))
acc = [f for f in d["findings"] if f["accepted"]]
want = [line.split() for line in open(expect) if line.strip()]
match = []
for effect, form, *_ in want:
    hit = [f for f in acc if f["effect"] == effect and form in f["form"]]
    match.append(hit[0] if hit else None)
named = int(len(acc) == len(want) and all(match))
sized = named
for f, (_, _, *pairs) in zip(match, want):
    for pair in pairs:
        name, truth = pair.split("=")
        got = f["parameters"].get(name, {}).get("value") if f else None
        if got is None or abs(got - float(truth)) > 0.15 * abs(float(truth)):
            sized = 0
ids = ",".join(f["effect"] for f in acc) or "-"
print(named if want else 0, sized if want else 0, ids, f"{float(end) - float(start):.1f}")
PY
}

rows=()
for fixture in $effects $nulls; do
  case " $nulls " in *" $fixture "*) list="$null_seeds" ;; *) list="$seeds" ;; esac
  n=0 named=0 sized=0 false_acc=0 failed=0 secs=0
  for seed in $list; do
    read -r a b ids t < <(score "$fixture" "$seed")
    echo "  $fixture seed $seed: accepted [$ids] named=$a sized=$b (${t} s)" >&2
    n=$((n + 1)) named=$((named + a)) sized=$((sized + b))
    if [ "$ids" = FAILED ]; then
      failed=$((failed + 1))
    elif [ "$ids" != "-" ]; then
      false_acc=$((false_acc + 1))
    fi
    secs=$(python3 -c "print($secs + $t)")
  done
  rows+=("$fixture $n $named $sized $false_acc $failed $secs")
done

echo
printf '| %-28s | %5s | %-16s | %-17s | %-13s | %6s | %9s |\n' effect seeds "named correctly" "size within 15 %" "false accept" failed "s per run"
printf '|%s|%s|%s|%s|%s|%s|%s|\n' "$(printf -- '-%.0s' {1..30})" "-------" "------------------" "-------------------" "---------------" "--------" "-----------"
for r in "${rows[@]}"; do
  read -r fixture n named sized false_acc failed secs <<<"$r"
  per=$(python3 -c "print(f'{$secs / $n:.1f}')")
  if [ -z "$(expect "$fixture")" ]; then
    printf '| %-28s | %5d | %-16s | %-17s | %-13s | %6d | %9s |\n' "$fixture (nothing missing)" "$n" "n/a" "n/a" "$false_acc/$n" "$failed" "$per"
  else
    printf '| %-28s | %5d | %-16s | %-17s | %-13s | %6d | %9s |\n' "$fixture" "$n" "$named/$n" "$sized/$n" "n/a" "$failed" "$per"
  fi
done
