#include "io/ply_io.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "io/atomic_file.h"
#include "io/file_error.h"
#include "splat/error.h"

namespace app {
namespace {

enum class Encoding { kAscii, kBinaryLittle, kBinaryBig };

struct Property {
  std::string name;
  std::string type;
  int size = 0;        // bytes in binary encodings
  bool is_list = false;
};

struct Element {
  std::string name;
  std::size_t count = 0;
  std::vector<Property> properties;
  std::size_t stride() const {
    std::size_t s = 0;
    for (const auto& p : properties) s += static_cast<std::size_t>(p.size);
    return s;
  }
};

int type_size(const std::string& type) {
  static const std::map<std::string, int> sizes = {
      {"char", 1},   {"int8", 1},    {"uchar", 1},  {"uint8", 1},   {"short", 2},
      {"int16", 2},  {"ushort", 2},  {"uint16", 2}, {"int", 4},     {"int32", 4},
      {"uint", 4},   {"uint32", 4},  {"float", 4},  {"float32", 4}, {"double", 8},
      {"float64", 8}};
  const auto it = sizes.find(type);
  return it == sizes.end() ? 0 : it->second;
}

bool is_float_type(const std::string& t) {
  return t == "float" || t == "float32" || t == "double" || t == "float64";
}

struct Header {
  Encoding encoding = Encoding::kAscii;
  std::vector<Element> elements;
  std::streamoff data_offset = 0;
};

Header parse_header(std::istream& in, const std::filesystem::path& path) {
  Header h;
  std::string line;
  if (!std::getline(in, line) || line.substr(0, 3) != "ply") fail(path, "not a PLY file (no 'ply' magic)");
  bool have_format = false;
  for (int line_no = 2;; ++line_no) {
    if (!std::getline(in, line)) fail(path, "header has no end_header line");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key == "end_header") break;
    if (key == "comment" || key == "obj_info" || key.empty()) continue;
    if (key == "format") {
      std::string fmt;
      words >> fmt;
      if (fmt == "ascii") h.encoding = Encoding::kAscii;
      else if (fmt == "binary_little_endian") h.encoding = Encoding::kBinaryLittle;
      else if (fmt == "binary_big_endian") h.encoding = Encoding::kBinaryBig;
      else fail(path, "header line " + std::to_string(line_no) + ": unknown format '" + fmt + "'");
      have_format = true;
    } else if (key == "element") {
      Element e;
      std::string count, rest;
      words >> e.name >> count;
      // A plain decimal integer: "1e3" or "-1" are refused, not read as 1 or wrapped.
      uint64_t value = 0;
      const auto [end, error] = std::from_chars(count.data(), count.data() + count.size(), value);
      if (e.name.empty() || count.empty() || error != std::errc{} || end != count.data() + count.size() || (words >> rest)) {
        fail(path, "header line " + std::to_string(line_no) + ": element '" + e.name + "' count '" + count +
                       "' is not a non-negative integer");
      }
      e.count = static_cast<std::size_t>(value);
      h.elements.push_back(e);
    } else if (key == "property") {
      if (h.elements.empty()) fail(path, "header line " + std::to_string(line_no) + ": property before any element");
      Property p;
      words >> p.type;
      if (p.type == "list") {
        std::string count_type, item_type;
        words >> count_type >> item_type >> p.name;
        p.is_list = true;
      } else {
        words >> p.name;
        p.size = type_size(p.type);
        if (p.size == 0) fail(path, "property '" + p.name + "' has unknown type '" + p.type + "'");
      }
      if (p.name.empty()) fail(path, "header line " + std::to_string(line_no) + ": property without a name");
      h.elements.back().properties.push_back(p);
    } else {
      fail(path, "header line " + std::to_string(line_no) + ": unexpected '" + key + "'");
    }
  }
  if (!have_format) fail(path, "header has no format line");
  h.data_offset = in.tellg();
  return h;
}

double decode_binary(const char* p, const std::string& type, bool swap) {
  const std::size_t n = static_cast<std::size_t>(type_size(type));
  char buf[8] = {};
  if (n == 0 || n > sizeof(buf)) return std::nan("");
  std::memcpy(buf, p, n);
  for (std::size_t i = 0; swap && i < n / 2; ++i) std::swap(buf[i], buf[n - 1 - i]);
  auto as = [&](auto v) {
    std::memcpy(&v, buf, sizeof(v));
    return static_cast<double>(v);
  };
  if (type == "char" || type == "int8") return as(int8_t{});
  if (type == "uchar" || type == "uint8") return as(uint8_t{});
  if (type == "short" || type == "int16") return as(int16_t{});
  if (type == "ushort" || type == "uint16") return as(uint16_t{});
  if (type == "int" || type == "int32") return as(int32_t{});
  if (type == "uint" || type == "uint32") return as(uint32_t{});
  if (type == "float" || type == "float32") return as(float{});
  return as(double{});
}

// Column of each vertex property the map needs, -1 where absent.
struct Layout {
  int x = -1, y = -1, z = -1, opacity = -1;
  int dc[3] = {-1, -1, -1}, scale[3] = {-1, -1, -1}, rot[4] = {-1, -1, -1, -1};
  std::vector<int> rest;  // f_rest_0..M-1
  std::vector<int> label, probability;  // label_0..K-1 and label_probability_0..K-1, if any
};

Layout make_layout(const Element& vertex, const std::filesystem::path& path,
                   std::vector<std::string>& skipped) {
  Layout l;
  std::map<int, int> rest, label, probability;
  for (int i = 0; i < static_cast<int>(vertex.properties.size()); ++i) {
    const Property& p = vertex.properties[static_cast<std::size_t>(i)];
    if (p.is_list) fail(path, "vertex property '" + p.name + "' is a list, expected a scalar");
    int* slot = nullptr;
    int index = -1;
    if (p.name == "x") slot = &l.x;
    else if (p.name == "y") slot = &l.y;
    else if (p.name == "z") slot = &l.z;
    else if (p.name == "opacity") slot = &l.opacity;
    else if (p.name == "nx" || p.name == "ny" || p.name == "nz") continue;  // unused normals
    else if (std::sscanf(p.name.c_str(), "f_dc_%d", &index) == 1 && index >= 0 && index < 3) slot = &l.dc[index];
    else if (std::sscanf(p.name.c_str(), "scale_%d", &index) == 1 && index >= 0 && index < 3) slot = &l.scale[index];
    else if (std::sscanf(p.name.c_str(), "rot_%d", &index) == 1 && index >= 0 && index < 4) slot = &l.rot[index];
    else if (std::sscanf(p.name.c_str(), "label_probability_%d", &index) == 1 && index >= 0 && index < 64) {
      probability[index] = i;
      continue;
    } else if (std::sscanf(p.name.c_str(), "label_%d", &index) == 1 && index >= 0 && index < 64) {
      label[index] = i;
      continue;
    } else if (std::sscanf(p.name.c_str(), "f_rest_%d", &index) == 1 && index >= 0) {
      if (!is_float_type(p.type)) fail(path, "property '" + p.name + "' has type " + p.type + ", expected float");
      rest[index] = i;
      continue;
    } else {
      skipped.push_back(p.name);
      continue;
    }
    if (!is_float_type(p.type)) fail(path, "property '" + p.name + "' has type " + p.type + ", expected float");
    *slot = i;
  }
  auto require = [&](int column, const std::string& name) {
    if (column < 0) fail(path, "vertex property '" + name + "' is missing");
  };
  require(l.x, "x");
  require(l.y, "y");
  require(l.z, "z");
  require(l.opacity, "opacity");
  for (int k = 0; k < 3; ++k) require(l.dc[k], "f_dc_" + std::to_string(k));
  for (int k = 0; k < 3; ++k) require(l.scale[k], "scale_" + std::to_string(k));
  for (int k = 0; k < 4; ++k) require(l.rot[k], "rot_" + std::to_string(k));
  for (int k = 0; k < static_cast<int>(rest.size()); ++k) {
    if (!rest.count(k)) fail(path, "f_rest_" + std::to_string(k) + " is missing (f_rest must be numbered 0..M-1)");
    l.rest.push_back(rest[k]);
  }
  // Labels (gslam's semantic maps): label_k with label_probability_k, k = 0..K-1.
  for (int k = 0; k < static_cast<int>(std::max(label.size(), probability.size())); ++k) {
    if (!label.count(k) || !probability.count(k)) {
      fail(path, "label_" + std::to_string(k) + " and label_probability_" + std::to_string(k) +
                     " must both be there (labels are numbered 0..K-1)");
    }
    l.label.push_back(label[k]);
    l.probability.push_back(probability[k]);
  }
  return l;
}

int sh_degree_from_rest(std::size_t rest, const std::filesystem::path& path) {
  for (int degree = 0; degree <= splat::kMaxShDegree; ++degree) {
    if (rest == static_cast<std::size_t>(3 * (splat::sh_coeff_count(degree) - 1))) return degree;
  }
  fail(path, "has " + std::to_string(rest) + " f_rest properties, expected 0, 9, 24 or 45 (SH degree 0..3)");
}

}  // namespace

PlyMap read_ply(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open file");
  const Header header = parse_header(in, path);
  const auto vertex_it = std::find_if(header.elements.begin(), header.elements.end(),
                                      [](const Element& e) { return e.name == "vertex"; });
  if (vertex_it == header.elements.end()) fail(path, "has no 'vertex' element");
  PlyMap out;
  const Layout layout = make_layout(*vertex_it, path, out.skipped_properties);
  splat::Gaussians& g = out.gaussians;
  g.sh_degree = sh_degree_from_rest(layout.rest.size(), path);
  const std::size_t n = vertex_it->count;
  const int k = splat::sh_coeff_count(g.sh_degree);
  const std::size_t columns = vertex_it->properties.size();
  // What the elements declare must fit in the bytes after the header before anything is
  // allocated: a few bytes of header may claim billions of vertices.
  const uint64_t file_bytes = std::filesystem::file_size(path);
  const uint64_t data_bytes = file_bytes - std::min<uint64_t>(file_bytes, static_cast<uint64_t>(header.data_offset));
  uint64_t needed = 0;
  for (auto e = header.elements.begin(); e != std::next(vertex_it); ++e) {
    // Binary: count x stride bytes; ASCII: at least a value and a separator per property.
    const uint64_t per = header.encoding == Encoding::kAscii ? 2 * std::max<uint64_t>(1, e->properties.size()) : e->stride();
    uint64_t bytes = 0;
    if (__builtin_mul_overflow(static_cast<uint64_t>(e->count), per, &bytes) || __builtin_add_overflow(needed, bytes, &needed) ||
        needed > data_bytes) {
      fail(path, "truncated: element '" + e->name + "' declares " + std::to_string(e->count) + " entries, but only " +
                     std::to_string(data_bytes) + " bytes follow the header");
    }
  }

  // Skip the elements stored before the vertices.
  std::vector<double> row(columns);
  in.seekg(header.data_offset);
  for (auto e = header.elements.begin(); e != vertex_it; ++e) {
    if (header.encoding == Encoding::kAscii) {
      std::string skip;
      for (std::size_t i = 0; i < e->count; ++i) {
        if (!std::getline(in, skip)) fail(path, "truncated: element '" + e->name + "' line " + std::to_string(i) + " of " + std::to_string(e->count) + " is missing");
      }
    } else {
      for (const auto& p : e->properties) {
        if (p.is_list) fail(path, "element '" + e->name + "' before the vertices has a list property; cannot skip it");
      }
      in.seekg(static_cast<std::streamoff>(e->count * e->stride()), std::ios::cur);
    }
  }

  g.resize(n);
  const auto top = static_cast<std::size_t>(layout.label.size());
  if (top > 0) {
    out.labels.top = static_cast<int>(top);
    out.labels.ids.resize(n * top);
    out.labels.probabilities.resize(n * top);
  }
  std::vector<char> record(vertex_it->stride());
  const bool swap = header.encoding == Encoding::kBinaryBig;
  std::string line;
  for (std::size_t v = 0; v < n; ++v) {
    if (header.encoding == Encoding::kAscii) {
      if (!std::getline(in, line)) fail(path, "truncated: vertex " + std::to_string(v) + " of " + std::to_string(n) + " is missing");
      std::istringstream words(line);
      for (std::size_t c = 0; c < columns; ++c) {
        std::string word;
        if (!(words >> word)) fail(path, "vertex " + std::to_string(v) + " has " + std::to_string(c) + " values, expected " + std::to_string(columns));
        char* end = nullptr;
        row[c] = std::strtod(word.c_str(), &end);
        if (end == word.c_str() || *end != '\0') fail(path, "vertex " + std::to_string(v) + " property '" + vertex_it->properties[c].name + "': '" + word + "' is not a number");
      }
    } else {
      if (!in.read(record.data(), static_cast<std::streamsize>(record.size()))) {
        fail(path, "truncated: vertex " + std::to_string(v) + " of " + std::to_string(n) + " is missing (" + std::to_string(vertex_it->stride()) + " bytes each)");
      }
      std::size_t offset = 0;
      for (std::size_t c = 0; c < columns; ++c) {
        row[c] = decode_binary(record.data() + offset, vertex_it->properties[c].type, swap);
        offset += static_cast<std::size_t>(vertex_it->properties[c].size);
      }
    }
    auto value = [&](int column) {
      const double x = row[static_cast<std::size_t>(column)];
      if (!std::isfinite(x)) fail(path, "vertex " + std::to_string(v) + " property '" + vertex_it->properties[static_cast<std::size_t>(column)].name + "' is " + std::to_string(x) + ", expected a finite value");
      return static_cast<float>(x);
    };
    g.means[v * 3] = value(layout.x);
    g.means[v * 3 + 1] = value(layout.y);
    g.means[v * 3 + 2] = value(layout.z);
    for (int a = 0; a < 3; ++a) g.log_scales[v * 3 + a] = value(layout.scale[a]);
    for (int a = 0; a < 4; ++a) g.rotations[v * 4 + a] = value(layout.rot[a]);
    g.opacity_logits[v] = value(layout.opacity);
    float* sh = &g.sh[v * static_cast<std::size_t>(k) * 3];
    for (int c = 0; c < 3; ++c) sh[c] = value(layout.dc[c]);
    // f_rest is channel-major: f_rest_(c * (K-1) + (k-1)) is coefficient k of channel c.
    for (int c = 0; c < 3; ++c) {
      for (int coeff = 1; coeff < k; ++coeff) {
        sh[coeff * 3 + c] = value(layout.rest[static_cast<std::size_t>(c * (k - 1) + coeff - 1)]);
      }
    }
    for (std::size_t t = 0; t < top; ++t) {
      const float id = value(layout.label[t]), p = value(layout.probability[t]);
      if (!(id >= 0 && id <= 65535 && id == std::floor(id)) || !(p >= 0 && p <= 1)) {
        fail(path, "vertex " + std::to_string(v) + " label_" + std::to_string(t) + " " + std::to_string(id) +
                       " with probability " + std::to_string(p) + ": expected an id 0..65535 and a probability in [0, 1]");
      }
      out.labels.ids[v * top + t] = static_cast<uint16_t>(id);
      out.labels.probabilities[v * top + t] = p;
    }
  }
  return out;
}

void write_ply(const std::filesystem::path& path, const splat::Gaussians& g, const splat::GaussianLabels* labels) {
  splat::validate_sizes(splat::GaussiansView(g), "write_ply " + path.string());
  const std::size_t top = labels && !labels->empty() ? static_cast<std::size_t>(labels->top) : 0;
  if (top > 0 && (labels->ids.size() != g.size() * top || labels->probabilities.size() != labels->ids.size())) {
    fail(path, "labels for " + std::to_string(labels->size()) + " Gaussians, the map has " + std::to_string(g.size()));
  }
  const std::size_t n = g.size();
  const int k = splat::sh_coeff_count(g.sh_degree);
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) fail(tmp, "cannot open for writing");
    out << "ply\nformat binary_little_endian 1.0\ncomment written by gslam\n"
        << "element vertex " << n << "\n";
    std::vector<std::string> names = {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"};
    for (int i = 0; i < 3 * (k - 1); ++i) names.push_back("f_rest_" + std::to_string(i));
    for (const char* name : {"opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"}) names.push_back(name);
    for (const auto& name : names) out << "property float " << name << "\n";
    for (std::size_t t = 0; t < top; ++t) out << "property ushort label_" << t << "\n";
    for (std::size_t t = 0; t < top; ++t) out << "property float label_probability_" << t << "\n";
    out << "end_header\n";
    static_assert(std::endian::native == std::endian::little, "PLY writer assumes a little-endian host");
    std::vector<float> row(names.size());
    for (std::size_t v = 0; v < n; ++v) {
      std::size_t c = 0;
      for (int a = 0; a < 3; ++a) row[c++] = g.means[v * 3 + a];
      for (int a = 0; a < 3; ++a) row[c++] = 0.f;
      const float* sh = &g.sh[v * static_cast<std::size_t>(k) * 3];
      for (int a = 0; a < 3; ++a) row[c++] = sh[a];
      for (int ch = 0; ch < 3; ++ch)
        for (int coeff = 1; coeff < k; ++coeff) row[c++] = sh[coeff * 3 + ch];
      row[c++] = g.opacity_logits[v];
      for (int a = 0; a < 3; ++a) row[c++] = g.log_scales[v * 3 + a];
      for (int a = 0; a < 4; ++a) row[c++] = g.rotations[v * 4 + a];
      out.write(reinterpret_cast<const char*>(row.data()), static_cast<std::streamsize>(row.size() * sizeof(float)));
      if (top > 0) {
        out.write(reinterpret_cast<const char*>(&labels->ids[v * top]), static_cast<std::streamsize>(top * sizeof(uint16_t)));
        out.write(reinterpret_cast<const char*>(&labels->probabilities[v * top]),
                  static_cast<std::streamsize>(top * sizeof(float)));
      }
    }
    if (!out.flush()) fail(tmp, "write failed (disk full?)");
  });
}

}  // namespace app
