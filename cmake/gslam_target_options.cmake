# One place that sets language level, warnings, tuning and sanitizers on every gslam target.
function(gslam_target_options target)
  target_compile_features(${target} PUBLIC cxx_std_20)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wconversion -Wno-sign-conversion)
  if(GSLAM_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  if(GSLAM_NATIVE_ARCH)
    # Every target gets the same -march: Eigen's alignment must agree across translation units.
    target_compile_options(${target} PRIVATE -march=native)
    if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
      # GCC 12 false positives inside Eigen's AVX-512 code (_mm512_undefined_* operands, and
      # 512-bit loads of 3-vectors in Eigen::umeyama that its masking keeps in bounds).
      target_compile_options(${target} PRIVATE -Wno-maybe-uninitialized -Wno-array-bounds)
    endif()
  endif()
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    # The CPU backend's 64-byte row vectors (splat/src/cpu/lanes.h) make GCC note, on targets
    # without AVX-512, that passing them by value differs from AVX-512 code. They never cross a
    # library boundary (every function taking them is inline), so the note says nothing here.
    target_compile_options(${target} PRIVATE -Wno-psabi)
  endif()
  # Lets `#pragma omp simd` loops call the vectorised libm (libmvec) without OpenMP threads.
  # -fno-trapping-math lets GCC if-convert float selects (we never read FP exception flags).
  target_compile_options(${target} PRIVATE -fopenmp-simd -fno-math-errno -fno-trapping-math)
  if(GSLAM_BUILD_FUZZERS AND target MATCHES "^gslam_(io|datasets)$")
    # Coverage for libFuzzer in the libraries that hold the readers. Only there: the same build
    # runs the whole test suite under the sanitizers, which coverage everywhere slows ~10x.
    target_compile_options(${target} PRIVATE -fsanitize=fuzzer-no-link)
  endif()
  if(GSLAM_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=${GSLAM_SANITIZE} -fno-omit-frame-pointer
                                             -fno-sanitize-recover=all)
    target_link_options(${target} PRIVATE -fsanitize=${GSLAM_SANITIZE})
  endif()
endfunction()

# The headers most of a target's files include, parsed once per target rather than once per file:
# the standard library and Eigen, plus nlohmann/json and GoogleTest where the arguments name them
# (json, gtest). Only for targets of many files: loading a precompiled header costs about a second.
# Files built with a -std or -ffp-contract of their own set SKIP_PRECOMPILE_HEADERS: a precompiled
# header holds to the options it was made with.
function(gslam_precompile_headers target)
  if(NOT GSLAM_PRECOMPILE_HEADERS)
    return()
  endif()
  set(headers <algorithm> <array> <cmath> <cstdint> <cstdio> <cstring> <filesystem> <fstream>
              <functional> <map> <memory> <optional> <span> <string> <vector> <Eigen/Core> <Eigen/Geometry>)
  if(json IN_LIST ARGN)
    list(APPEND headers <nlohmann/json.hpp>)
  endif()
  if(gtest IN_LIST ARGN)
    list(APPEND headers <gtest/gtest.h>)
  endif()
  target_precompile_headers(${target} PRIVATE ${headers})
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    # GCC 12 at -O3 warns of overflows inside std::string's operator+ that cannot happen; the
    # standard headers' diagnostics are silenced as system headers' only when not precompiled.
    target_compile_options(${target} PRIVATE -Wno-stringop-overflow -Wno-array-bounds)
  endif()
endfunction()

# The targets a folder defines after this call compile their files eight to a compiler run (one
# generated file that includes them): the headers those files share (json, GoogleTest, CLI11,
# Eigen, OpenCV) are parsed and their templates compiled once a batch rather than once a file.
# For the app and the tests only: the rasterizer's, tracking's and mapping's kernels compile file
# by file, so that what the compiler inlines there (and contracts into FMAs) never depends on
# which files share a batch. Files in one batch share a scope: helpers of the same name in two
# files' anonymous namespaces collide there (give shared helpers one home; rename the rest).
macro(gslam_unity_build)
  set(CMAKE_UNITY_BUILD ${GSLAM_UNITY_BUILD})
  set(CMAKE_UNITY_BUILD_BATCH_SIZE 8)
endmacro()
