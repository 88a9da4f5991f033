#!/usr/bin/env bash
# Every check, as the README's second command and .ci/run run it, each step every
# time (none is skipped, whatever the machine):
#  1. install what is missing (scripts/install-deps.sh);
#  2. the layering rules of DESIGN.md (scripts/check-layering.py);
#  3. the optimised build and its default tests (cmake --workflow --preset ci);
#  4. a short libFuzzer run of the file readers (scripts/fuzz-smoke.sh);
#  5. every default test again under AddressSanitizer + UndefinedBehaviorSanitizer
#     (cmake --workflow --preset asan-ubsan: a clang build of its own).
# It prints the minutes each step took, and stops at the first failure.
set -euo pipefail
cd "$(dirname "$0")/.."

start=$(date +%s)
step_start=$start
timings=()
step_done() {
  local now
  now=$(date +%s)
  timings+=("$(printf '%-42s %5d s' "$1" $((now - step_start)))")
  echo "test-all: $1 took $((now - step_start)) s ($((now - start)) s so far)"
  step_start=$now
}

./scripts/install-deps.sh
step_done "1. install-deps"
python3 scripts/check-layering.py
step_done "2. layering check"
cmake --workflow --preset ci
step_done "3. release build and default tests"
./scripts/fuzz-smoke.sh
step_done "4. fuzz smoke run"
cmake --workflow --preset asan-ubsan
step_done "5. ASan + UBSan build and default tests"

echo "test-all: every step passed in $(($(date +%s) - start)) s:"
printf '  %s\n' "${timings[@]}"
