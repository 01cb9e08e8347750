#!/bin/bash
# Packs what the Vulkan checks need on another x86-64 Linux machine with a GPU driver into the
# git-ignored .device-data/: the Release binaries, their non-glibc libraries, and the
# third-party data (../shared/data) with teddy cut to its first N frames (default 64) so the
# bundle stays under 64 MiB. Run scripts/gpu_check.sh there.
# Usage: scripts/gpu_bundle.sh [N|bench|app N]
# `bench` packs only the rasterizer's tests and benchmarks and the donut map (7 MiB): the full
# bundle's libraries (OpenCV, FFmpeg, ROS) now pass the device tool's 64 MiB.
# `app N` packs gslam for reconstruct and live on teddy's first N frames, with rasterizer_bench,
# splat_tests and the donut map for the mapping iteration's bench and the Vulkan tests: their
# libraries xz-compressed into app.tar.xz, less OpenCV's video and image codecs, whose closures (FFmpeg,
# GDAL, ...) are most of the 350 MiB. Stubs stand in for them (render's video export and ROS's
# compressed images call them; reconstruct and live do not: a call aborts naming the stub).
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
  # The stubs: every symbol gslam takes from the two libraries, each aborting with its name.
  stubs=$(mktemp -d)
  for lib in libopencv_videoio.so.406 libopencv_imgcodecs.so.406; do
    nm -D --defined-only "/lib/x86_64-linux-gnu/$lib" | awk '{print $3}' | sort > "$stubs/defined"
    nm -D --undefined-only build/app/gslam | awk '{print $2}' | sed 's/@.*//' | sort > "$stubs/used"
    { echo '#include <stdio.h>'; echo '#include <stdlib.h>'
      comm -12 "$stubs/defined" "$stubs/used" | while read -r sym; do
        echo "void $sym(void) { fprintf(stderr, \"gslam bundle: %s is a stub\\n\", \"$sym\"); abort(); }"
      done; } > "$stubs/$lib.c"
    gcc -shared -fPIC -Wl,-soname,"$lib" -o "$bundle/lib/$lib" "$stubs/$lib.c"
  done
  rm -rf "$stubs"
else
  cp build/app/gslam build/bench/{rasterizer_bench,mapping_host_bench} build/tests/{splat_tests,app_tests,system_tests} "$bundle/bin/"
fi
# Libraries the target lacks or has in other versions; glibc and libstdc++ come from the target.
# In app mode: only what gslam needs without the two stubbed libraries (LD_LIBRARY_PATH=lib).
closure() {
  if $app_mode; then LD_LIBRARY_PATH=$bundle/lib ldd "$1"; else ldd "$1"; fi
}
for b in "$bundle"/bin/*; do closure "$b" | awk '{print $3}' | grep '^/' | grep -v "^$PWD/$bundle" || true; done | sort -u |
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
