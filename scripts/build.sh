#!/usr/bin/env bash
# Configures and builds gslam (Release) into build/. Extra arguments go to cmake.
set -euo pipefail
cd "$(dirname "$0")/.."
extra=()
# CI: warnings fail the build, and Vulkan tests fail (not skip) without a device.
if [ "${CI:-}" = "true" ]; then extra+=(-DGSLAM_WARNINGS_AS_ERRORS=ON -DGSLAM_REQUIRE_GPU_TESTS=ON); fi
cmake -S . -B "${GSLAM_BUILD_DIR:-build}" -G Ninja -DCMAKE_BUILD_TYPE=Release "${extra[@]}" "$@"
cmake --build "${GSLAM_BUILD_DIR:-build}" --parallel
