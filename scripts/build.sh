#!/usr/bin/env bash
# Configures and builds gslam (Release) into build/ (or $GSLAM_BUILD_DIR).
#   scripts/build.sh [--target NAME]... [CMAKE_ARGS...]
# --target builds only those targets (scripts/run.sh: --target gslam); without it, everything
# the configuration enables (tests and benchmarks by default). Other arguments go to cmake.
set -euo pipefail
cd "$(dirname "$0")/.."
extra=()
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --target) targets+=(--target "$2"); shift 2 ;;
    *) extra+=("$1"); shift ;;
  esac
done
# CI: warnings fail the build, and Vulkan, Slurm and ROS recording tests fail (not skip) without a
# device, a test cluster, or ROS 1 and the MCAP writer (CI runs as root after scripts/install_deps.sh).
if [ "${CI:-}" = "true" ]; then
  extra+=(-DGSLAM_WARNINGS_AS_ERRORS=ON -DGSLAM_REQUIRE_GPU_TESTS=ON -DGSLAM_REQUIRE_SLURM_TESTS=ON
              -DGSLAM_REQUIRE_ROS_TESTS=ON)
fi
cmake -S . -B "${GSLAM_BUILD_DIR:-build}" -G Ninja -DCMAKE_BUILD_TYPE=Release "${extra[@]}"
cmake --build "${GSLAM_BUILD_DIR:-build}" --parallel "${targets[@]}"
