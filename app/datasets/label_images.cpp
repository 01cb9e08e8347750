#include "datasets/label_images.h"

#include <algorithm>
#include <fstream>
#include <set>

#include <nlohmann/json.hpp>

#include "io/file_error.h"
#include "io/image_io.h"

namespace app {

const LabelClass* LabelSet::find(uint16_t id) const {
  const auto it = std::find_if(classes.begin(), classes.end(), [&](const LabelClass& c) { return c.id == id; });
  return it == classes.end() ? nullptr : &*it;
}

const LabelClass* LabelSet::find(const std::string& wanted) const {
  const auto it = std::find_if(classes.begin(), classes.end(), [&](const LabelClass& c) { return c.name == wanted; });
  return it == classes.end() ? nullptr : &*it;
}

bool LabelSet::is_dynamic(uint16_t id) const {
  const LabelClass* c = find(id);
  return c && c->dynamic;
}

std::string LabelSet::name(uint16_t id) const {
  if (id == 0) return "unknown";
  const LabelClass* c = find(id);
  return c ? c->name : "class " + std::to_string(id);
}

LabelSet read_label_set(const std::filesystem::path& dir) {
  const std::filesystem::path path = dir / "classes.json";
  if (!std::filesystem::is_regular_file(path)) fail(path, "missing: a labels folder needs classes.json naming its class ids");
  if (std::filesystem::file_size(path) > (16u << 20)) fail(path, "larger than 16 MiB; not a class list");
  LabelSet set;
  set.dir = dir;
  try {
    std::ifstream in(path);
    const nlohmann::json doc = nlohmann::json::parse(in);
    std::set<uint16_t> ids;
    std::set<std::string> names;
    for (const nlohmann::json& c : doc.at("classes")) {
      const long long id = c.at("id").get<long long>();
      if (id < 1 || id > 65535) fail(path, "class id " + std::to_string(id) + " outside 1..65535 (0 means unknown)");
      LabelClass k;
      k.id = static_cast<uint16_t>(id);
      k.name = c.at("name").get<std::string>();
      k.dynamic = c.value("dynamic", false);
      if (k.name.empty()) fail(path, "class " + std::to_string(id) + " has an empty name");
      if (!ids.insert(k.id).second) fail(path, "class id " + std::to_string(id) + " is listed twice");
      if (!names.insert(k.name).second) fail(path, "class name '" + k.name + "' is listed twice");
      set.classes.push_back(std::move(k));
    }
  } catch (const nlohmann::json::exception& e) {
    fail(path, std::string("malformed class list (expected {\"classes\": [{\"id\": 1, \"name\": \"floor\"}, ...]}): ") + e.what());
  }
  if (set.classes.empty()) fail(path, "lists no class");
  return set;
}

std::optional<std::vector<uint16_t>> read_label_image(const LabelSet& set, const std::filesystem::path& colour,
                                                      int width, int height) {
  const std::filesystem::path path = set.dir / (colour.stem().string() + ".png");
  if (!std::filesystem::exists(path)) return std::nullopt;
  splat::Image16 image = read_png_labels(path);
  if (image.width != width || image.height != height) {
    fail(path, "label image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                   ", its colour image " + std::to_string(width) + "x" + std::to_string(height));
  }
  std::vector<uint8_t> listed(65536, 0);
  listed[0] = 1;
  for (const LabelClass& c : set.classes) listed[c.id] = 1;
  for (const uint16_t id : image.data) {
    if (!listed[id]) fail(path, "class id " + std::to_string(id) + " is not in " + (set.dir / "classes.json").string());
  }
  return std::move(image.data);
}

}  // namespace app
