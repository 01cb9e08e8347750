#!/bin/bash
# Packs what the Vulkan checks need on another x86-64 Linux machine with a GPU driver into the
# git-ignored .device-data/: the Release binaries, their non-glibc libraries, and the
# third-party data (../shared/data) with teddy cut to its first N frames (default 64) so the
# bundle stays under 64 MiB. Run scripts/gpu_check.sh there.
# Usage: scripts/gpu_bundle.sh [N|bench|app N]
# `bench` packs only the rasterizer's tests and benchmarks and the donut map (7 MiB): the full
# bundle's libraries (OpenCV, Ceres, ROS) now pass the device tool's 64 MiB.
# `app N` packs gslam for reconstruct and live on teddy's first N frames, with rasterizer_bench,
# splat_tests and the donut map for the mapping iteration's bench and the Vulkan tests: their
# libraries xz-compressed into app.tar.xz.
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${1:-64}
app_mode=false
if [ "$frames" = app ]; then app_mode=true; frames=${2:-48}; fi
shared=../shared/data
bundle=.device-data
[ -x build/app/gslam ] || { echo "gpu_bundle: build first (scripts/build.sh)" >&2; exit 1; }
[ -d "$shared" ] || { echo "gpu_bundle: $shared not found" >&2; exit 1; }
rm -rf "$bundle" && mkdir -p "$bundle/bin" "$bundle/lib" "$bundle/data"
if [ "$frames" = bench ]; then
  cp build/bench/{rasterizer_bench,mapping_host_bench} build/tests/splat_tests "$bundle/bin/"
elif $app_mode; then
  cp build/app/gslam build/bench/rasterizer_bench build/tests/splat_tests "$bundle/bin/"
else
  cp build/app/gslam build/bench/{rasterizer_bench,mapping_host_bench} build/tests/{splat_tests,app_tests,system_tests} "$bundle/bin/"
fi
# Libraries the target lacks or has in other versions; glibc and libstdc++ come from the target.
for b in "$bundle"/bin/*; do ldd "$b" | awk '{print $3}' | grep '^/' | grep -v "^$PWD/$bundle" || true; done | sort -u |
  grep -v -E 'libc\.so|libm\.so|libstdc\+\+|libgcc_s|libpthread|libdl\.so|librt\.so|ld-linux|libvulkan|libGLdispatch|libOpenGL' |
  xargs -I{} cp -L {} "$bundle/lib/"
if [ "$frames" = bench ]; then
  cp -r "$shared"/{INDEX.md,v3dg_donut_3dgs_ply} "$bundle/data/" && du -sh "$bundle" && exit 0
fi
if $app_mode; then
  tar -C "$bundle" -cJf "$bundle/app.tar.xz" bin lib && rm -rf "$bundle/bin" "$bundle/lib"
  mkdir -p "$bundle/data/v3dg_donut_3dgs_ply"  # the benchmark's map
  cp "$shared"/v3dg_donut_3dgs_ply/{fused.ply,SOURCE.md} "$bundle/data/v3dg_donut_3dgs_ply/"
else
  cp -r "$shared"/{INDEX.md,gsplat_reference_render_brush,khr_gaussian_splatting_fixtures_bevy,supersplat_fruit_drops_3dgs_ply,v3dg_donut_3dgs_ply} "$bundle/data/"
fi
src=$shared/tum_rgbd_fr3_teddy_first200/rgbd_dataset_freiburg3_teddy
dst=$bundle/data/tum_rgbd_fr3_teddy_first200/rgbd_dataset_freiburg3_teddy
mkdir -p "$dst/rgb" "$dst/depth"
cp "$src/groundtruth.txt" "$dst/" && cp "$src/../SOURCE.md" "$dst/.."
for list in rgb depth; do
  (head -3 "$src/$list.txt"; grep -v "^#" "$src/${list}_first200.txt" | sed -n "1,${frames}p") > "$dst/$list.txt"
  grep -v '^#' "$dst/$list.txt" | awk '{print $2}' | while read -r f; do cp "$src/$f" "$dst/$f"; done
done
du -sh "$bundle"
