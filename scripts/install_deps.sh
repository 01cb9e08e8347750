#!/usr/bin/env bash
# Installs the Debian 12 packages gslam builds with, skipping those already present.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libglm-dev libpng-dev libjpeg-dev libopenexr-dev libtinygltf-dev nlohmann-json3-dev
  libcli11-dev libgtest-dev libbenchmark-dev libstb-dev libopencv-dev
  libvulkan-dev glslang-tools mesa-vulkan-drivers
  libglfw3-dev libgl-dev libgl1-mesa-dri xvfb xauth
  clang libclang-rt-14-dev
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install: all ${#packages[@]} packages present"
  exit 0
fi
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "install: ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
