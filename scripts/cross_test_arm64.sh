#!/usr/bin/env bash
# Cross-builds the rasterizer (splat and splat_tests) for arm64 with a portable -march and runs
# its tests under qemu-user-static: the CPU backend's vector code must build and agree with its
# oracles on ARM too. Installs what it needs (Debian's cross compiler, qemu, and GoogleTest's
# arm64 package through multiarch). The other libraries need target packages that Debian cannot
# install beside the build machine's (libopenexr-dev, libopencv-dev); on the device itself the
# whole project builds natively with scripts/build.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
if ! dpkg --print-foreign-architectures | grep -qx arm64; then $sudo dpkg --add-architecture arm64; fi
missing=()
for p in crossbuild-essential-arm64 qemu-user-static libgtest-dev:arm64; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "install: ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
build=${GSLAM_ARM64_BUILD_DIR:-build-arm64}
mkdir -p "$build"
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain_arm64.cmake \
  -DGSLAM_CORE_ONLY=ON -DGSLAM_NATIVE_ARCH=OFF -DGSLAM_ENABLE_VULKAN=OFF -DGSLAM_WARNINGS_AS_ERRORS=ON > "$build/configure.log"
cmake --build "$build"
aarch64-linux-gnu-readelf -h "$build/tests/splat_tests" | grep -q AArch64 || { echo "splat_tests is not an arm64 binary"; exit 1; }
ctest --test-dir "$build" --output-on-failure --timeout 1200 -j "$(nproc)"
