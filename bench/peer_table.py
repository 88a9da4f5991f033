#!/usr/bin/env python3
"""Formats the Par2 GU peer comparison collected by bench/run_peers.sh.

Usage: python3 bench/peer_table.py RESULTS.txt [--reference sysid]

RESULTS.txt holds, per tool, the driver's own line
    RESULT tag=T status=ok|failed fit_time_s=... maxrss_mb=... [reason=...]
the process figures measured by /usr/bin/time -v
    PROC tag=T elapsed=M:SS.ss maxrss_kb=N exit=E
and the common evaluator's scores (bench/par2_eval.cpp)
    EVAL name=T fit=... inband=... order=... max_pole=...
It prints a Markdown table, one row per tool in the order of the RESULT lines,
with the identification time of each tool divided by that of the reference row.
"""
import argparse
import math
import sys


def parse_fields(text):
    """key=value pairs; a `reason=` field takes the rest of the line (it has spaces)."""
    out = {}
    head, sep, reason = text.partition(" reason=")
    for tok in head.split():
        k, _, v = tok.partition("=")
        out[k] = v
    if sep:
        out["reason"] = reason.strip()
    return out


def elapsed_seconds(s):
    """/usr/bin/time's 'h:mm:ss' or 'm:ss.ss'."""
    secs = 0.0
    for part in s.split(":"):
        secs = secs * 60 + float(part)
    return secs


def fnum(v, fmt):
    try:
        x = float(v)
    except (TypeError, ValueError):
        return "–"
    if math.isnan(x):
        return "NaN"
    if abs(x) >= 1e6:
        return f"{x:.2e}"
    return format(x, fmt)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("results")
    p.add_argument("--reference", default="sysid")
    a = p.parse_args()

    order, result, proc, ev = [], {}, {}, {}
    with open(a.results) as f:
        for line in f:
            kind, _, rest = line.strip().partition(" ")
            if kind == "RESULT":
                d = parse_fields(rest)
                if d["tag"] not in result:
                    order.append(d["tag"])
                result[d["tag"]] = d
            elif kind == "PROC":
                d = parse_fields(rest)
                proc[d["tag"]] = d
            elif kind == "EVAL":
                d = parse_fields(rest)
                ev[d["name"]] = d

    ref = result.get(a.reference, {})
    ref_time = float(ref["fit_time_s"]) if ref.get("status") == "ok" else float("nan")

    print("| tool | identification time [s] (min of runs) | time / sysid | process wall [s] | peak RSS [MB] "
          "| validation fit [%] | in-band fit [%] | max pole modulus | status |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---|")
    for tag in order + [t for t in ev if t not in result]:
        r, pr, e = result.get(tag, {}), proc.get(tag, {}), ev.get(tag, {})
        t = r.get("fit_time_s")
        ratio = "–"
        if t is not None and r.get("status") == "ok" and ref_time == ref_time and ref_time > 0:
            ratio = f"{float(t) / ref_time:.1f}"
        wall = fnum(elapsed_seconds(pr["elapsed"]), ".2f") if "elapsed" in pr else "–"
        rss = fnum(int(pr["maxrss_kb"]) / 1024.0, ".1f") if "maxrss_kb" in pr else fnum(r.get("maxrss_mb"), ".1f")
        if tag in result:
            status = "ok" if r.get("status") == "ok" else "FAILED: " + r.get("reason", "(no reason given)")
            if r.get("status") == "ok" and "repeats" in r:
                status += f" ({r['repeats']} runs)"
        else:
            status = "reference (not identified)"
        time_cell = fnum(t, ".4f") if t is not None else "–"
        if r.get("status") == "failed" and t is not None:
            time_cell += " (until failure)"
        print(f"| {tag} | {time_cell} | {ratio} | {wall} | {rss} | {fnum(e.get('fit'), '.2f')} "
              f"| {fnum(e.get('inband'), '.2f')} | {fnum(e.get('max_pole'), '.5f')} | {status} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
