# Every dependency is a Debian package; a missing one names the package to install.
#
# The packages' own find scripts print notes that read like errors and are not: Debian's Imath
# config (pulled in by OpenEXR) lists its Python binding, whose library comes with python3-imath,
# and prints a "does not exist" block without it; Ceres' SuiteSparse search prints a line per
# library and "Could NOT find METIS", an optional ordering library that Debian's Ceres and gslam
# do without. Their status messages are hidden here (the variable is function-scoped);
# `cmake --log-level=STATUS` shows them. Warnings and errors still show.
set(GSLAM_FOUND_PACKAGES "")
function(gslam_require_package name apt_package)
  set(CMAKE_MESSAGE_LOG_LEVEL NOTICE)
  find_package(${name} ${ARGN} QUIET)
  if(NOT ${name}_FOUND)
    message(FATAL_ERROR "gslam needs ${name}: apt-get install ${apt_package}")
  endif()
  string(STRIP "${name} ${${name}_VERSION}" found)
  set(GSLAM_FOUND_PACKAGES ${GSLAM_FOUND_PACKAGES} "${found}" PARENT_SCOPE)
endfunction()

gslam_require_package(Eigen3 libeigen3-dev NO_MODULE)
gslam_require_package(glm libglm-dev)
gslam_require_package(Threads libc6-dev)
gslam_require_package(PNG libpng-dev)
gslam_require_package(JPEG libjpeg-dev)
gslam_require_package(OpenEXR libopenexr-dev)
gslam_require_package(TinyGLTF libtinygltf-dev)
gslam_require_package(nlohmann_json nlohmann-json3-dev)
# Image pyramids and gradients for the RGB-D odometry; rgbd (libopencv-contrib-dev): the
# benchmark's baseline, OpenCV's own RGB-D odometry.
gslam_require_package(OpenCV "libopencv-dev libopencv-contrib-dev" COMPONENTS core imgproc features2d calib3d rgbd)
# The keyframe pose graph (loop closure).
gslam_require_package(Ceres libceres-dev)
if(GSLAM_BUILD_TESTS)
  gslam_require_package(GTest libgtest-dev)
endif()
if(GSLAM_BUILD_BENCHMARKS)
  gslam_require_package(benchmark libbenchmark-dev)
endif()

list(JOIN GSLAM_FOUND_PACKAGES ", " found)
message(STATUS "Found ${found} (their find scripts' notes hidden: cmake --log-level=STATUS shows them)")

# Vulkan backend: the loader headers (libvulkan-dev) and glslang (glslang-tools). Without
# them the build goes on CPU-only, with a warning.
set(GSLAM_HAVE_VULKAN OFF)
if(GSLAM_ENABLE_VULKAN)
  find_package(Vulkan QUIET)
  find_program(GSLAM_GLSLANG glslangValidator)
  if(Vulkan_FOUND AND GSLAM_GLSLANG)
    set(GSLAM_HAVE_VULKAN ON)
  else()
    message(WARNING "Vulkan backend disabled: apt-get install libvulkan-dev glslang-tools "
                    "mesa-vulkan-drivers to build it")
  endif()
endif()

# The `gslam live` window: GLFW (libglfw3-dev) and OpenGL (libgl-dev). Without them live mode
# runs --headless only, with a warning.
set(OpenGL_GL_PREFERENCE GLVND)
find_package(glfw3 QUIET)
find_package(OpenGL QUIET)
if(glfw3_FOUND AND OpenGL_FOUND)
  set(GSLAM_HAVE_VIEWER ON)
else()
  set(GSLAM_HAVE_VIEWER OFF)
  message(WARNING "gslam live viewer disabled: apt-get install libglfw3-dev libgl-dev to build it")
endif()
