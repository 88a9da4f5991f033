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
function(sysid_compile_light target)
  target_compile_options(${target} PRIVATE $<$<CONFIG:Release,RelWithDebInfo>:-O1>)
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
