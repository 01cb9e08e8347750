#include "heap_tuning.h"

#include <mutex>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace splat {

void keep_freed_frame_memory() {
#if defined(__GLIBC__)
  static std::once_flag once;
  std::call_once(once, [] {
    mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's upper limit for this setting
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
    // Blocks over that limit (a 1M-Gaussian frame's intersection list, 76 MB at 640x480)
    // would still be mapped per call: serve every block from the heap. glibc falls back to the
    // main arena when another thread's arena cannot grow without mmap.
    mallopt(M_MMAP_MAX, 0);
  });
#endif
}

}  // namespace splat
