// Per-pixel class labels from any segmenter (SAM, Mask2Former, a dataset's ground truth): a
// folder of PNG images, one per colour frame with the colour image's file name stem (8 or 16-bit
// class ids at the colour image's size; 0 = unknown), and classes.json naming the classes:
//   {"classes": [{"id": 1, "name": "floor"}, {"id": 7, "name": "person", "dynamic": true}]}
// Pixels of dynamic classes are left out of tracking and mapping.
#pragma once
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace app {

struct LabelClass {
  uint16_t id = 0;
  std::string name;
  bool dynamic = false;
};

struct LabelSet {
  std::filesystem::path dir;  // holds NAME.png and classes.json
  std::vector<LabelClass> classes;  // in the file's order
  const LabelClass* find(uint16_t id) const;
  const LabelClass* find(const std::string& name) const;
  bool is_dynamic(uint16_t id) const;
  std::string name(uint16_t id) const;  // "unknown" for 0, "class N" for an unlisted id
};

// Reads dir/classes.json. Throws splat::Error naming the file for a missing or malformed file,
// an id outside 1..65535, a repeated id or name, or an empty name.
LabelSet read_label_set(const std::filesystem::path& dir);

// The label image of the colour image `colour` (the same stem, .png, in set.dir): [H, W] class
// ids, or nullopt if there is none (an unlabelled frame). Throws splat::Error naming the file for
// an unreadable image, a size other than width x height, or an id classes.json does not list.
std::optional<std::vector<uint16_t>> read_label_image(const LabelSet& set, const std::filesystem::path& colour,
                                                      int width, int height);

}  // namespace app
