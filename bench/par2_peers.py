#!/usr/bin/env python3
"""Python peers of the Par2 GU comparison (bench/run_peers.sh): SIPPY and nfoursid.

Usage:
    python3 bench/par2_peers.py {sippy,nfoursid} EST.csv OUT.json [--order 10] [--horizon 20] [--repeats 1]

The estimation log (t,u,y) is read, the means of u and y are removed (the common
evaluator, par2_eval.cpp, adds them back for every tool), and the identification
call alone is timed, best of --repeats. The model is written as DESIGN.md
state-space JSON (Ts, A, B, C, D).

- sippy:    sippy_unipi.system_identification(y, u, 'N4SID', SS_fixed_order=n,
            SS_f=horizon, SS_D_required=True) -- the N4SID weighting of SIPPY's
            OLSims; D is estimated (SIPPY's default would force D = 0, and the
            Par2 GU path is biproper, D != 0).
- nfoursid: nfoursid.NFourSID(df, ['y'], ['u'], num_block_rows=horizon),
            subspace_identification(), system_identification(rank=n)
            (PO-MOESP, Verhaegen & Verdult 2007).

Prints:  RESULT tag=sippy status=ok fit_time_s=... repeats=... maxrss_mb=... base_rss_mb=...
or, when the tool raises (exit code 3; MemoryError included, see run_peers.sh's cap):
         RESULT tag=nfoursid status=failed fit_time_s=... maxrss_mb=... reason=<exception>
"""
import argparse
import contextlib
import io
import json
import resource
import sys
import time

import numpy as np


def max_rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # KiB on Linux


def identify_sippy(u, y, ts, order, horizon):
    from sippy_unipi import system_identification

    # SIPPY prints progress to stdout; keep ours parseable.
    with contextlib.redirect_stdout(io.StringIO()):
        model = system_identification(y.reshape(1, -1), u.reshape(1, -1), "N4SID", tsample=ts,
                                      SS_fixed_order=order, SS_f=horizon, SS_D_required=True)
    return model.A, model.B, model.C, model.D


def identify_nfoursid(u, y, ts, order, horizon, frame):
    from nfoursid.nfoursid import NFourSID

    n4 = NFourSID(frame, output_columns=["y"], input_columns=["u"], num_block_rows=horizon)
    n4.subspace_identification()
    ss, _ = n4.system_identification(rank=order)
    return ss.a, ss.b, ss.c, ss.d


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("tool", choices=["sippy", "nfoursid"])
    p.add_argument("est")
    p.add_argument("out")
    p.add_argument("--order", type=int, default=10)
    p.add_argument("--horizon", type=int, default=20)
    p.add_argument("--repeats", type=int, default=1)
    a = p.parse_args()

    data = np.loadtxt(a.est, delimiter=",", skiprows=1, comments="#")
    t, u, y = data[:, 0], data[:, 1], data[:, 2]
    ts = (t[-1] - t[0]) / (len(t) - 1)
    u = u - u.mean()
    y = y - y.mean()
    frame = None
    if a.tool == "nfoursid":
        import pandas as pd

        frame = pd.DataFrame({"u": u, "y": y})
        import nfoursid.nfoursid  # noqa: F401  (import cost outside the timed region)
    else:
        # system_identification imports its N4SID module (and python-control) on
        # first use: import it here so the first timed run does not pay for it.
        import sippy_unipi.OLSims_methods  # noqa: F401
    base = max_rss_mb()

    best = float("inf")
    for _ in range(a.repeats):
        t0 = time.perf_counter()
        try:
            if a.tool == "sippy":
                A, B, C, D = identify_sippy(u.copy(), y.copy(), ts, a.order, a.horizon)
            else:
                A, B, C, D = identify_nfoursid(u, y, ts, a.order, a.horizon, frame)
        except (Exception, MemoryError) as e:  # a failure is a result too: the table reports it
            reason = f"{type(e).__name__}: {e}".replace("\n", " ")
            print(f"RESULT tag={a.tool} status=failed fit_time_s={time.perf_counter() - t0:.6f} "
                  f"maxrss_mb={max_rss_mb():.1f} base_rss_mb={base:.1f} reason={reason}")
            return 3
        best = min(best, time.perf_counter() - t0)

    def mat(m):
        return np.atleast_2d(np.asarray(m, dtype=float)).tolist()

    model = {"type": "state-space", "Ts": ts, "A": mat(A), "B": mat(B), "C": mat(C), "D": mat(D),
             "provenance": {"method": a.tool, "order": a.order, "horizon": a.horizon}}
    with open(a.out, "w") as f:
        json.dump(model, f)  # repr of floats: shortest round-trip form
    print(f"RESULT tag={a.tool} status=ok fit_time_s={best:.6f} repeats={a.repeats} maxrss_mb={max_rss_mb():.1f} "
          f"base_rss_mb={base:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
