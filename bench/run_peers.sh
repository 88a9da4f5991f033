#!/usr/bin/env bash
# Performance benchmarks of sysid against its peers, all in one run on the same logs.
#
#   bash bench/run_peers.sh [options]
#
# 1. installs the peers when missing: octave + octave-control (SLICOT IB01AD/BD/CD)
#    and GNU time with apt-get; sippy-unipi and nfoursid with pip;
# 2. configures (preset `bench`, or --build-dir DIR) and builds the benchmark
#    programs, the example-data generator and, when it builds, the sysid CLI;
# 3. Par2 GU, 40 000 samples, order 10, horizon 20: every tool identifies a model
#    from par2_gu.csv (means removed, the same for all), its identification call is
#    timed (minimum over runs), its process is measured by /usr/bin/time -v, and one
#    common evaluator (sysid_bench_par2_eval) scores every model on par2_gu_val.csv:
#    validation fit and in-band fit (zero-phase 5th-order Butterworth at 120 Hz);
# 4. 8x8, 10^6 samples, order 16, horizon 20 through the library
#    (sysid_bench_big_mimo, data made in memory) and through the CLI (data written
#    to a temporary CSV, deleted afterwards);
# 5. CSV parsing throughput (sysid_bench_csv_parse, 100 MB file).
# Prints a Markdown table of step 3 and the figures of steps 4-5; everything is
# also kept in the output directory (--out-dir, default a new /tmp/sysid_bench.*).
#
# Options:
#   --build-dir DIR       use (and, if needed, configure) this build directory
#                         instead of build/bench from `cmake --preset bench`
#   --no-install          never install anything (a missing peer is reported as such)
#   --no-build            use the programs already in the build directory
#   --repeats N           runs of sysid per measurement (default 10)
#   --peer-repeats N      runs of Octave and SIPPY (default 3; nfoursid runs once)
#   --big-repeats N       runs of the 8x8 library benchmark (default 3)
#   --nfoursid-mem-gb G   address-space cap for nfoursid (default 8): its last step
#                         takes a full SVD of a 20 x N matrix, i.e. an N x N array
#                         (12 GB at N = 40 000); the cap turns that into a quick
#                         MemoryError instead of a machine-wide out-of-memory
#   --skip-par2 --skip-big --skip-cli --skip-csv   leave out a part
#   --out-dir DIR         where models, logs and results go
set -u -o pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=""
INSTALL=1
DO_BUILD=1
REPEATS=10
PEER_REPEATS=3
BIG_REPEATS=3
NFOURSID_GB=8
SKIP_PAR2=0 SKIP_BIG=0 SKIP_CLI=0 SKIP_CSV=0
OUT=""

while [ $# -gt 0 ]; do
  case "$1" in
    --build-dir) BUILD=$2; shift ;;
    --no-install) INSTALL=0 ;;
    --no-build) DO_BUILD=0 ;;
    --repeats) REPEATS=$2; shift ;;
    --peer-repeats) PEER_REPEATS=$2; shift ;;
    --big-repeats) BIG_REPEATS=$2; shift ;;
    --nfoursid-mem-gb) NFOURSID_GB=$2; shift ;;
    --skip-par2) SKIP_PAR2=1 ;;
    --skip-big) SKIP_BIG=1 ;;
    --skip-cli) SKIP_CLI=1 ;;
    --skip-csv) SKIP_CSV=1 ;;
    --out-dir) OUT=$2; shift ;;
    -h|--help) sed -n '2,35p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "run_peers.sh: unknown option $1" >&2; exit 1 ;;
  esac
  shift
done

[ -n "$OUT" ] || OUT=$(mktemp -d /tmp/sysid_bench.XXXXXX)
mkdir -p "$OUT/models"
RESULTS=$OUT/results.txt
: > "$RESULTS"
say() { echo "== $*"; }

# ---- 1. peers ----------------------------------------------------------------
SUDO=""
[ "$(id -u)" = 0 ] || SUDO=sudo
have_octave_control() { command -v octave >/dev/null && octave --no-gui --quiet --norc --eval 'pkg load control' >/dev/null 2>&1; }
have_py() { python3 -c "import $1" >/dev/null 2>&1; }
if [ $INSTALL = 1 ]; then
  if ! have_octave_control || [ ! -x /usr/bin/time ]; then
    say "installing octave octave-control time (apt-get)"
    $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq octave octave-control time >/dev/null
  fi
  for pkg in sippy_unipi:sippy-unipi nfoursid:nfoursid; do
    have_py "${pkg%%:*}" || { say "installing ${pkg#*:} (pip)"; python3 -m pip install -q "${pkg#*:}"; }
  done
fi
[ -x /usr/bin/time ] || { echo "run_peers.sh: /usr/bin/time (GNU time) is required" >&2; exit 1; }

# ---- 2. build ----------------------------------------------------------------
if [ -z "$BUILD" ]; then
  BUILD=$ROOT/build/bench
  if [ $DO_BUILD = 1 ]; then
    (cd "$ROOT" && cmake --preset bench -DSYSID_BUILD_DATA=ON >"$OUT/configure.log") || { echo "configure failed: $OUT/configure.log" >&2; exit 1; }
  fi
elif [ $DO_BUILD = 1 ] && [ ! -f "$BUILD/CMakeCache.txt" ]; then
  cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS=-march=native \
    -DSYSID_BUILD_BENCH=ON -DSYSID_BUILD_DATA=ON >"$OUT/configure.log" || { echo "configure failed: $OUT/configure.log" >&2; exit 1; }
fi
if [ $DO_BUILD = 1 ]; then
  say "building benchmarks and example data in $BUILD"
  cmake --build "$BUILD" --target sysid_benchmarks sysid_example_data -j2 >"$OUT/build.log" 2>&1 ||
    { echo "build failed: $OUT/build.log" >&2; exit 1; }
  if [ $SKIP_CLI = 0 ]; then
    cmake --build "$BUILD" --target sysid_cli -j2 >"$OUT/build_cli.log" 2>&1 ||
      say "the sysid CLI does not build yet (see $OUT/build_cli.log): the CLI run is skipped"
  fi
fi
B=$BUILD/bench
DATA=$BUILD/data
EST=$DATA/par2_gu.csv
VAL=$DATA/par2_gu_val.csv

# ---- machine -----------------------------------------------------------------
{
  echo "date: $(date -u +%Y-%m-%dT%H:%MZ)"
  echo "sysid: $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?')$(git -C "$ROOT" diff --quiet 2>/dev/null || echo ' (with uncommitted changes)')"
  echo "machine: nproc $(nproc), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(awk '/MemTotal/ {printf "%.1f GiB", $2/1048576}' /proc/meminfo), load average $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "compiler: $(c++ --version | head -1); flags: Release -march=native"
  command -v octave >/dev/null && echo "octave: $(octave --version 2>/dev/null | head -1), control $(octave --no-gui --quiet --norc --eval 'p = pkg("list", "control"); disp(p{1}.version)' 2>/dev/null)"
  python3 -c "
import importlib.metadata as m
for p in ('numpy', 'scipy', 'sippy_unipi', 'nfoursid'):
    try: print(p + ':', m.version(p))
    except Exception: print(p + ': not installed')"
} | tee "$OUT/machine.txt"

# run_tool TAG CMD... : runs CMD under /usr/bin/time -v, keeps its RESULT line and
# the process's elapsed time and peak RSS (a tool that dies without a RESULT line,
# e.g. killed, gets a failed one with its exit code).
run_tool() {
  local tag=$1; shift
  /usr/bin/time -v -o "$OUT/$tag.time" "$@" >"$OUT/$tag.out" 2>"$OUT/$tag.err"
  local rc=$?
  if grep -q '^RESULT ' "$OUT/$tag.out"; then
    grep '^RESULT ' "$OUT/$tag.out" | tail -1 >>"$RESULTS"
  elif [ $rc = 0 ]; then  # a program without the RESULT protocol (the CLI): its exit code says it all
    echo "RESULT tag=$tag status=ok" >>"$RESULTS"
  else
    echo "RESULT tag=$tag status=failed reason=exit code $rc without a result (see $OUT/$tag.err)" >>"$RESULTS"
  fi
  local wall rss
  wall=$(sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$OUT/$tag.time")
  rss=$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$OUT/$tag.time")
  echo "PROC tag=$tag elapsed=${wall:-0} maxrss_kb=${rss:-0} exit=$rc" >>"$RESULTS"
  echo "   $tag: $(grep "^RESULT tag=$tag " "$RESULTS" | tail -1 | cut -c8-)"
}

# ---- 3. Par2 GU ----------------------------------------------------------------
if [ $SKIP_PAR2 = 0 ]; then
  [ -f "$EST" ] && [ -f "$VAL" ] || { echo "run_peers.sh: $EST or $VAL missing (build target sysid_example_data)" >&2; exit 1; }
  say "Par2 GU: $(($(wc -l <"$EST") - 1)) samples, order 10, horizon 20"
  M=$OUT/models
  ID=$B/sysid_bench_par2_identify
  run_tool sysid        "$ID" "$EST" --out "$M/sysid.json" --repeats "$REPEATS" --tag sysid
  run_tool sysid_moesp  "$ID" "$EST" --out "$M/sysid_moesp.json" --repeats "$REPEATS" --weighting moesp --tag sysid_moesp
  run_tool sysid_fullrate "$ID" "$EST" --out "$M/sysid_fullrate.json" --repeats "$REPEATS" --decimation 1 --tag sysid_fullrate
  run_tool sysid_moesp_fullrate "$ID" "$EST" --out "$M/sysid_moesp_fullrate.json" --repeats "$REPEATS" --decimation 1 \
    --weighting moesp --tag sysid_moesp_fullrate
  if have_octave_control; then
    OCT=(octave --no-gui --quiet --norc "$ROOT/bench/par2_octave.m")
    run_tool octave_n4sid       "${OCT[@]}" "$EST" "$M/octave_n4sid.json" n4sid 10 20 "$PEER_REPEATS"
    run_tool octave_moesp       "${OCT[@]}" "$EST" "$M/octave_moesp.json" moesp 10 20 "$PEER_REPEATS"
    run_tool octave_moesp_alg_f "${OCT[@]}" "$EST" "$M/octave_moesp_alg_f.json" moesp 10 20 "$PEER_REPEATS" f
  else
    echo "RESULT tag=octave status=failed reason=octave with octave-control not installed" >>"$RESULTS"
  fi
  PY=(python3 "$ROOT/bench/par2_peers.py")
  if have_py sippy_unipi; then
    run_tool sippy "${PY[@]}" sippy "$EST" "$M/sippy.json" --repeats "$PEER_REPEATS"
  else
    echo "RESULT tag=sippy status=failed reason=sippy-unipi not installed" >>"$RESULTS"
  fi
  if have_py nfoursid; then
    run_tool nfoursid bash -c "ulimit -v $((NFOURSID_GB * 1024 * 1024)); exec \"\$@\"" _ "${PY[@]}" nfoursid "$EST" "$M/nfoursid.json"
  else
    echo "RESULT tag=nfoursid status=failed reason=nfoursid not installed" >>"$RESULTS"
  fi

  models=("true=$DATA/par2_gu_true.json")
  for tag in $(sed -n 's/^RESULT tag=\([^ ]*\) status=ok.*/\1/p' "$RESULTS"); do
    [ -f "$M/$tag.json" ] && models+=("$tag=$M/$tag.json")
  done
  "$B/sysid_bench_par2_eval" "$EST" "$VAL" "${models[@]}" >>"$RESULTS" 2>"$OUT/eval.err"
  echo
  python3 "$ROOT/bench/peer_table.py" "$RESULTS" --reference sysid | tee "$OUT/par2_table.md"
  echo
fi

# ---- 4. 8x8, 10^6 samples ----------------------------------------------------
if [ $SKIP_BIG = 0 ]; then
  say "8x8, 10^6 samples, order 16, horizon 20: library (sysid_bench_big_mimo, best of $BIG_REPEATS)"
  run_tool big_mimo "$B/sysid_bench_big_mimo" --repeats "$BIG_REPEATS"
  sed 's/^/   /' "$OUT/big_mimo.out"
  grep "^PROC tag=big_mimo " "$RESULTS" | sed 's/^/   /'
fi
if [ $SKIP_CLI = 0 ]; then
  if [ -x "$BUILD/sysid" ]; then
    say "8x8, 10^6 samples, order 16, horizon 20: CLI (sysid n4sid on a CSV log)"
    "$B/sysid_bench_big_mimo" --csv "$OUT/big.csv" | sed 's/^/   /'
    echo "   log size: $(du -m "$OUT/big.csv" | cut -f1) MB"
    run_tool big_cli "$BUILD/sysid" n4sid "$OUT/big.csv" --inputs u1,u2,u3,u4,u5,u6,u7,u8 \
      --outputs y1,y2,y3,y4,y5,y6,y7,y8 --order 16 --horizon 20 --out "$OUT/models/big_cli.json"
    grep "^PROC tag=big_cli " "$RESULTS" | sed 's/^/   /'
    grep -E "User time|System time" "$OUT/big_cli.time" | sed 's/^\s*/   /'
    rm -f "$OUT/big.csv"
  else
    say "the sysid CLI ($BUILD/sysid) is not built: CLI run skipped"
  fi
fi

# ---- 5. CSV parsing ----------------------------------------------------------
if [ $SKIP_CSV = 0 ]; then
  say "CSV parsing (sysid_bench_csv_parse, 100 MB, best of 5)"
  "$B/sysid_bench_csv_parse" 100 "$OUT/csv_parse.csv" | sed 's/^/   /'
fi

say "all outputs in $OUT"
