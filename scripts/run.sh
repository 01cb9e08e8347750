#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine, builds gslam and runs the main job on bundled data:
# a turntable render of assets/demo_map.ply into out/demo_orbit (PNG + EXR).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh
scripts/build.sh
build/app/gslam render assets/demo_map.ply --out out/demo_orbit --orbit 36 --size 640x480 --format png,exr
