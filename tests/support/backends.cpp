#include "support/backends.h"

#include <map>
#include <memory>
#include <mutex>

#include "splat/error.h"
#include "splat/vulkan_rasterizer.h"

namespace gslam::test {

std::vector<std::string> backend_names() {
  std::vector<std::string> names{"cpu"};
  if (splat::vulkan_backend_built()) names.push_back("vulkan");
  return names;
}

bool gpu_tests_required() {
#ifdef GSLAM_REQUIRE_GPU_TESTS
  return true;
#else
  return false;
#endif
}

splat::Rasterizer* shared_backend(const std::string& name, std::string& why_not) {
  struct Entry {
    std::unique_ptr<splat::Rasterizer> rasterizer;
    std::string why_not;
  };
  static std::mutex mutex;
  // Never destroyed: at exit, a GPU driver loaded after this map was built may already have
  // run its own teardown, and destroying a device then crashes (seen with NVIDIA's driver).
  static auto& cache = *new std::map<std::string, Entry>;
  std::lock_guard lock(mutex);
  auto it = cache.find(name);
  if (it == cache.end()) {
    Entry entry;
    try {
      if (name == "cpu") {
        entry.rasterizer = splat::make_cpu_rasterizer({2});
      } else if (name == "vulkan") {
        entry.rasterizer = splat::make_vulkan_rasterizer({});
      } else if (name == "vulkan_portable") {
        splat::VulkanOptions options;
        options.float_atomics = false;
        options.map_device_memory = false;
        entry.rasterizer = splat::make_vulkan_rasterizer(options);
      } else {
        entry.why_not = "unknown backend";
      }
    } catch (const splat::Error& e) {
      entry.why_not = e.what();
    }
    it = cache.emplace(name, std::move(entry)).first;
  }
  why_not = it->second.why_not;
  return it->second.rasterizer.get();
}

}  // namespace gslam::test
