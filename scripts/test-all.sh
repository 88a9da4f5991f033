#!/usr/bin/env bash
# Every test, as the README's second command and .ci/run run it:
#  1. install what is missing (scripts/install-deps.sh);
#  2. the optimised build and its default tests (cmake --workflow --preset ci);
#  3. a short libFuzzer run of the file readers (scripts/fuzz-smoke.sh);
#  4. the default tests again under AddressSanitizer + UndefinedBehaviorSanitizer
#     (cmake --workflow --preset asan-ubsan: a clang build of its own; the three
#     longest acceptance runs are left to the asan-ubsan-full preset, see
#     CMakePresets.json).
#
# CI stops a run at 90 minutes, and its machines differ in speed by up to 2x. Step 4
# costs about SYSID_SANITIZER_COST_RATIO times what step 2 took on the same machine
# (measured on a quiet 2-core machine: see the ratio's default below), so before it
# starts the script predicts its duration from step 2 and runs it only if the whole
# run then ends at least SYSID_CI_MARGIN_S before SYSID_CI_LIMIT_S. Otherwise it
# says on stderr that it skipped the step and why, and exits 0 (the tests that ran
# passed). SYSID_SANITIZER=always or never overrides the prediction.
set -euo pipefail
cd "$(dirname "$0")/.."

limit_s=${SYSID_CI_LIMIT_S:-5400}
margin_s=${SYSID_CI_MARGIN_S:-420}
# Step 4 / step 2, both from an empty build directory, same machine (2 cores):
# 2026-11-23, unity build: see the README ("Building by hand").
ratio=${SYSID_SANITIZER_COST_RATIO:-1.6}
mode=${SYSID_SANITIZER:-auto}
case "$mode" in auto | always | never) ;; *)
  echo "test-all: SYSID_SANITIZER must be auto, always or never, not '$mode'" >&2
  exit 1
  ;;
esac

now() { date +%s; }
start=$(now)
./scripts/install-deps.sh
step2_start=$(now)
cmake --workflow --preset ci
step2_s=$(( $(now) - step2_start ))
./scripts/fuzz-smoke.sh

elapsed=$(( $(now) - start ))
# awk for the fractional ratio; rounds up.
predicted=$(awk -v t="$step2_s" -v r="$ratio" 'BEGIN { p = t * r; print (p == int(p)) ? p : int(p) + 1 }')
echo "test-all: steps 1-3 took ${elapsed} s (the release build and tests ${step2_s} s); the ASan + UBSan" \
     "step should take about ${predicted} s (${ratio} x ${step2_s} s)"
if [[ "$mode" == never ]] ||
   [[ "$mode" == auto && $(( elapsed + predicted + margin_s )) -gt $limit_s ]]; then
  echo "test-all: NOT running the tests under ASan + UBSan (SYSID_SANITIZER=${mode}): ${elapsed} s spent," \
       "about ${predicted} s more needed, and the run must end ${margin_s} s before ${limit_s} s." \
       "Run 'cmake --workflow --preset asan-ubsan' on its own." >&2
  exit 0
fi
step4_start=$(now)
cmake --workflow --preset asan-ubsan
echo "test-all: the ASan + UBSan step took $(( $(now) - step4_start )) s (predicted ${predicted} s);" \
     "all steps done in $(( $(now) - start )) s"
