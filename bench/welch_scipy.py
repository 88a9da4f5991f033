#!/usr/bin/env python3
"""Welch H1 of an 8x8 log of 10^6 samples (nfft 4096): sysid against scipy.signal.csd.

Runs the C++ benchmark (sysid_bench_welch), which makes the data, times sysid::frf
(minimum of 3) and writes the data and its H1 as raw float64/complex128 files; then
times scipy on exactly those samples, minimum of 3:

  G_uu[i, :] = csd(u_i, U)   (8 calls, each broadcasting u_i against all 8 inputs)
  G_uy[i, :] = csd(u_i, Y)   (8 calls)
  G_yy       = welch(Y)      (diagonal; H1 itself does not need it, sysid's coherences do)
  H1^T       = solve(G_uu, G_uy) per frequency (numpy.linalg.solve, batched)

with the same settings as sysid's (Hann periodic window, 50 % overlap, constant
detrend per segment, density scaling), and checks that both give the same H1.

scipy is not a dependency of sysid; this script is only for the benchmark.
Usage: welch_scipy.py --bench PATH/sysid_bench_welch [--samples 1000000] [--nfft 4096] [--repeats 3]
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np
import scipy
import scipy.signal as sig


def scipy_h1(u, y, fs, nfft):
    kw = dict(fs=fs, window="hann", nperseg=nfft, noverlap=nfft // 2, detrend="constant", scaling="density")
    m = u.shape[0]
    g_uu = np.empty((m, m, nfft // 2 + 1), dtype=complex)
    g_uy = np.empty((m, y.shape[0], nfft // 2 + 1), dtype=complex)
    for i in range(m):
        _, g_uu[i] = sig.csd(u[i], u, **kw)  # conj(U_i) U_j, the same convention as sysid
        _, g_uy[i] = sig.csd(u[i], y, **kw)
    _, g_yy = sig.welch(y, **kw)
    # H^T = G_uu^{-1} G_uy per frequency: move frequency to the batch axis.
    ht = np.linalg.solve(np.moveaxis(g_uu, 2, 0), np.moveaxis(g_uy, 2, 0))
    return np.transpose(ht, (0, 2, 1)), g_yy  # bins x outputs x inputs


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", required=True, help="path of the sysid_bench_welch program")
    ap.add_argument("--samples", type=int, default=1000000)
    ap.add_argument("--nfft", type=int, default=4096)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()

    with tempfile.TemporaryDirectory(prefix="sysid_welch_") as tmp:
        data_path, h_path = os.path.join(tmp, "uy.f64"), os.path.join(tmp, "h.c128")
        out = subprocess.run([a.bench, "--samples", str(a.samples), "--nfft", str(a.nfft), "--repeats", str(a.repeats),
                              "--write-data", data_path, "--write-h", h_path],
                             check=True, capture_output=True, text=True).stdout
        sys.stdout.write(out)
        t_sysid = float(re.search(r"welch_h1_seconds ([0-9.eE+-]+)", out).group(1))
        uy = np.fromfile(data_path, dtype=np.float64).reshape(16, a.samples)  # column-major N x 16 -> rows are channels
        h_sysid = np.fromfile(h_path, dtype=np.complex128).reshape(-1, 8, 8)
    u, y = np.ascontiguousarray(uy[:8]), np.ascontiguousarray(uy[8:])
    del uy
    fs = 1000.0
    best = float("inf")
    for _ in range(a.repeats):
        t0 = time.perf_counter()
        h_scipy, _ = scipy_h1(u, y, fs, a.nfft)
        best = min(best, time.perf_counter() - t0)
    diff = np.max(np.abs(h_scipy[1:] - h_sysid[1:])) / np.max(np.abs(h_sysid[1:]))
    print(f"scipy {scipy.__version__} numpy {np.__version__}: welch_h1_seconds {best:.4f} (min of {a.repeats})")
    print(f"sysid / scipy time ratio {t_sysid / best:.3f}  ({'met' if t_sysid <= best else 'NOT met'}: sysid at least as fast)")
    print(f"max |H1_sysid - H1_scipy| / max |H1| over f > 0: {diff:.2e}")
    if not diff < 1e-9:
        print("the two H1 estimates differ: the comparison is not like for like", file=sys.stderr)
        return 1
    return 0 if t_sysid <= best else 1


if __name__ == "__main__":
    sys.exit(main())
