#include "support/safetensors.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace gslam::test {

std::map<std::string, Tensor> read_safetensors(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path.string());
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
  uint64_t header_len = 0;
  if (bytes.size() < 8) throw std::runtime_error(path.string() + ": truncated");
  std::memcpy(&header_len, bytes.data(), 8);
  if (header_len > bytes.size() - 8) throw std::runtime_error(path.string() + ": header longer than the file");
  const std::size_t data_size = bytes.size() - 8 - header_len;
  const char* data = bytes.data() + 8 + header_len;
  std::map<std::string, Tensor> tensors;
  try {
    const auto header = nlohmann::json::parse(bytes.begin() + 8, bytes.begin() + 8 + long(header_len));
    for (const auto& [name, info] : header.items()) {
      if (name == "__metadata__") continue;
      if (info.at("dtype") != "F32") throw std::runtime_error(path.string() + ": " + name + ": dtype is not F32");
      Tensor t;
      t.shape = info.at("shape").get<std::vector<long>>();
      const auto offsets = info.at("data_offsets").get<std::vector<std::size_t>>();
      // Offsets in order, inside the data, a whole number of floats.
      if (offsets.size() != 2 || offsets[0] > offsets[1] || offsets[1] > data_size || (offsets[1] - offsets[0]) % 4 != 0) {
        throw std::runtime_error(path.string() + ": " + name + ": data_offsets outside the file's " +
                                 std::to_string(data_size) + " data bytes");
      }
      t.values.resize((offsets[1] - offsets[0]) / 4);
      if (!t.values.empty()) std::memcpy(t.values.data(), data + offsets[0], offsets[1] - offsets[0]);  // an empty vector's data() may be null
      tensors.emplace(name, std::move(t));
    }
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path.string() + ": " + e.what());
  }
  return tensors;
}

}  // namespace gslam::test
