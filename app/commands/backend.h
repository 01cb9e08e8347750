#pragma once
#include <memory>
#include <string>

#include "splat/rasterizer.h"

namespace app {

struct BackendChoice {
  std::string backend = "auto";  // auto | cpu | vulkan
  int device = -1;               // Vulkan device index; -1 picks the best
  int threads = 0;               // CPU threads; 0 = all
};

// Creates the rasterizer asked for. `auto` takes the best available and says why in `note`;
// an explicit backend that cannot run is a splat::Error.
std::unique_ptr<splat::Rasterizer> make_rasterizer(const BackendChoice& choice, std::string& note);

}  // namespace app
