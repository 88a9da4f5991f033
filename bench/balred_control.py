#!/usr/bin/env python3
"""Balanced truncation of the order-112 8x8 isolator-like model to order 30:
sysid against python-control + slycot (SLICOT AB09AD) in the same run.

Runs the C++ benchmark (sysid_bench_balred), which builds the model, times
sysid::balanced_truncation (median of --repeats) and writes the model, its Hankel
singular values and the reduced model as JSON; then times the peer on exactly
that model, median of --repeats:

  slycot.ab09ad('D', 'B', 'N', n, m, p, A, B, C, nr=30, tol=0)

i.e. the square-root balanced truncation (JOB = 'B') that python-control's
`balanced_reduction` / `balred(sys, 30, method='truncate')` calls. The call is made
directly because python-control 0.10.x passes DICO = 'C' for every model (its own
source: "only continuous supported for now"), so `control.balred` on a discrete
model would treat the z-plane A as continuous. `control.balred` is also timed on
the model as given, for reference only (its result is not valid for this
discrete model).

Checks: the two sets of HSV agree, and the two reduced models have the same
frequency response to within the truncation error (both are balanced truncations
of the same order; they differ only by a state basis and rounding).

The BLAS thread count is forced to 1 (OPENBLAS_NUM_THREADS etc., set before numpy
is imported) so both sides run on one core, as sysid does; --blas-threads changes it.
python-control and slycot are not dependencies of sysid; `pip install slycot
control` for this script only.

Usage: balred_control.py --bench PATH/sysid_bench_balred [--order 30] [--repeats 21] [--dense 0|1]
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bench", required=True, help="path of sysid_bench_balred")
    ap.add_argument("--order", type=int, default=30)
    ap.add_argument("--repeats", type=int, default=21)
    ap.add_argument("--dense", type=int, default=0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--blas-threads", type=int, default=1)
    args = ap.parse_args()
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(args.blas_threads)

    import numpy as np  # after the thread settings

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "model.json")
        out = subprocess.run([args.bench, "--order", str(args.order), "--repeats", str(args.repeats),
                              "--dense", str(args.dense), "--seed", str(args.seed), "--write-json", path],
                             check=True, capture_output=True, text=True).stdout
        print(out, end="")
        t_sysid = float(re.search(r"balred_seconds (\S+)", out).group(1))
        with open(path) as f:
            j = json.load(f)

    A, B, C, D = (np.array(j[k], dtype=float) for k in ("A", "B", "C", "D"))
    Ts, nr = j["Ts"], j["order"]
    n, m, p = A.shape[0], B.shape[1], C.shape[0]

    from slycot import ab09ad
    import control
    import warnings

    def peer():
        return ab09ad("D", "B", "N", n, m, p, A.copy(order="F"), B.copy(order="F"), C.copy(order="F"),
                      nr=nr, tol=0.0)

    peer()  # warm-up
    times = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        res = peer()
        times.append(time.perf_counter() - t0)
    t_peer = float(np.median(times))
    Nr, Ar, Br, Cr, hsv = res

    sys_full = control.ss(A, B, C, D, Ts)
    ctimes = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(max(1, args.repeats // 3)):
            t0 = time.perf_counter()
            control.balred(sys_full, nr, method="truncate")
            ctimes.append(time.perf_counter() - t0)

    # Accuracy checks against sysid's output.
    hsv_sysid = np.array(j["hsv"])
    hsv_rel = np.max(np.abs(hsv_sysid - hsv[:n])) / hsv[0]
    red = j["reduced"]
    Ar2, Br2, Cr2, Dr2 = (np.array(red[k], dtype=float) for k in ("A", "B", "C", "D"))
    f = np.linspace(0.0, 0.5 / Ts, 2001)
    z = np.exp(2j * np.pi * f * Ts)

    def resp(a, b, c, d, zz):
        eye = np.eye(a.shape[0])
        return np.array([c @ np.linalg.solve(zk * eye - a, b) + d for zk in zz])

    g_peer = resp(Ar, Br, Cr, D, z)
    g_sysid = resp(Ar2, Br2, Cr2, Dr2, z)
    g_full = resp(A, B, C, D, z)
    diff = max(np.linalg.norm(g_peer[k] - g_sysid[k], 2) for k in range(len(z)))
    err_peer = max(np.linalg.norm(g_full[k] - g_peer[k], 2) for k in range(len(z)))

    print(f"slycot_ab09ad_seconds {t_peer:.6g}  (python-control {control.__version__}, BLAS threads {args.blas_threads})")
    print(f"control_balred_seconds {np.median(ctimes):.6g}  (treats the model as continuous: reference only)")
    print(f"hsv max |sysid - slycot| / hsv[0] = {hsv_rel:.3g}")
    print(f"reduced models: max_f ||G_sysid - G_slycot|| = {diff:.6g}  (peer's own error on a 2001-point "
          f"grid: {err_peer:.6g}; sysid bound {j['hinf_bound']:.6g})")
    print(f"ratio slycot / sysid = {t_peer / t_sysid:.3g}  (> 1: sysid faster)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
