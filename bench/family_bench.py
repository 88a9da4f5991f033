#!/usr/bin/env python3
"""`sysid family` on 100 logs against `sysid n4sid` on one of them (issue 35).

Target (issue 35): a family of 100 logs of 40 000 samples (n4sid, order 10) in at
most 1.2 x (one log's time x 100 / 2) on 2 cores, peak memory at most twice one
log's.

What it does, in one run, with one sysid binary:

1. Makes the family in the work directory: N logs (--members, default 100) of the
   base log's length (default: Par2 GU, build/<preset>/data/par2_gu.csv, 40 000
   samples, columns t,u,y). Member i is the base log with y plus independent white
   Gaussian noise of 1 % of y's RMS (seed (35, i), numpy's default generator); t and
   u are copied as they are, text unchanged. manifest.csv beside them: header
   `log,run`, one row per member, run = 1..N (a numeric condition).
2. One log, the reference: `sysid n4sid MEMBER.csv --inputs u --outputs y --order 10
   --out m.json --force` on --repeats different members (one untimed warm-up run
   first). Wall time = the whole process (start-up, CSV parsing, identification,
   model file); peak RSS = ru_maxrss of the command (os.wait4). Medians. Every
   command is started by a small launcher (a fresh `python -I -S`, about 5 MB)
   that forks it and waits for it: ru_maxrss is inherited across fork and exec, so
   a command started straight from this script would report at least this
   script's own peak (numpy and the family in memory, more than one n4sid needs).
3. The family: `sysid family manifest.csv --inputs u --outputs y --method n4sid
   --order 10 --out family.json --force`, --repeats-family runs (default
   --repeats), measured the same way; family.json must parse and hold N members.
4. Prints the table and the verdicts:
       time ratio = family time / (one-log time x N / 2)   target <= 1.2
       memory ratio = family peak RSS / one-log peak RSS   target <= 2
   (medians). The "/ 2" is the issue's 2 cores: the bench machine's nproc is 2; the
   script prints the cores it sees and warns when they are not 2.

Exit status: 0 when every command ran (whatever the verdicts), 1 when a sysid
command failed or family.json is wrong (its stderr is printed), 2 when the binary
or the base log is missing.

Run from the repository root with any Python 3 that has numpy:

    build/venv/bin/python bench/family_bench.py
    build/venv/bin/python bench/family_bench.py --sysid build/bench/sysid --repeats 5 --repeats-family 1 \\
        --json /tmp/family_bench.json

Build (bench/README.md): `cmake --preset bench && cmake --build build/bench --target
sysid_cli sysid_example_data -j2` (the program lands in build/<preset>/sysid, the
example logs in build/<preset>/data); the release and ci presets serve as well.
"""
import argparse
import json
import math
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
PRESETS = ("bench", "release", "ci")  # searched in this order for the binary and the base log
ORDER = 10
INPUT, OUTPUT = "u", "y"
NOISE_FRACTION = 0.01  # added noise: 1 % of y's RMS
SEED = 35  # the number; member i uses the seed (SEED, i)
TIME_TARGET = 1.2  # issue 35: family time <= 1.2 x (one log's time x N / 2)
RSS_TARGET = 2.0  # issue 35: family peak RSS <= 2 x one log's
CORES = 2  # issue 35: "on 2 cores"


class CommandFailed(Exception):
    def __init__(self, argv, status, stderr, stdout, hint=""):
        super().__init__(f"exit status {status}")
        self.argv, self.status, self.stderr, self.stdout, self.hint = argv, status, stderr, stdout, hint


def build_hint(preset="bench"):
    return (f"build it with the {preset} preset (bench/README.md), in the repository root:\n"
            f"  cmake --preset {preset} && cmake --build build/{preset} --target sysid_cli sysid_example_data -j2\n"
            "(the release and ci presets work too: build/release, build/ci)")


def candidate_binaries():
    """Where the program lands: build/<preset>/sysid (apps/CMakeLists.txt puts the runtime output
    in the project's binary directory); build/<preset>/apps/sysid is also looked at."""
    for preset in PRESETS:
        yield REPO / "build" / preset / "sysid"
        yield REPO / "build" / preset / "apps" / "sysid"


def find_binary(given):
    if given is not None:
        path = Path(given)
        if not (path.is_file() and os.access(path, os.X_OK)):
            sys.stderr.write(f"family_bench.py: --sysid {path}: no such executable; {build_hint()}\n")
            sys.exit(2)
        return path.resolve()
    for path in candidate_binaries():
        if path.is_file() and os.access(path, os.X_OK):
            return path
    tried = "\n".join(f"  {p.relative_to(REPO)}" for p in candidate_binaries())
    sys.stderr.write(f"family_bench.py: no sysid binary found; looked for\n{tried}\n{build_hint()}\n"
                     "or pass --sysid PATH\n")
    sys.exit(2)


def build_dir_of(binary):
    """build/<preset> when the binary is one of a preset's, else None."""
    for parent in (binary.parent, binary.parent.parent):
        if parent.parent == REPO / "build":
            return parent
    return None


def find_log(given, binary):
    """--log, else the par2_gu.csv of the binary's own build directory, else of any preset."""
    if given is not None:
        path = Path(given)
        if not path.is_file():
            sys.stderr.write(f"family_bench.py: --log {path}: no such file\n")
            sys.exit(2)
        return path.resolve()
    own = build_dir_of(binary)
    candidates = ([own / "data" / "par2_gu.csv"] if own else []) + \
                 [REPO / "build" / p / "data" / "par2_gu.csv" for p in PRESETS]
    candidates = list(dict.fromkeys(candidates))  # the binary's own directory once
    for path in candidates:
        if path.is_file():
            return path
    preset = own.name if own else "bench"
    sys.stderr.write(f"family_bench.py: the base log par2_gu.csv was not found (looked in "
                     f"{', '.join(str(c.parent.relative_to(REPO)) for c in candidates)}).\n"
                     f"Generate the example logs: cmake --build build/{preset} --target sysid_example_data -j2\n"
                     "(data/README.md), or pass --log PATH (a CSV with columns t,u,y)\n")
    sys.exit(2)


def read_base_log(path):
    """(header line, list of rows as lists of field texts, index of the y column, y as floats)."""
    with open(path, newline="") as f:
        lines = f.read().splitlines()
    if not lines:
        sys.exit(f"family_bench.py: {path} is empty")
    header = lines[0]
    names = [n.strip() for n in header.split(",")]
    for name in (INPUT, OUTPUT):
        if name not in names:
            sys.exit(f"family_bench.py: {path} has no column '{name}' (header: {header})")
    rows = [line.split(",") for line in lines[1:] if line.strip()]
    iy = names.index(OUTPUT)
    try:
        y = np.array([float(r[iy]) for r in rows])
    except (ValueError, IndexError) as e:
        sys.exit(f"family_bench.py: {path}: column '{OUTPUT}' is not numeric throughout ({e})")
    return header, rows, iy, y


def make_family(base_log, folder, members):
    """N perturbed copies of the base log and manifest.csv in `folder`; returns the member paths
    and the number of samples."""
    header, rows, iy, y = read_base_log(base_log)
    rms = float(np.sqrt(np.mean(y * y)))
    sigma = NOISE_FRACTION * rms
    folder.mkdir(parents=True, exist_ok=True)
    width = max(3, len(str(members)))
    paths, manifest = [], ["log,run"]
    # Everything but y is written back as it was read: the members differ from the base log in y only.
    prefix = [",".join(r[:iy]) + "," if iy > 0 else "" for r in rows]
    suffix = ["," + ",".join(r[iy + 1:]) if iy + 1 < len(r) else "" for r in rows]
    for i in range(members):
        rng = np.random.default_rng([SEED, i])
        noisy = (y + sigma * rng.standard_normal(y.size)).tolist()
        name = f"member_{i + 1:0{width}d}.csv"
        text = "\n".join(p + repr(v) + s for p, v, s in zip(prefix, noisy, suffix))
        (folder / name).write_text(header + "\n" + text + "\n")
        paths.append(folder / name)
        manifest.append(f"{name},{i + 1}")
    (folder / "manifest.csv").write_text("\n".join(manifest) + "\n")
    return paths, len(rows), rms


# The launcher that starts every measured command. ru_maxrss is a high-water mark that a child
# inherits from the process it was forked from (the forked copy's mm, and exec carries its peak
# into the new image's count): started straight from this script, `sysid` would report at least
# this script's own peak RSS (numpy and the family's rows: tens of MB, more than one n4sid run
# needs). So a fresh, small interpreter (python -I -S, a few MB) forks the command, waits for it
# with os.wait4 and writes back "seconds status maxrss"; the command's peak is then exact whenever
# it exceeds the launcher's own (printed as the launcher floor, and checked). It also reports the
# command's CPU time (user + system), which tells how many cores one n4sid keeps busy.
LAUNCHER = r"""
import os, sys, time
result, argv = sys.argv[1], sys.argv[2:]
start = time.perf_counter()
pid = os.fork()
if pid == 0:
    try:
        os.execv(argv[0], argv)
    except BaseException as e:
        os.write(2, ("launcher: cannot run %s: %s\n" % (argv[0], e)).encode())
    os._exit(127)
_, status, usage = os.wait4(pid, 0)
seconds = time.perf_counter() - start
with open(result, "w") as f:
    f.write("%r %d %d %r\n" % (seconds, os.waitstatus_to_exitcode(status), usage.ru_maxrss,
                               usage.ru_utime + usage.ru_stime))
"""


def run_measured(argv, workdir, tag):
    """(wall seconds, peak RSS in kB, CPU seconds) of one run of argv, through LAUNCHER (wall time from the fork
    to the end of the wait, the launcher's own start-up excluded); stdout and stderr go to files
    (no pipe to fill). Raises CommandFailed on a non-zero exit or a signal."""
    out_path, err_path = workdir / f"{tag}.stdout", workdir / f"{tag}.stderr"
    result_path = workdir / f"{tag}.rusage"
    if result_path.exists():
        result_path.unlink()
    with open(out_path, "wb") as out, open(err_path, "wb") as err:
        code = subprocess.run([sys.executable, "-I", "-S", "-c", LAUNCHER, str(result_path)] + [str(x) for x in argv],
                              stdout=out, stderr=err, stdin=subprocess.DEVNULL, cwd=workdir).returncode
    try:
        seconds, status, maxrss, cpu = result_path.read_text().split()
        seconds, status, maxrss, cpu = float(seconds), int(status), int(maxrss), float(cpu)
    except (OSError, ValueError):
        raise CommandFailed(argv, code, err_path.read_text(errors="replace"), out_path.read_text(errors="replace"),
                            "(the measuring launcher itself failed)")
    if status != 0:
        raise CommandFailed(argv, status, err_path.read_text(errors="replace"), out_path.read_text(errors="replace"))
    # ru_maxrss: kB on Linux (bytes on macOS).
    rss_kb = maxrss / 1024.0 if sys.platform == "darwin" else float(maxrss)
    return seconds, rss_kb, cpu


def launcher_floor_kb(workdir):
    """The peak RSS the launcher reports for a command that needs almost none (`true`): below
    this a measured peak is the launcher's, not the command's."""
    true = shutil.which("true") or "/bin/true"
    try:
        return run_measured([true], workdir, "launcher_floor")[1]
    except CommandFailed:
        return math.nan


def run_reporting(argv, workdir, tag):
    """run_measured, ending the progress line the caller started when the command fails."""
    try:
        return run_measured(argv, workdir, tag)
    except CommandFailed:
        print(" failed", flush=True)
        raise


def sysid_has_verb(binary, verb):
    """Whether `sysid --help` lists the verb (None when that cannot be told)."""
    try:
        r = subprocess.run([str(binary), "--help"], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return None
    text = r.stdout + r.stderr
    return any(line.split()[:1] == [verb] for line in text.splitlines())


def one_log_argv(binary, log, out):
    return [str(binary), "n4sid", str(log), "--inputs", INPUT, "--outputs", OUTPUT, "--order", str(ORDER),
            "--out", str(out), "--force"]


def family_argv(binary, manifest, out):
    return [str(binary), "family", str(manifest), "--inputs", INPUT, "--outputs", OUTPUT, "--method", "n4sid",
            "--order", str(ORDER), "--out", str(out), "--force"]


def measure_one_log(binary, members, repeats, workdir):
    # Warm-up (not counted): the binary and its libraries into the page cache.
    run_measured(one_log_argv(binary, members[-1], workdir / "m.json"), workdir, "one_log_warmup")
    seconds, rss, cpu = [], [], []
    for k in range(repeats):
        log = members[k % len(members)]
        print(f"  one log, run {k + 1}/{repeats}: {log.name} ...", end="", flush=True)
        s, r, c = run_reporting(one_log_argv(binary, log, workdir / "m.json"), workdir, f"one_log_{k + 1}")
        print(f" {s:.3f} s, {r / 1024:.1f} MB, CPU {c:.3f} s", flush=True)
        seconds.append(s)
        rss.append(r)
        cpu.append(c)
    with open(workdir / "m.json") as f:
        model = json.load(f)
    order = len(model.get("A", [])) if isinstance(model, dict) else None
    return seconds, rss, cpu, order


def check_family_json(path, members):
    """Raises ValueError when family.json does not parse or does not hold N members; returns
    warnings about the rest of the DESIGN.md contract that the benchmark relies on."""
    try:
        with open(path) as f:
            family = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        raise ValueError(f"{path} does not parse: {e}") from e
    if not isinstance(family, dict) or not isinstance(family.get("members"), list):
        raise ValueError(f"{path} has no list 'members'")
    got = len(family["members"])
    if got != len(members):
        raise ValueError(f"{path} has {got} members, the manifest {len(members)}")
    notes = []
    if family.get("type") != "family":
        notes.append(f"\"type\" is {family.get('type')!r}, not \"family\"")
    for i, m in enumerate(family["members"]):
        run = (m.get("conditions") or {}).get("run") if isinstance(m, dict) else None
        if run != i + 1 or isinstance(run, bool):
            notes.append(f"members[{i}].conditions.run is {run!r}, expected the number {i + 1} "
                         "(manifest order, numbers as JSON numbers)")
            break
    orders = {len((m.get("model") or {}).get("A", [])) for m in family["members"] if isinstance(m, dict)}
    if orders != {ORDER}:
        notes.append(f"member model orders {sorted(orders)}, expected {ORDER}")
    return notes


def measure_family(binary, manifest, members, repeats, workdir):
    seconds, rss, cpu = [], [], []
    out = workdir / "family.json"
    notes = []
    for k in range(repeats):
        if out.exists():
            out.unlink()  # a stale family.json must not pass the check
        print(f"  family, run {k + 1}/{repeats} ...", end="", flush=True)
        s, r, c = run_reporting(family_argv(binary, manifest, out), workdir, f"family_{k + 1}")
        print(f" {s:.3f} s, {r / 1024:.1f} MB, CPU {c:.2f} s", flush=True)
        seconds.append(s)
        rss.append(r)
        cpu.append(c)
        notes = check_family_json(out, members)
    return seconds, rss, cpu, notes


def cores_seen():
    try:
        affinity = len(os.sched_getaffinity(0))
    except AttributeError:
        affinity = None
    return os.cpu_count(), affinity


def environment(binary):
    nproc, affinity = cores_seen()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else math.nan
    try:
        head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, timeout=10).stdout.strip() or "?"
        dirty = subprocess.run(["git", "-C", str(REPO), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
        head += " (+ working tree)" if dirty else ""
    except (OSError, subprocess.TimeoutExpired):
        head = "?"
    return {"binary": str(binary), "commit": head, "nproc": nproc, "affinity": affinity, "load_1min": load,
            "python": platform.python_version(), "numpy": np.__version__, "machine": platform.machine()}


def verdict(ok):
    return "PASS" if ok else "FAIL"


def print_table(r):
    n = r["members"]
    one_t, one_m = r["one_log"]["time_median_s"], r["one_log"]["rss_median_kb"] / 1024
    fam = r.get("family")
    print()
    print("| quantity | value | target | verdict |")
    print("|---|---:|---:|---|")
    print(f"| one log: time (median of {len(r['one_log']['time_s'])}) [s] | {one_t:.3f} | | |")
    print(f"| one log: peak RSS (median) [MB] | {one_m:.1f} | | |")
    one_c = r["one_log"]["cpu_median_s"]
    print(f"| one log: CPU time, user + system (median) [s] | {one_c:.3f} ({one_c / one_t:.2f} cores busy) | | |")
    print(f"| one log x N / 2 [s] | {one_t * n / CORES:.2f} | | |")
    if fam is None or "time_median_s" not in fam:
        status = r.get("status", "not measured")
        print(f"| family of {n}: time [s] | – | | {status} |")
        print(f"| family of {n}: peak RSS [MB] | – | | {status} |")
        return
    print(f"| family of {n}: time (median of {len(fam['time_s'])}) [s] | {fam['time_median_s']:.3f} | | |")
    print(f"| family of {n}: peak RSS (median) [MB] | {fam['rss_median_kb'] / 1024:.1f} | | |")
    fam_c = fam["cpu_median_s"]
    print(f"| family of {n}: CPU time (median) [s] | {fam_c:.2f} ({fam_c / fam['time_median_s']:.2f} cores busy; "
          f"{fam_c / (one_c * n):.2f} x N one-log CPU) | | |")
    print(f"| time ratio: family / (one log x {n} / {CORES}) | {r['time_ratio']:.3f} | <= {TIME_TARGET} "
          f"| {verdict(r['time_pass'])} |")
    print(f"| memory ratio: family / one log (peak RSS) | {r['rss_ratio']:.3f} | <= {RSS_TARGET} "
          f"| {verdict(r['rss_pass'])} |")


def write_json(path, result):
    if path is None:
        return
    Path(path).write_text(json.dumps(result, indent=2) + "\n")
    print(f"\nwrote {path}")


def report_failure(e, what):
    sys.stdout.flush()
    sys.stderr.write(f"\nfamily_bench.py: {what} failed (exit status {e.status}):\n  {' '.join(e.argv)}\n")
    sys.stderr.write("--- its stderr ---\n" + (e.stderr.rstrip() or "(empty)") + "\n")
    if e.stdout.strip():
        tail = "\n".join(e.stdout.rstrip().splitlines()[-20:])
        sys.stderr.write("--- its stdout (last lines) ---\n" + tail + "\n")
    if e.hint:
        sys.stderr.write(e.hint + "\n")


def run(a, workdir):
    binary = find_binary(a.sysid)
    base_log = find_log(a.log, binary)
    env = environment(binary)
    print(f"sysid: {binary} (commit {env['commit']})")
    print(f"Cores: nproc {env['nproc']}, affinity {env['affinity']}; load {env['load_1min']:.2f}")
    if env["nproc"] != CORES or (env["affinity"] not in (None, CORES)):
        print(f"warning: the target is for {CORES} cores; this machine shows nproc {env['nproc']}, "
              f"affinity {env['affinity']} (the ratio still divides by {CORES})")
    if env["load_1min"] > 1.0:
        print(f"warning: load average {env['load_1min']:.2f}: other work shares the cores, the times are inflated "
              "(the one-log reference less than the family, whose 2 busy cores compete with it)")

    floor = launcher_floor_kb(workdir)
    print(f"Peak RSS through the launcher: floor {floor / 1024:.1f} MB (what `true` reports; a command's peak "
          "is exact above it)")

    folder = workdir / "family"
    print(f"Making the family: {a.members} members from {base_log} in {folder} ...", flush=True)
    start = time.perf_counter()
    members, samples, rms = make_family(base_log, folder, a.members)
    print(f"  {a.members} logs of {samples} samples (y + white noise, sigma {NOISE_FRACTION:.0%} of "
          f"y's RMS {rms:.4g}), manifest.csv; {time.perf_counter() - start:.1f} s")

    result = {"target": "issue 35", "environment": env, "base_log": str(base_log), "members": a.members,
              "samples": samples, "order": ORDER, "workdir": str(workdir), "launcher_floor_kb": floor,
              "commands": {"one_log": " ".join(one_log_argv(binary, members[0], workdir / "m.json")),
                           "family": " ".join(family_argv(binary, folder / "manifest.csv",
                                                          workdir / "family.json"))}}

    print(f"One log: sysid n4sid, order {ORDER} ({a.repeats} runs after one warm-up)", flush=True)
    try:
        seconds, rss, cpu, order = measure_one_log(binary, members, a.repeats, workdir)
    except CommandFailed as e:
        report_failure(e, "sysid n4sid (one log)")
        result["status"] = "FAILED: sysid n4sid"
        write_json(a.json, result)
        return 1
    result["one_log"] = {"time_s": seconds, "rss_kb": rss, "cpu_s": cpu, "time_median_s": statistics.median(seconds),
                         "rss_median_kb": statistics.median(rss), "cpu_median_s": statistics.median(cpu),
                         "model_order": order}
    if order != ORDER:
        print(f"warning: the n4sid model has order {order}, expected {ORDER}")
    if min(rss) <= 1.1 * floor:
        print(f"warning: the one-log peak RSS ({min(rss) / 1024:.1f} MB) is at the launcher's floor "
              f"({floor / 1024:.1f} MB): the memory ratio is not meaningful")

    print(f"Family: sysid family --method n4sid, {a.members} members ({a.repeats_family} runs)", flush=True)
    has_family = sysid_has_verb(binary, "family")
    try:
        fseconds, frss, fcpu, notes = measure_family(binary, folder / "manifest.csv", members, a.repeats_family, workdir)
    except CommandFailed as e:
        if has_family is False:
            e.hint = ("This sysid has no verb `family` (`sysid --help` does not list it): issue 35, "
                      "/work/shared/DESIGN.md \"Model families over operating conditions\".\n"
                      "The one-log reference above was measured; build a sysid with `family` and run again.")
        report_failure(e, "sysid family")
        result["status"] = "FAILED: sysid family" + (" (no such verb)" if has_family is False else "")
        print_table(result)
        write_json(a.json, result)
        return 1
    except ValueError as e:
        sys.stdout.flush()
        sys.stderr.write(f"\nfamily_bench.py: family.json is wrong: {e}\n")
        result["status"] = f"FAILED: family.json: {e}"
        print_table(result)
        write_json(a.json, result)
        return 1
    for note in notes:
        print(f"warning: family.json: {note}")
    result["family"] = {"time_s": fseconds, "rss_kb": frss, "cpu_s": fcpu, "time_median_s": statistics.median(fseconds),
                        "rss_median_kb": statistics.median(frss), "cpu_median_s": statistics.median(fcpu),
                        "contract_warnings": notes}
    one = result["one_log"]
    result["time_budget_s"] = one["time_median_s"] * a.members / CORES
    result["time_ratio"] = result["family"]["time_median_s"] / result["time_budget_s"]
    result["rss_ratio"] = result["family"]["rss_median_kb"] / one["rss_median_kb"]
    result["time_pass"] = result["time_ratio"] <= TIME_TARGET
    result["rss_pass"] = result["rss_ratio"] <= RSS_TARGET
    result["status"] = "ok"
    print_table(result)
    print(f"\nTimes: whole processes (start-up, CSV parsing, identification, output files), medians. "
          f"Peak RSS: ru_maxrss of the command (os.wait4 in a small launcher process). Targets (issue 35): time ratio <= {TIME_TARGET}, "
          f"memory ratio <= {RSS_TARGET}.")
    print(f"Issue 35: time {verdict(result['time_pass'])}, memory {verdict(result['rss_pass'])}")
    write_json(a.json, result)
    return 0


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="\n".join(__doc__.splitlines()[1:]))
    p.add_argument("--sysid", help="the sysid binary (default: build/bench/sysid, build/release/sysid, "
                                   "build/ci/sysid, the first that exists)")
    p.add_argument("--log", help="base log, columns t,u,y (default: data/par2_gu.csv of the binary's build "
                                 "directory, else of the bench, release or ci preset)")
    p.add_argument("--members", type=int, default=100, help="logs in the family (default 100)")
    p.add_argument("--repeats", type=int, default=3, help="timed one-log runs, each on another member (default 3)")
    p.add_argument("--repeats-family", type=int, default=None, help="timed family runs (default: --repeats)")
    p.add_argument("--workdir", type=Path, help="where the family and outputs go, kept afterwards "
                                                "(default: a temporary directory, removed)")
    p.add_argument("--json", help="also write the results to this JSON file")
    a = p.parse_args()
    if a.repeats_family is None:
        a.repeats_family = a.repeats
    if a.members < 1 or a.repeats < 1 or a.repeats_family < 1:
        p.error("--members, --repeats and --repeats-family must be >= 1")
    if a.json is not None:
        a.json = str(Path(a.json).resolve())
    if a.workdir is not None:
        a.workdir.mkdir(parents=True, exist_ok=True)
        return run(a, a.workdir.resolve())
    with tempfile.TemporaryDirectory(prefix="sysid_family_bench.") as tmp:
        return run(a, Path(tmp))


if __name__ == "__main__":
    sys.exit(main())
