#pragma once
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace gslam::test {

struct Tensor {
  std::vector<long> shape;
  std::vector<float> values;  // row-major
};

// Reads a safetensors file of little-endian F32 tensors: an 8-byte header length, a JSON
// header, then raw data. Throws std::runtime_error on anything else.
std::map<std::string, Tensor> read_safetensors(const std::filesystem::path& path);

}  // namespace gslam::test
