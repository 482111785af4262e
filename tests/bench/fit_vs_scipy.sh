#!/usr/bin/env bash
# Fit the same synthetic single runs with groove (Rust, one core) and with SciPy's
# least_squares on the same closed-form model, same start values, same robust loss, and print
# the per-core speed ratio. Usage: tests/bench/fit_vs_scipy.sh [RUNS] [SCIPY_RUNS]
#   RUNS        runs the Rust bench fits (default 10000)
#   SCIPY_RUNS  how many of them SciPy fits (default 500; its rate is per run, so a subset suffices)
# Needs python3 with venv and network access for `pip install numpy scipy` (once).
set -euo pipefail
runs=${1:-10000}
scipy_runs=${2:-500}
root=$(cd "$(dirname "$0")/../.." && pwd)
work=${GROOVE_BENCH_DIR:-$root/target/fit_vs_scipy}
venv=$work/venv
mkdir -p "$work"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet numpy scipy
fi
# GROOVE_BENCH_CARGO_ARGS: extra cargo arguments, e.g. "--profile dev" on a machine where a
# release build of the dependencies is too costly (with CARGO_PROFILE_DEV_OPT_LEVEL=3 for groove).
(cd "$root" && cargo bench ${GROOVE_BENCH_CARGO_ARGS:-} --bench fit -- --runs "$runs" --dump "$work" --dump-count "$scipy_runs")
"$venv/bin/python" - "$work" "$scipy_runs" <<'PY'
import sys, time
import numpy as np
from scipy.optimize import least_squares, brentq

work, n_fit = sys.argv[1], int(sys.argv[2])
G = 9.81
S = np.sin(np.radians(70.6 / 2))
K = 2.5
KS2 = K * S * S

def positions(x, t):
    """z(t) = z0 + Δz(t + t0; v0, va0 = 0, μ, T): sliding with Coulomb friction and drag, then rolling."""
    z0, t0, v0, mu, T = x
    d = 1.0 if v0 > 0 else -1.0
    A = d * G * mu * T / S
    spin = d * K * G * mu
    g = lambda tt: (v0 + A) * np.exp(-tt / T) - A - S * spin * tt
    hi = 2.0 * (abs(v0) + abs(A)) / (G * mu / S + S * abs(spin))
    while g(hi) * d > 0:
        hi *= 2.0
    t1 = brentq(g, 0.0, hi, xtol=1e-15, rtol=1e-13)
    Te = T * (1 + KS2) / KS2
    tau = np.maximum(t + t0, 0.0)
    sl = T * (v0 + A) * (-np.expm1(-tau / T)) - A * tau
    z1 = T * (v0 + A) * (-np.expm1(-t1 / T)) - A * t1
    v1 = (v0 + A) * np.exp(-t1 / T) - A
    ro = z1 + v1 * Te * (-np.expm1(-(tau - t1) / Te))
    return z0 + np.where(tau < t1, sl, ro)

data = np.loadtxt(f"{work}/runs.csv", delimiter=",", skiprows=1)
starts = np.loadtxt(f"{work}/starts.csv", delimiter=",", skiprows=1)
rate_rust = float(open(f"{work}/rust_rate.txt").read())
run_idx = data[:, 0].astype(int)
bounds_at = np.searchsorted(run_idx, np.arange(len(starts) + 1))
n_fit = min(n_fit, len(starts))

def mad(r):
    return 1.4826 * np.median(np.abs(r - np.median(r)))

errs = []
t_start = time.process_time()
for i in range(n_fit):
    t = data[bounds_at[i]:bounds_at[i + 1], 1]
    z = data[bounds_at[i]:bounds_at[i + 1], 2]
    fps, z0, t0, v0, mu, T = starts[i, 1:7]
    x0 = np.array([z0, t0, v0, mu, T])
    lo = [-np.inf, 0.0, 1e-7 if v0 > 0 else -20.0, 1e-4, 1e-4]
    hi = [np.inf, 1.0 / fps, 20.0 if v0 > 0 else -1e-7, 5.0, 1e3]
    x0 = np.clip(x0, lo, hi)
    fun = lambda x: positions(x, t) - z
    scale = max(mad(fun(x0)), 1e-10)
    for _ in range(3):  # re-estimate the robust scale, as groove does
        res = least_squares(fun, x0, bounds=(lo, hi), loss="huber", f_scale=scale, x_scale="jac")
        x0 = res.x
        new = max(mad(res.fun), 1e-10)
        if abs(new - scale) <= 0.02 * scale:
            break
        scale = new
    errs.append(abs(res.x[2] / starts[i, 7] - 1.0))
secs = time.process_time() - t_start
rate_scipy = n_fit / secs
print(f"scipy least_squares: {n_fit} fits in {secs:.2f} CPU s = {rate_scipy:.1f} runs/s per core "
      f"(median |v0 error| {100 * np.median(errs):.3f} %, worst {100 * max(errs):.2f} %)")
print(f"groove (Rust, one core): {rate_rust:.0f} runs/s")
print(f"ratio groove / scipy per core: {rate_rust / rate_scipy:.0f}x")
PY
