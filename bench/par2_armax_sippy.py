#!/usr/bin/env python3
"""ARMAX(32,32,26,0) on the Par2 GU log: sysid against SIPPY in the same run.

Usage:
    python3 bench/par2_armax_sippy.py --sysid BUILD/sysid --data BUILD/data [--na 32 --nb 32 --nc 26]
           [--sippy-mode ILLS] [--max-iterations 200]

Times `sysid armax` (wall, one run, the CLI including CSV reading) and SIPPY's
system_identification(..., 'ARMAX', ARMAX_mod=...) on the same estimation log,
then scores both on the validation log the same way: simulation from rest of
B/A u (nk 0), measured and simulated outputs through the same zero-phase
5th-order Butterworth low-pass at 120 Hz (1.2 x the excited band), fit % as in
DESIGN.md. Prints one RESULT line per tool, the time ratio and a VERDICT; exits 1
when the target (>= 20x, a better in-band fit, sysid converged) is not met. Peers are bench
dependencies only (pip install sippy-unipi scipy), not project dependencies.
"""
import argparse
import json
import subprocess
import tempfile
import time

import numpy as np
from scipy import signal


def load(path):
    d = np.genfromtxt(path, delimiter=",", names=True)
    return d["u"], d["y"]


def in_band_fit(b, a, u_val, y_val, u_off, y_off):
    y_hat = signal.lfilter(b, a, u_val - u_off) + y_off
    sos = signal.butter(5, 120.0, fs=2000.0, output="sos")
    y_f, yh_f = signal.sosfiltfilt(sos, y_val), signal.sosfiltfilt(sos, y_hat)
    return 100.0 * (1.0 - np.linalg.norm(y_f - yh_f) / np.linalg.norm(y_f - y_f.mean()))


def run_sysid(exe, est, val, na, nb, nc, max_iterations):
    with tempfile.TemporaryDirectory() as tmp:
        out = f"{tmp}/m.json"
        cmd = [exe, "armax", est, "--inputs", "u", "--outputs", "y", "--na", str(na), "--nb", str(nb), "--nc", str(nc),
               "--nk", "0", "--max-iterations", str(max_iterations), "--out", out, "--write-unconverged"]
        t0 = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        status = "ok" if p.returncode == 0 else f"exit{p.returncode}"
        m = json.load(open(out))
    a = np.array(m["A"][0])
    b = np.array(m["B"][0][0])
    u_off, y_off = m.get("input_offset", [0.0])[0], m.get("output_offset", [0.0])[0]
    return wall, status, b, a, u_off, y_off


def run_sippy(u, y, na, nb, nc, mode, max_iterations):
    from sippy_unipi import system_identification
    t0 = time.perf_counter()
    model = system_identification(y.reshape(1, -1), u.reshape(1, -1), "ARMAX", centering="MeanVal", tsample=0.0005,
                                  ARMAX_orders=[na, nb, nc, 0], ARMAX_mod=mode, max_iterations=max_iterations)
    wall = time.perf_counter() - t0
    num = np.asarray(model.NUMERATOR).ravel() if hasattr(model, "NUMERATOR") else None
    den = np.asarray(model.DENOMINATOR).ravel() if hasattr(model, "DENOMINATOR") else None
    # model.G is a python-control TransferFunction in z: num/den coefficient lists.
    b = np.asarray(model.G.num[0][0], dtype=float)
    a = np.asarray(model.G.den[0][0], dtype=float)
    # Align the z-polynomials to q^-1 form (same length, leading zeros of b kept).
    n = max(len(a), len(b))
    a = np.concatenate([np.zeros(n - len(a)), a])
    b = np.concatenate([np.zeros(n - len(b)), b])
    return wall, b / a[0], a / a[0], num, den


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--sysid", required=True)
    p.add_argument("--data", required=True)
    p.add_argument("--na", type=int, default=32)
    p.add_argument("--nb", type=int, default=32)
    p.add_argument("--nc", type=int, default=26)
    p.add_argument("--sippy-mode", default="ILLS")
    p.add_argument("--max-iterations", type=int, default=200)
    a = p.parse_args()
    est, val = f"{a.data}/par2_gu.csv", f"{a.data}/par2_gu_val.csv"
    u, y = load(est)
    u_val, y_val = load(val)
    wall, status, b, den, u_off, y_off = run_sysid(a.sysid, est, val, a.na, a.nb, a.nc, a.max_iterations)
    fit_sysid = in_band_fit(np.concatenate([b, np.zeros(max(0, len(den) - len(b)))]), den, u_val, y_val, u_off, y_off)
    print(f"RESULT tool=sysid status={status} wall_s={wall:.3f} in_band_fit={fit_sysid:.2f}", flush=True)
    t_sippy, bs, as_, _, _ = run_sippy(u, y, a.na, a.nb, a.nc, a.sippy_mode, a.max_iterations)
    fit_sippy = in_band_fit(bs, as_, u_val, y_val, u.mean(), y.mean())
    print(f"RESULT tool=sippy mode={a.sippy_mode} wall_s={t_sippy:.3f} in_band_fit={fit_sippy:.2f}", flush=True)
    ratio = t_sippy / wall
    print(f"RATIO sippy/sysid = {ratio:.1f} (target >= 20, with a better fit)")
    # The target as the exit status: a NaN SIPPY fit counts as worse.
    met = status == "ok" and ratio >= 20.0 and not (fit_sippy >= fit_sysid)
    print("VERDICT " + ("met" if met else "NOT met"))
    return 0 if met else 1


if __name__ == "__main__":
    raise SystemExit(main())
