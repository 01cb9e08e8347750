#include "support/backends.h"

#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>

#include <gtest/gtest.h>

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
  return std::getenv("GSLAM_REQUIRE_GPU_TESTS") != nullptr;
#endif
}

namespace {

struct Entry {
  std::unique_ptr<splat::Rasterizer> rasterizer;
  std::string why_not;
};
std::mutex cache_mutex;
std::map<std::string, Entry> cache;

// Destroys the backends after the last test, while GPU drivers are still loaded: by the time
// static objects are destroyed, a driver loaded after this cache was built (NVIDIA's) may have
// torn itself down, and destroying a device then crashes.
class ReleaseBackends : public ::testing::Environment {
 public:
  void TearDown() override {
    std::lock_guard lock(cache_mutex);
    cache.clear();
  }
};
[[maybe_unused]] ::testing::Environment* const release_backends =
    ::testing::AddGlobalTestEnvironment(new ReleaseBackends);

}  // namespace

splat::Rasterizer* shared_backend(const std::string& name, std::string& why_not) {
  std::lock_guard lock(cache_mutex);
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
