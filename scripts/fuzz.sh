#!/usr/bin/env bash
# Builds the libFuzzer target of every reader with clang under AddressSanitizer + UBSan into
# build-fuzz/ and runs each for SECONDS (default 30; one a core at a time), seeded from
# ../shared/data where present and from inputs the project makes itself. Each input must be
# answered within 10 s and 1 GiB.
# Prints a table of executions per target; a crash or sanitizer report fails the script and
# leaves the reproducer in build-fuzz/findings/.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
build=${GSLAM_FUZZ_BUILD_DIR:-build-fuzz}
data=../shared/data
mkdir -p "$build"
# Line tables alone: sanitizer reports still name file and line, and the build is some 12% faster.
CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGSLAM_BUILD_FUZZERS=ON \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" \
  -DGSLAM_SANITIZE=address,undefined -DGSLAM_ENABLE_VULKAN=OFF -DGSLAM_BUILD_TESTS=ON \
  -DGSLAM_BUILD_BENCHMARKS=OFF -DGSLAM_ENABLE_ROS1_NODE=OFF > "$build/configure.log"
targets=(ply gltf image trajectory dataset config safetensors checkpoint mcap)
cmake --build "$build" --target "${targets[@]/#/fuzz_}"

seed() {  # seed TARGET FILE [PREFIX_BYTE]: copies FILE (its first 64 KiB) into the corpus
  local dir="$build/corpus/$1"; mkdir -p "$dir"
  [ -f "$2" ] || return 0
  local name; name=$(basename "$2")
  if [ -n "${3:-}" ]; then { printf '%b' "$3"; head -c 65536 "$2"; } > "$dir/$name"; else head -c 65536 "$2" > "$dir/$name"; fi
}
teddy=$data/tum_rgbd_fr3_teddy_first200/rgbd_dataset_freiburg3_teddy
kitchen=$data/sevenscenes_redkitchen_first200
seed ply assets/demo_map.ply
seed ply "$data/supersplat_fruit_drops_3dgs_ply/fruit_drops_minimal.ply"
seed gltf "$data/khr_gaussian_splatting_fixtures_bevy/khr_conformance_matrix.glb" '\x00'
seed gltf "$data/khr_gaussian_splatting_fixtures_bevy/khr_conformance_matrix.gltf" '\x01'
seed gltf "$data/khr_gaussian_splatting_fixtures_bevy/khr_extensible_fallback.gltf" '\x01'
seed image "$(ls "$kitchen"/depth/*.png 2>/dev/null | head -1)"
seed image "$(ls "$teddy"/rgb/*.png 2>/dev/null | head -1)"
seed trajectory "$teddy/groundtruth.txt"
seed dataset "$teddy/rgb.txt" '\x00'
seed dataset "$kitchen/rgb.txt" '\x00'
seed safetensors "$data/gsplat_reference_render_brush/tiny_case.safetensors"
# Inputs the project makes itself: a map and a trajectory it writes, its configuration.
mkdir -p "$build/made"
printf '1000.0 0 0 0 0 0 0 1\n1000.1 0.01 0 0 0 0 0.0499792 0.99875\n' > "$build/made/trajectory.txt"
seed trajectory "$build/made/trajectory.txt"
printf '0 traj line\n1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n' > "$build/made/traj.txt"
seed dataset "$build/made/traj.txt" '\x01'
printf '{"keyframe_every": 4, "odometry": {"iterations": [3, 3]}, "mapping": {"window": 2}}' > "$build/made/config.json"
seed config "$build/made/config.json"
# A checkpoint of an empty run: magic, header length (8 bytes, little-endian), header, 17 empty arrays.
header='{"run":{},"tracker":{"last_poses":[],"last_times":[],"last_keyframe":[1,0,0,0,0,1,0,0,0,0,1,0],'\
'"since_keyframe":0,"references":[],"residual_spreads":[]},"mapper":{"sh_degree":0,"keyframes":[],"vignetting":[0,0],'\
'"vignetting_m":[0,0],"vignetting_v":[0,0],"vignetting_steps":0,"added":0,"rng":"1"},"mapper_keyframes":[],'\
'"keyframe_world":[],"frames":[],"totals":{"keyframes_mapped":0,"keyframes_skipped":0,"gaussians_added":0,'\
'"gaussians_pruned":0,"iterations":0,"last_loss":0,"mapping_ms":0},"edges":[],"loop_events":[],'\
'"tracker_correction":[1,0,0,0,0,1,0,0,0,0,1,0]}'
length=${#header}
{ printf 'gslam checkpoint 1\n'; printf "\\x$(printf %02x $((length & 255)))\\x$(printf %02x $((length >> 8)))"
  head -c 6 /dev/zero; printf '%s' "$header"; head -c 136 /dev/zero; } > "$build/made/checkpoint.bin"
seed checkpoint "$build/made/checkpoint.bin"
# Small MCAP files (a 4x3 frame, chunks uncompressed, zstd, lz4) from the MCAP reference writer,
# where Node and its packages are installed (scripts/install_deps.sh).
tools=${GSLAM_TOOLS_DIR:-$HOME/.cache/gslam/tools}
if command -v node > /dev/null && [ -d "$tools/node_modules/@mcap/core" ]; then
  mkdir -p "$build/made/mcap"
  head -c 36 /dev/zero | tr '\0' '\200' > "$build/made/mcap/colour"
  head -c 24 /dev/zero | tr '\0' '\010' > "$build/made/mcap/depth"
  for compression in "" zstd lz4; do
    printf '{"compression": "%s", "width": 4, "height": 3, "k": [5, 0, 2, 0, 5, 1.5, 0, 0, 1],
      "colour_topic": "/rgb/image", "colour_encoding": "rgb8", "depth_topic": "/depth/image",
      "depth_encoding": "16UC1", "info_topic": "/rgb/camera_info", "frames": [
      {"colour": "colour", "colour_stamp": [10, 0], "depth": "depth", "depth_stamp": [10, 5000000]},
      {"colour": "colour", "colour_stamp": [10, 33000000], "depth": "depth", "depth_stamp": [10, 34000000]}]}' \
      "$compression" > "$build/made/mcap/manifest.json"
    node tests/interop/write_mcap.mjs "$tools" "$build/made/mcap/manifest.json" "$build/made/frames_${compression:-none}.mcap"
    seed mcap "$build/made/frames_${compression:-none}.mcap"
  done
fi
mkdir -p "$build/findings"
echo "| target | seconds | executions | executions/s | result |"
echo "|---|---|---|---|---|"
# One fuzzer a core at a time (each is single-threaded): every target still gets SECONDS of a core.
fuzz_target() {  # fuzz_target TARGET: runs it and writes its table row to $build/fuzz_TARGET.row
  local t=$1 log="$build/fuzz_$1.log" result runs
  # The targets write each input to a file in TMPDIR: a folder of the build's, removed after.
  local scratch="$build/scratch_$t"
  mkdir -p "$scratch"
  if TMPDIR="$scratch" "$build/tests/fuzz/fuzz_$t" "$build/corpus/$t" -max_total_time="$seconds" -max_len=65536 -timeout=10 \
       -rss_limit_mb=1024 -artifact_prefix="$build/findings/$t-" -print_final_stats=1 > "$log" 2>&1; then
    result=clean
  else
    result="FAILED (see $log)"
  fi
  rm -rf "$scratch"
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  echo "| $t | $seconds | $runs | $((runs / seconds)) | $result |" > "$build/fuzz_$t.row"
}
jobs_at_once=$(nproc)
rm -f "$build"/fuzz_*.row
for t in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$jobs_at_once" ]; do wait -n; done
  fuzz_target "$t" &
done
wait
status=0
for t in "${targets[@]}"; do
  cat "$build/fuzz_$t.row"
  grep -q '| clean |$' "$build/fuzz_$t.row" || status=1
done
exit $status
