#!/usr/bin/env bash
# Regenerates everything under assets/ from the project's own generators.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh
build/app/gslam_make_demo_map assets/demo_map.ply
