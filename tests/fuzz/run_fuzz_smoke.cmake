# ctest smoke run of one fuzz target (cmake -P): the seed corpus is copied to a
# scratch directory in the build tree, so the fuzzer never writes into the source
# tree (libFuzzer adds the inputs it finds to the first corpus directory, and
# writes crash-*/leak-*/timeout-* files to -artifact_prefix).
#
# -D variables: FUZZER (executable), SEEDS (seed directory), DICT (dictionary),
# WORK_DIR (scratch directory, emptied first), RUNS, SECONDS.
foreach(var FUZZER SEEDS DICT WORK_DIR RUNS SECONDS)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_fuzz_smoke.cmake: -D${var}=... is required")
  endif()
endforeach()

file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR}/corpus ${WORK_DIR}/artifacts)
file(GLOB seeds ${SEEDS}/*)
if(NOT seeds)
  message(FATAL_ERROR "run_fuzz_smoke.cmake: no seed files in ${SEEDS}")
endif()
file(COPY ${seeds} DESTINATION ${WORK_DIR}/corpus)

# -seed fixed: the same mutations on every run, so a red smoke test is reproducible.
# -rss_limit_mb / -timeout: a memory blow-up or a hang counts as a failure.
execute_process(
  COMMAND ${FUZZER} ${WORK_DIR}/corpus -dict=${DICT} -seed=1 -runs=${RUNS} -max_total_time=${SECONDS}
          -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 -artifact_prefix=${WORK_DIR}/artifacts/
  WORKING_DIRECTORY ${WORK_DIR}
  RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  file(GLOB artifacts ${WORK_DIR}/artifacts/*)
  message(FATAL_ERROR "${FUZZER} failed (exit ${result}); reproducer(s): ${artifacts}\n"
                      "Rerun one with: ${FUZZER} <file>")
endif()
