# Cross build for 64-bit ARM (Jetson class) with Debian's crossbuild-essential-arm64. Target
# libraries come from an arm64 sysroot (GSLAM_ARM64_SYSROOT: a folder Debian's arm64 packages
# were extracted into, as scripts/cross_test_arm64.sh makes it) or, without one, from arm64
# packages installed through multiarch. Tests run under qemu-user-static.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)
set(GSLAM_ARM64_SYSROOT "$ENV{GSLAM_ARM64_SYSROOT}" CACHE PATH "arm64 sysroot (empty: multiarch packages)")
if(GSLAM_ARM64_SYSROOT)
  set(CMAKE_SYSROOT ${GSLAM_ARM64_SYSROOT})
  set(CMAKE_FIND_ROOT_PATH ${GSLAM_ARM64_SYSROOT})
  # Shared libraries' own dependencies are looked up in the sysroot too.
  set(rpath_link "-Wl,-rpath-link,${GSLAM_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu:${GSLAM_ARM64_SYSROOT}/lib/aarch64-linux-gnu")
  set(CMAKE_EXE_LINKER_FLAGS_INIT "${rpath_link}")
  set(CMAKE_SHARED_LINKER_FLAGS_INIT "${rpath_link}")
  set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64-static -L ${GSLAM_ARM64_SYSROOT})
else()
  set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu)
  set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64-static -L /usr/aarch64-linux-gnu)
endif()
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
