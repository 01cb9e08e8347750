#!/usr/bin/env bash
# Installs the Debian 12 packages gslam builds with, skipping those already present. slurm-wlm
# and munge serve the --slurm tests, which start their own daemons; this script starts no service.
# The ROS 1 packages (Debian's Noetic-era rosbag, sensor_msgs; rosbag/bag.h needs the include
# folders of pluginlib, class_loader, rcpputils, rcutils, ament_index_cpp) let gslam read .bag
# files and the tests write them; with roscpp and tf2_ros gslam_ros (the node) is
# built, and ros-core's roscore, rosbag play, rostopic and rosservice test it (the Python message
# packages serve rostopic, rosservice and scripts/ros_node_bench.sh). gslam builds
# without any of them. zstd and lz4 decompress MCAP chunks.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libglm-dev libpng-dev libjpeg-dev libopenexr-dev libtinygltf-dev nlohmann-json3-dev
  libcli11-dev libgtest-dev libbenchmark-dev libstb-dev libopencv-dev libopencv-contrib-dev libceres-dev
  libvulkan-dev glslang-tools mesa-vulkan-drivers
  libglfw3-dev libgl-dev libgl1-mesa-dri xvfb xauth
  clang libclang-rt-14-dev
  ffmpeg
  slurm-wlm munge
  libzstd-dev liblz4-dev lz4
  librosbag-dev libroscpp-dev libsensor-msgs-dev libtf2-msgs-dev libroslz4-dev
  pluginlib-dev libclass-loader-dev librcpputils-dev librcutils-dev libament-index-cpp-dev
  libtf2-ros-dev libnav-msgs-dev libstd-srvs-dev
  ros-core python3-tf2-msgs python3-std-srvs python3-sensor-msgs python3-pil python3-numpy
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Node runs the Khronos glTF validator in the tests; any Node (Debian's, or one already there).
command -v node > /dev/null && command -v npm > /dev/null || missing+=(nodejs npm)
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
if [ ${#missing[@]} -eq 0 ]; then
  echo "install: all ${#packages[@]} packages present"
else
  echo "install: ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
# The glTF validator (a test tool) from the npm registry, pinned, where the tests look for it.
validator_dir=${GSLAM_TOOLS_DIR:-$HOME/.cache/gslam/tools}
validator_version=2.0.0-dev.3.10
if ! grep -qs "\"version\": \"$validator_version\"" "$validator_dir/node_modules/gltf-validator/package.json"; then
  echo "install: gltf-validator@$validator_version into $validator_dir"
  mkdir -p "$validator_dir"
  npm install --prefix "$validator_dir" --no-audit --no-fund --silent "gltf-validator@$validator_version"
fi
# The MCAP project's reference writer with ROS 2 CDR serialization (tests/interop/write_mcap.mjs
# writes the test MCAP files with them; its lz4 chunks come from the lz4 command), the message
# definition parser and the zstd chunk compressor, pinned, beside the validator.
mcap_packages=(@mcap/core@2.2.2 @foxglove/rosmsg2-serialization@3.1.0 @foxglove/rosmsg@5.0.5
               @foxglove/wasm-zstd@1.0.1)
if ! grep -qs '"version": "2.2.2"' "$validator_dir/node_modules/@mcap/core/package.json" ||
   ! grep -qs '"version": "1.0.1"' "$validator_dir/node_modules/@foxglove/wasm-zstd/package.json"; then
  echo "install: ${mcap_packages[*]} into $validator_dir"
  mkdir -p "$validator_dir"
  npm install --prefix "$validator_dir" --no-audit --no-fund --silent "gltf-validator@$validator_version" \
    "${mcap_packages[@]}"
fi
