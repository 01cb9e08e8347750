#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine, builds gslam with its tests and runs the whole suite.
# With --sanitize, builds into build-asan/ with AddressSanitizer + UBSan and runs it there.
set -euo pipefail
cd "$(dirname "$0")/.."
# Each stage's wall time, printed as it ends (CI's budget is the sum).
stage_start=$SECONDS
stage_done() { echo "== $1: $((SECONDS - stage_start)) s (total $SECONDS s)"; stage_start=$SECONDS; }
scripts/install_deps.sh
stage_done "dependencies"
# Per-test time limit: the sanitized GCC build (--sanitize) runs the SLAM system tests some 25x slower.
timeout_s=600
if [ "${1:-}" = "--sanitize" ]; then
  export GSLAM_BUILD_DIR=build-asan
  scripts/build.sh -DGSLAM_SANITIZE=address,undefined -DGSLAM_BUILD_BENCHMARKS=OFF
  timeout_s=2400
else
  scripts/build.sh
fi
stage_done "build"
ctest --test-dir "${GSLAM_BUILD_DIR:-build}" --output-on-failure --timeout "$timeout_s" -j "$(nproc)"
stage_done "tests"
if [ "${1:-}" = "--sanitize" ]; then exit 0; fi

# arm64 (Jetson class): cross-built with a portable -march; the CPU suites run under qemu.
scripts/cross_test_arm64.sh
stage_done "arm64 build and tests"

# Hostile input: every reader's libFuzzer target (clang, ASan + UBSan), then the whole suite in
# that same sanitized build (coverage instrumentation is on the readers' libraries alone there).
# Tests that replay a camera in real time replay 8x slower (GSLAM_TEST_TIME_SCALE).
scripts/fuzz.sh "${GSLAM_FUZZ_SECONDS:-15}"
fuzz_build=${GSLAM_FUZZ_BUILD_DIR:-build-fuzz}
cmake --build "$fuzz_build"
stage_done "fuzzing and the sanitized build"
# Fifteen long tests are left out there (they run in the main suite above): under ASan the
# two-lap loop-closure sequence takes over 20 minutes and the exposure, hard-motion, look-alike,
# covisibility, two moving-objects, two label-fusion, unsynchronized-depth and the
# resume-after-Ctrl-C runs 1-20 minutes each, the two 100-frame lens-distortion runs 2.5 minutes,
# the blurred-odometry and vignetting-refinement runs 1.5 minutes each and the blur model's fit
# 1 minute, which would put CI past its budget. Their parts run there in smaller tests: the
# pose graph, place recognition, the exposure model, the odometry's blur weighting, the
# vignetting's gradient, the blur model's views, the mapper's keyframe corrections, the kidnapped
# sequence, covisibility's edges (RunCheckpoint), moving regions, label fusion, the label PLY, a
# lens's undistortion (Undistortion, on frames and through a dataset), a
# continued run's checkpoint (RunCheckpoint, with depth moved to its colour's instant), depth
# reprojection (ReprojectDepth) and Ctrl-C's outputs.
# gslam_ros is not built there (its tests skip): it is a thin layer over `live`, which runs there.
left_out='TwoLapsLoopClosureRemovesOdometryDrift|ExposureEstimate.MeasuresTheExposureTheFramesWereBlurredOver'
left_out+='|HardMotionSyntheticSequenceTracksEveryFrame|CovisibleKeyframesReduceDriftUnderBlur|LookAlikePlaceIsNotTakenForALoop'
left_out+='|MovingObjects\.|CliLabels\.|ResumeAfterCtrlCEndsAsTheUninterruptedRun'
left_out+='|RgbdOdometry.BlurAwareDepthWeightAlignsBlurredFramesBetter|Vignetting.RefinementLearnsTheFramesFallOffAndNoneWhereThereIsNone'
left_out+='|BlurModel.FramesFittedThroughTheirMotionLeaveASharperMap|UnsynchronizedDepthIsMovedToTheColoursInstant'
left_out+='|LensDistortionIsUndistortedAsFramesLoad'
GSLAM_TEST_TIME_SCALE=8 ctest --test-dir "$fuzz_build" --output-on-failure --timeout 1800 -j "$(nproc)" -E "$left_out"
stage_done "the sanitized suite"
