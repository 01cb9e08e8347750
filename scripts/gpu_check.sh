#!/bin/bash
# Runs the Vulkan checks on a GPU machine, from the repository root, on the bundle that
# scripts/gpu_bundle.sh made: STEP = tests (the Vulkan tests), bench (rasterizer_bench),
# teddy (reconstruct + eval on the teddy prefix), render (donut orbit, Vulkan and CPU), live
# (replayed at 1x and 0.25x), all (the first four), or app (on `gpu_bundle.sh app N`: the Vulkan
# tests of splat_tests, the mapping iteration's bench, reconstruct with the resident map and,
# unless HOST_LOOP=0, with the host loop, then live at 1x). Results go to $OUT (default
# /tmp/gpu_out).
# The binaries carry their build's absolute paths (/work/main, ../shared/data): links stand in.
# Expects the Vulkan loader and glvnd unpacked from .gl/*.deb when present (a bare NVIDIA image).
R=$PWD; B=$R/.device-data; OUT=${OUT:-/tmp/gpu_out}; mkdir -p "$OUT"
if ls .gl/*.deb > /dev/null 2>&1; then for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig; fi
if [ -f "$B/app.tar.xz" ]; then mkdir -p "$B/app" && tar -C "$B/app" -xJf "$B/app.tar.xz"; ln -sfn app/bin "$B/bin"; ln -sfn app/lib "$B/lib"; fi
export LD_LIBRARY_PATH=$B/lib:/usr/local/nvidia/lib64:/usr/local/nvidia/lib
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f $icd ] && export VK_DRIVER_FILES=$icd
mkdir -p /work/shared; [ -e /work/main ] || ln -s "$R" /work/main; [ -e /work/shared/data ] || ln -s "$B/data" /work/shared/data
[ -x "$B/bin/gslam" ] && mkdir -p build/app && cp "$B/bin/gslam" build/app/gslam
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv | tee "$OUT/gpu.txt"
STEP=${1:-all}
T=$B/data/tum_rgbd_fr3_teddy_first200/rgbd_dataset_freiburg3_teddy
if [ "$STEP" = all ] || [ "$STEP" = tests ]; then
  for t in splat_tests app_tests system_tests; do
    timeout 240 "$B/bin/$t" --gtest_brief=1 --gtest_filter='*Vulkan*:*vulkan*' > "$OUT/$t.log" 2>&1; echo "$t rc=$?"; tail -3 "$OUT/$t.log"
  done
fi
if [ "$STEP" = all ] || [ "$STEP" = bench ]; then
  timeout 200 "$B/bin/rasterizer_bench" --benchmark_filter=vulkan 2>&1 | tee "$OUT/bench.txt"
  timeout 60 "$B/bin/mapping_host_bench" 2>&1 | tee "$OUT/host_bench.txt"  # the host's share of a mapping step
fi
if [ "$STEP" = all ] || [ "$STEP" = teddy ]; then
  timeout 240 build/app/gslam reconstruct "$T" --backend vulkan --out /tmp/teddy_vk > "$OUT/teddy_vk.log" 2>&1; echo "reconstruct rc=$?"; tail -3 "$OUT/teddy_vk.log"
  timeout 120 build/app/gslam eval /tmp/teddy_vk --dataset "$T" --backend vulkan 2>&1 | tail -1
  cp /tmp/teddy_vk/summary.json "$OUT/teddy_vk_summary.json"
fi
if [ "$STEP" = all ] || [ "$STEP" = render ]; then
  for be in vulkan cpu; do
    timeout 120 build/app/gslam render "$B/data/v3dg_donut_3dgs_ply/fused.ply" --orbit 60 --size 1280x720 --format png --backend $be --out /tmp/render_$be 2>&1 | tail -1
  done
fi
if [ "$STEP" = live ]; then
  for sp in 1 0.25; do
    timeout 150 build/app/gslam live "$T" --out /tmp/live_$sp --headless --backend vulkan --speed $sp > "$OUT/live_$sp.log" 2>&1; echo "live speed $sp rc=$?"; tail -2 "$OUT/live_$sp.log"
    timeout 60 build/app/gslam eval /tmp/live_$sp --dataset "$T" --backend vulkan 2>&1 | tail -1
  done
fi
if [ "$STEP" = app ]; then
  timeout 240 "$B/bin/splat_tests" --gtest_brief=1 --gtest_filter='*Vulkan*:*vulkan*:*Resident*' > "$OUT/splat_tests.log" 2>&1; echo "splat_tests rc=$?"; tail -2 "$OUT/splat_tests.log"
  [ -x "$B/bin/rasterizer_bench" ] && timeout 120 "$B/bin/rasterizer_bench" --benchmark_filter='MappingResident|ForwardBackward/vulkan/100000/640' 2>&1 | tee "$OUT/bench.txt"
  echo '{"mapping": {"device_resident": false}}' > /tmp/host_loop.json
  runs=(resident); [ "${HOST_LOOP:-1}" = 1 ] && runs+=(host_loop)
  for run in "${runs[@]}"; do
    config=(); [ $run = host_loop ] && config=(--config /tmp/host_loop.json)
    timeout 240 build/app/gslam reconstruct "$T" --backend vulkan "${config[@]}" --out /tmp/rec_$run > "$OUT/rec_$run.log" 2>&1; echo "reconstruct $run rc=$?"; tail -2 "$OUT/rec_$run.log"
    cp /tmp/rec_$run/summary.json "$OUT/rec_${run}_summary.json"
  done
  timeout 150 build/app/gslam live "$T" --out /tmp/live_1 --headless --backend vulkan --speed 1 > "$OUT/live_1.log" 2>&1; echo "live rc=$?"; tail -2 "$OUT/live_1.log"
  cp /tmp/live_1/summary.json "$OUT/live_1_summary.json"
fi
