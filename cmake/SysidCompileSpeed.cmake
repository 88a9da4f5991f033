# Compile-time measures for the project's own targets (the library, the program,
# the tests, the data generators, the benchmarks); none of them reaches the
# installed package's interface, so a consumer compiles exactly as before.
#
# sysid_compile_fast(<target> [PCH <header>...] [SHARE_PCH <group>])
#   - every translation unit of <target> sees src/core/detail/eigen_instances.hpp
#     first: the heavy Eigen decompositions are declared `extern template` there
#     and compiled once, in the library (src/core/eigen_instances.cpp), instead of
#     in each unit that calls them (why and how much: that header);
#   - with SYSID_PRECOMPILED_HEADERS (default ON), that header, Eigen and the
#     <header>s given are a precompiled header, so Eigen (and GoogleTest, CLI11,
#     nlohmann/json for the targets that list them) is parsed once per target
#     instead of once per unit; SHARE_PCH <group> shares one precompiled header
#     among the targets of a group, all compiled with the same flags (the test
#     executables, the data generators): the group's first target builds it, the
#     others reuse it.
option(SYSID_PRECOMPILED_HEADERS "Precompile Eigen and the shared third-party headers of each target" ON)

set(SYSID_EIGEN_INSTANCES_HEADER ${PROJECT_SOURCE_DIR}/src/core/detail/eigen_instances.hpp)

function(sysid_compile_fast target)
  cmake_parse_arguments(arg "" "SHARE_PCH" "PCH" ${ARGN})
  if(NOT SYSID_PRECOMPILED_HEADERS)
    target_compile_options(${target} PRIVATE "SHELL:-include ${SYSID_EIGEN_INSTANCES_HEADER}")
    return()
  endif()
  if(arg_SHARE_PCH)
    get_property(owner GLOBAL PROPERTY SYSID_PCH_OWNER_${arg_SHARE_PCH})
    if(owner)
      target_precompile_headers(${target} REUSE_FROM ${owner})
      return()
    endif()
    set_property(GLOBAL PROPERTY SYSID_PCH_OWNER_${arg_SHARE_PCH} ${target})
  endif()
  target_precompile_headers(${target} PRIVATE ${SYSID_EIGEN_INSTANCES_HEADER} ${arg_PCH})
endfunction()

# sysid_compile_light(<target>)
#   Compiles <target> at -O1 in optimised builds (Release, RelWithDebInfo; later on
#   the command line than CMAKE_CXX_FLAGS_<CONFIG>, so it wins). For the code that
#   calls the library rather than being it: the tests and the data generators,
#   whose run time is spent inside libsysid (and the program), which keep the
#   configuration's optimisation. Sanitized and debug builds keep their own level.
#   In the sanitized build (clang), <target> is compiled without AddressSanitizer's
#   stack instrumentation (-mllvm -asan-stack=0); its heap and global checks and
#   UBSan stay, and so does every check of the library and the program, whose
#   code the tests exercise. The tests' own stack frames (large TEST bodies) are
#   what it mostly instruments: the unity batches of test_unit_diagnose and
#   test_unit_core (0) compile in 43.8 s and 59.0 s against 52.1 s and 67.2 s
#   (clang 14, precompiled headers, 2026-11-28); the tests run as long (479 s
#   against 458 s for all of them, within the runs' spread). Measured without the
#   precompiled header and not taken: -O0 (19.8 s against 50.7 s, but the library
#   templates the tests instantiate then run so slowly that one diagnose case
#   took 161 s, the whole file 181 s at -O1) and no ASan at all in test code
#   (34.2 s: the library's header templates instantiated there would lose their
#   heap checks).
function(sysid_compile_light target)
  target_compile_options(${target} PRIVATE $<$<CONFIG:Release,RelWithDebInfo>:-O1>
                                           "$<$<AND:$<CONFIG:Sanitize>,$<CXX_COMPILER_ID:Clang>>:SHELL:-mllvm -asan-stack=0>")
endfunction()

# sysid_compile_uninstrumented(<target>)
#   In the sanitized build (CMAKE_BUILD_TYPE Sanitize), compiles <target>'s own code
#   without the sanitizers; it still links their runtime and the instrumented
#   library, whose code it calls. For the data generators: tools that write the
#   tests' input files, not code under test (every line of libsysid they run is
#   checked). Instrumented, they took 1.8 times as long to compile (clang 14,
#   generate_concealed.cpp: 46.8 s against 25.1 s, 2026-11-28) and ran slower.
function(sysid_compile_uninstrumented target)
  if(CMAKE_BUILD_TYPE STREQUAL "Sanitize")
    target_compile_options(${target} PRIVATE -fno-sanitize=all)
  endif()
endfunction()
