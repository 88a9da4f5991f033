#!/usr/bin/env python3
"""The Python package against the C++ library and the Python peers, in one process (issue 36).

Measures, on the Par2 GU example (estimation log par2_gu.csv, validation log
par2_gu_val.csv; order 10, horizon (block rows) 20 for every tool, as in
bench/README.md "Method"):

1. The overhead of the Python call: ``sysid.n4sid(u, y, Ts, order=10, horizon=20)``
   timed with time.perf_counter, against the same library build's C++ ``n4sid``
   timed inside the extension (``sysid._sysid._time_n4sid``, data already in C++).
   The two are timed in alternating blocks so that the machine's other work
   slows both alike; overhead = median(Python) / median(C++) - 1 (and the same
   for the minima). Target: <= 5 %.
2. SIPPY (``sippy_unipi.system_identification(..., 'N4SID', SS_D_required=True)``)
   and nfoursid (``NFourSID(...).subspace_identification();
   system_identification(rank=10)``), called as bench/par2_peers.py calls them:
   identification call only, imports and data preparation outside the timed
   region. Target: SIPPY time / sysid time >= 50 with a better validation fit.

Scoring: every model, sysid's and the peers', is scored by the one scorer,
``sysid.compare`` (simulation, x0 estimated by least squares) on the validation
log. sysid removes the estimation means itself and keeps them in the model
(input_offset, output_offset), which compare subtracts again. The peers fit on
the data they are given without removing means, so they get u and y with the
estimation means removed, and their models (``sysid.Model(A, B, C, D, Ts)``, no
offsets) are scored on the validation log with the same estimation means
subtracted: the same arithmetic as sysid's offsets.

Run from the repository root, with the package built by a CMake preset or installed:

    PYTHONPATH=build/ci/python python3 bench/python_bench.py
    pip install . && python3 bench/python_bench.py --peer-repeats 3

Peers: ``pip install sippy-unipi nfoursid pandas`` (a missing peer is reported and
skipped; --skip-peers skips both). nfoursid runs under an address-space cap
(--nfoursid-mem-gb, as bench/run_peers.sh does): at 40 000 samples its full SVD
asks for an N x N matrix (12 GB), and the cap makes that a quick MemoryError.
"""
import argparse
import contextlib
import io
import math
import os
import platform
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
ORDER = 10
HORIZON = 20
METHOD = "n4sid"
OVERHEAD_TARGET = 0.05  # issue 36: the Python call's overhead <= 5 % over the C++ call
SIPPY_RATIO_TARGET = 50.0  # issue 36: >= 50x faster than SIPPY, with a better fit


def import_sysid():
    """The sysid package, or exit 2 with what to do: the benchmark means nothing without it."""
    try:
        import sysid
    except ImportError as e:
        sys.exit(f"python_bench.py: cannot import sysid ({e}).\n"
                 "Install the package (`pip install .` in the repository root), or build a preset and point\n"
                 "PYTHONPATH at its module: PYTHONPATH=build/<preset>/python python3 bench/python_bench.py")
    return sysid


def default_data_dir():
    """build/bench/data (run_peers.sh's build) when present, else build/ci/data."""
    bench = REPO / "build" / "bench" / "data"
    return bench if bench.is_dir() else REPO / "build" / "ci" / "data"


@contextlib.contextmanager
def quiet():
    """sysid warns on every call (decimation, Kalman gain, out-of-band gain) and SIPPY prints
    progress and overflows: neither belongs inside a timing loop or the table."""
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        yield


def load(sysid, data_dir):
    est, val = data_dir / "par2_gu.csv", data_dir / "par2_gu_val.csv"
    for f in (est, val):
        if not f.is_file():
            sys.exit(f"python_bench.py: {f} not found; build the example logs (target sysid_example_data) "
                     "or pass --data-dir")
    u, y, ts = sysid.read_log(str(est), inputs=["u"], outputs=["y"])
    u_val, y_val, _ = sysid.read_log(str(val), inputs=["u"], outputs=["y"])
    return u, y, ts, u_val, y_val


def sysid_n4sid(sysid, u, y, ts):
    return sysid.n4sid(u, y, ts, order=ORDER, horizon=HORIZON, method=METHOD)


def first_warnings(sysid, u, y, ts):
    """The warnings of one call, printed once so the reader knows what the timed call does
    (on Par2 it decimates by 5 before the subspace step)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sysid_n4sid(sysid, u, y, ts)
    return [str(w.message) for w in caught]


def time_python_block(sysid, u, y, ts, count):
    seconds = []
    with quiet():
        for _ in range(count):
            start = time.perf_counter()
            sysid_n4sid(sysid, u, y, ts)
            seconds.append(time.perf_counter() - start)
    return seconds


def measure_overhead(sysid, u, y, ts, repeats, block):
    """Python and C++ timings of the same n4sid, in alternating blocks of `block` calls.
    Which side goes first alternates too, so a slow spell of the machine or a warm cache
    favours neither."""
    with quiet():  # warm-up: first-touch allocations and thread-pool start are no one's overhead
        sysid_n4sid(sysid, u, y, ts)
        sysid._sysid._time_n4sid(u, y, ts, ORDER, HORIZON, METHOD, 1)
    python, cpp = [], []
    done, turn = 0, 0
    while done < repeats:
        count = min(block, repeats - done)
        sides = [lambda: python.extend(time_python_block(sysid, u, y, ts, count)),
                 lambda: cpp.extend(sysid._sysid._time_n4sid(u, y, ts, ORDER, HORIZON, METHOD, count))]
        for side in (sides if turn % 2 == 0 else sides[::-1]):
            side()
        done += count
        turn += 1
    return python, cpp


def timed_runs(identify, repeats):
    """(seconds of each run, (A, B, C, D) of the last, failure reason or None). A failure is a
    result too (nfoursid's MemoryError): its time until failure is kept and no more runs are made."""
    seconds, matrices = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        try:
            with quiet():
                matrices = identify()
        except (Exception, MemoryError) as e:
            seconds.append(time.perf_counter() - start)
            return seconds, None, f"{type(e).__name__}: {e}".replace("\n", " ")
        seconds.append(time.perf_counter() - start)
    return seconds, matrices, None


def sippy_peer(u0, y0, ts):
    """SIPPY as bench/par2_peers.py calls it; None when not installed."""
    try:
        # system_identification imports its N4SID module (and python-control) on first use:
        # import it here so the first timed run does not pay for it.
        import sippy_unipi.OLSims_methods  # noqa: F401
        from sippy_unipi import system_identification
    except ImportError:
        return None
    y_row, u_row = y0.reshape(1, -1), u0.reshape(1, -1)

    def identify():
        # SS_D_required: SIPPY's default forces D = 0, and the Par2 GU path is biproper.
        m = system_identification(y_row.copy(), u_row.copy(), "N4SID", tsample=ts, SS_fixed_order=ORDER,
                                  SS_f=HORIZON, SS_D_required=True)
        return m.A, m.B, m.C, m.D

    return identify


def vm_size_bytes():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmSize:"):
                return int(line.split()[1]) * 1024
    raise OSError("no VmSize in /proc/self/status")


@contextlib.contextmanager
def address_space_cap(extra_gb):
    """The process's address space limited to what it uses now plus extra_gb, restored after:
    a one-process version of run_peers.sh's `ulimit -v` around nfoursid. No cap where
    RLIMIT_AS or /proc are missing (non-Linux)."""
    try:
        import resource
        soft, hard = resource.getrlimit(resource.RLIMIT_AS)
        cap = vm_size_bytes() + int(extra_gb * 2**30)
        if hard != resource.RLIM_INFINITY:
            cap = min(cap, hard)
        resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    except (ImportError, OSError, ValueError):
        yield
        return
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def nfoursid_peer(u0, y0, ts, mem_gb):
    """nfoursid as bench/par2_peers.py calls it; None when not installed."""
    try:
        import pandas as pd
        from nfoursid.nfoursid import NFourSID
    except ImportError:
        return None
    frame = pd.DataFrame({"u": u0, "y": y0})  # the DataFrame is nfoursid's input format, not its work

    def identify():
        with address_space_cap(mem_gb):
            n4 = NFourSID(frame, output_columns=["y"], input_columns=["u"], num_block_rows=HORIZON)
            n4.subspace_identification()
            ss, _ = n4.system_identification(rank=ORDER)
        return ss.a, ss.b, ss.c, ss.d

    return identify


def score(sysid, model, u_val, y_val):
    """Validation fit [%] by sysid.compare; NaN when the simulation is not finite (an unstable
    model) or compare refuses the model."""
    try:
        with quiet():
            fit, _ = sysid.compare(model, u_val, y_val)
        value = float(np.asarray(fit).ravel()[0])
    except Exception:
        return math.nan
    return value if math.isfinite(value) else math.nan


def peer_model(sysid, matrices, ts):
    A, B, C, D = (np.atleast_2d(np.asarray(m, dtype=float)) for m in matrices)
    return sysid.Model(A, B, C, D, ts)


def max_pole(model):
    return float(np.max(np.abs(np.linalg.eigvals(model.A))))


def overhead_report(python, cpp):
    med_py, med_cpp = statistics.median(python), statistics.median(cpp)
    min_py, min_cpp = min(python), min(cpp)
    over_med, over_min = med_py / med_cpp - 1.0, min_py / min_cpp - 1.0
    print(f"\nOverhead of the Python call ({len(python)} Python and {len(cpp)} C++ calls, interleaved):")
    print(f"  sysid.n4sid (Python)      median {med_py * 1e3:8.3f} ms   min {min_py * 1e3:8.3f} ms")
    print(f"  n4sid (C++, same build)   median {med_cpp * 1e3:8.3f} ms   min {min_cpp * 1e3:8.3f} ms")
    print(f"  overhead                  median {over_med * 100:+7.2f} %    min {over_min * 100:+7.2f} %")
    return over_med, over_min


def fmt(x, spec):
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def print_table(rows, sysid_min, sysid_med):
    print("\n| tool | time min [s] | time median [s] | runs | time / sysid (min) | time / sysid (median) "
          "| validation fit [%] | max pole modulus | status |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---|")
    for r in rows:
        t = r["seconds"]
        tmin, tmed = (min(t), statistics.median(t)) if t else (None, None)
        ok = r["status"] == "ok"
        ratio_min = tmin / sysid_min if ok else None
        ratio_med = tmed / sysid_med if ok else None
        until = "" if ok or not t else " (until failure)"
        print(f"| {r['tool']} | {fmt(tmin, '.4f')}{until} | {fmt(tmed, '.4f')} | {len(t)} | {fmt(ratio_min, '.1f')} "
              f"| {fmt(ratio_med, '.1f')} | {fmt(r['fit'], '.2f') if ok else '–'} | {fmt(r.get('pole'), '.5f')} "
              f"| {r['status']} |")


def acceptance(over_med, rows, sysid_row):
    print("\nIssue 36 acceptance:")
    verdict = "MET" if over_med <= OVERHEAD_TARGET else "NOT met"
    print(f"  Python overhead <= {OVERHEAD_TARGET * 100:.0f} % (medians): {over_med * 100:+.2f} % -> {verdict}")
    sippy = next((r for r in rows if r["tool"] == "sippy"), None)
    if sippy is None:
        print("  >= 50x SIPPY with a better fit: not measured (SIPPY skipped or not installed)")
        return
    if sippy["status"] != "ok":
        print(f"  >= 50x SIPPY with a better fit: SIPPY failed ({sippy['status']})")
        return
    ratio_min = min(sippy["seconds"]) / min(sysid_row["seconds"])
    ratio_med = statistics.median(sippy["seconds"]) / statistics.median(sysid_row["seconds"])
    # A non-finite fit (an unstable model's simulation) is worse than any finite one.
    better = math.isfinite(sysid_row["fit"]) and (math.isnan(sippy["fit"]) or sysid_row["fit"] > sippy["fit"])
    verdict = "MET" if ratio_min >= SIPPY_RATIO_TARGET and better else "NOT met"
    print(f"  SIPPY / sysid time >= {SIPPY_RATIO_TARGET:.0f}x (minima): {ratio_min:.1f}x (medians {ratio_med:.1f}x); "
          f"fit sysid {fmt(sysid_row['fit'], '.2f')} % vs SIPPY {fmt(sippy['fit'], '.2f')} % "
          f"({'better' if better else 'not better'}) -> {verdict}")


def environment(sysid):
    versions = [f"Python {platform.python_version()}", f"numpy {np.__version__}", f"sysid {sysid.__version__}"]
    for name in ("sippy_unipi", "nfoursid"):
        try:
            from importlib.metadata import version
            versions.append(f"{name} {version(name.replace('_', '-'))}")
        except Exception:
            pass
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else math.nan
    return f"{', '.join(versions)}; nproc {os.cpu_count()}; load {load:.2f}"


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="\n".join(__doc__.splitlines()[1:]))
    p.add_argument("--data-dir", type=Path, default=default_data_dir(),
                   help="directory with par2_gu.csv and par2_gu_val.csv (default: %(default)s)")
    p.add_argument("--repeats", type=int, default=200,
                   help="calls of each side for the overhead (default 200: at ~7 ms a call, 40 left the median +-5 %%)")
    p.add_argument("--block", type=int, default=5, help="calls per interleaved block (default 5)")
    p.add_argument("--peer-repeats", type=int, default=3, help="runs of each peer (default 3)")
    p.add_argument("--skip-peers", action="store_true", help="measure the overhead only")
    p.add_argument("--nfoursid-mem-gb", type=float, default=8.0,
                   help="address space nfoursid may add to the process (default 8)")
    a = p.parse_args()
    if a.repeats < 1 or a.block < 1 or a.peer_repeats < 1:
        p.error("--repeats, --block and --peer-repeats must be >= 1")

    sysid = import_sysid()
    u, y, ts, u_val, y_val = load(sysid, a.data_dir)
    print(f"Par2 GU: {len(y)} estimation / {len(y_val)} validation samples, Ts {ts:g} s; order {ORDER}, "
          f"horizon {HORIZON}, method '{METHOD}'; data {a.data_dir}")
    print(f"Environment: {environment(sysid)}")
    print("sysid.n4sid warns (suppressed while timing):")
    for message in first_warnings(sysid, u, y, ts):
        print(f"  {message}")

    python, cpp = measure_overhead(sysid, u, y, ts, a.repeats, a.block)
    over_med, _ = overhead_report(python, cpp)

    with quiet():
        model = sysid_n4sid(sysid, u, y, ts)
    sysid_fit = score(sysid, model, u_val, y_val)
    rows = [{"tool": "sysid (Python)", "seconds": python, "fit": sysid_fit, "pole": max_pole(model), "status": "ok"},
            {"tool": "sysid (C++)", "seconds": cpp, "fit": sysid_fit, "pole": max_pole(model), "status": "ok"}]

    if not a.skip_peers:
        # The peers do not remove means: they get the estimation data without its means, and are
        # scored on the validation data less the same means (sysid's offsets, applied by hand).
        u_mean, y_mean = u.mean(axis=0), y.mean(axis=0)
        u0, y0 = (u - u_mean).ravel(), (y - y_mean).ravel()
        u_val0, y_val0 = u_val - u_mean, y_val - y_mean
        peers = [("sippy", sippy_peer(u0, y0, ts)), ("nfoursid", nfoursid_peer(u0, y0, ts, a.nfoursid_mem_gb))]
        for tool, identify in peers:
            if identify is None:
                rows.append({"tool": tool, "seconds": [], "fit": math.nan, "status": "not installed"})
                continue
            print(f"Running {tool} ({a.peer_repeats} runs) ...", flush=True)
            seconds, matrices, failure = timed_runs(identify, a.peer_repeats)
            row = {"tool": tool, "seconds": seconds, "fit": math.nan, "status": "ok" if failure is None else
                   f"FAILED: {failure}"}
            if failure is None:
                m = peer_model(sysid, matrices, ts)
                row["fit"], row["pole"] = score(sysid, m, u_val0, y_val0), max_pole(m)
            rows.append(row)

    print_table(rows, min(python), statistics.median(python))
    print("\nTimes: the identification call only (min and median of the runs); ratios against sysid (Python). "
          "Fit: sysid.compare on par2_gu_val.csv, simulation, x0 estimated; '–' = not finite (NaN).")
    acceptance(over_med, rows, rows[0])
    return 0


if __name__ == "__main__":
    sys.exit(main())
