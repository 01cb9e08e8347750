// Keeps freed frame-sized buffers inside the process.
#pragma once

namespace splat {

// Every render allocates images and per-Gaussian buffers of a few to a few tens of MB. With
// glibc's defaults such blocks are mmap'd and returned to the kernel on free, so each frame
// page-faults and zeroes them again: half the CPU forward time at 100K Gaussians on a VM.
// This raises glibc's mmap threshold to its maximum (32 MB), turns mmap off for larger blocks
// and raises the trim threshold to 1 GB, once per process, so those blocks are reused from the
// heap (1M Gaussians, 640x480: forward 548 -> 264 ms). It changes the allocator for
// the whole process (peak memory is unchanged; freed memory is kept for the next frame).
// A no-op outside glibc.
void keep_freed_frame_memory();

}  // namespace splat
