#!/usr/bin/env bash
# Fuzz smoke test (CI): builds the three libFuzzer targets of tests/fuzz with clang
# in build/fuzz and runs each for a short fixed budget on the seed corpus (ctest
# label "fuzz"). Under 4 minutes of CPU time to build, 30 s to fuzz (measured:
# 5 min 51 s in all on the 2-core VM while other builds ran).
# Long runs and how to reproduce a finding: tests/fuzz/README.md.
#
# Needs clang and its libFuzzer runtime (Debian: clang, libclang-rt-14-dev), which
# scripts/install-deps.sh installs when missing.
set -euo pipefail
cd "$(dirname "$0")/.."

./scripts/install-deps.sh  # clang and libclang-rt-14-dev are among its packages

jobs=${SYSID_FUZZ_JOBS:-2}
CC=clang CXX=clang++ cmake -S . -B build/fuzz -G Ninja -DCMAKE_BUILD_TYPE=Debug \
  -DSYSID_BUILD_FUZZ=ON -DSYSID_BUILD_APPS=OFF -DSYSID_BUILD_TESTS=OFF -DSYSID_BUILD_DATA=OFF -DSYSID_BUILD_BENCH=OFF
cmake --build build/fuzz --target sysid_fuzz_csv sysid_fuzz_model_json sysid_fuzz_augmented_model -j "$jobs"
# The tests are registered in tests/fuzz's own directory (enable_testing() there),
# so point ctest at it whatever the top-level CMakeLists does.
ctest --test-dir build/fuzz/tests/fuzz -L fuzz --output-on-failure --no-tests=error -j "$jobs"
