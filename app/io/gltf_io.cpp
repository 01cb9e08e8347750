#include "io/gltf_io.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <optional>

#include <Eigen/Geometry>
#include <tiny_gltf.h>

#include "io/atomic_file.h"
#include "io/file_error.h"
#include "io/image_io.h"
#include "splat/error.h"

namespace app {
namespace {

constexpr const char* kExtension = "KHR_gaussian_splatting";
constexpr const char* kPrefix = "KHR_gaussian_splatting:";
// gslam's semantic labels, as application-specific attributes (glTF: names start with '_').
const std::string kLabel = "_LABEL_", kLabelProbability = "_LABEL_PROBABILITY_";
constexpr int kMaxLabels = 64;
constexpr double kShC0 = 0.28209479177387814;
// write_gltf's mark on the node whose rotation turns gslam's world frame into glTF's axes.
constexpr const char* kGslamExtras = "gslam";
constexpr const char* kNodeRotation = "node_rotation";
constexpr const char* kWorldToGltf = "world_to_gltf";

double decode_component(const unsigned char* p, int component_type, bool normalized) {
  auto as = [&](auto v) {
    std::memcpy(&v, p, sizeof(v));
    return v;
  };
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return as(float{});
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      const double v = as(int8_t{});
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
      const double v = as(uint8_t{});
      return normalized ? v / 255.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      const double v = as(int16_t{});
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      const double v = as(uint16_t{});
      return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return as(uint32_t{});
    default: return std::nan("");
  }
}

// Element `index` of `list`, or a one-line error naming what refers to it.
template <typename T>
const T& element(const std::vector<T>& list, int index, const std::string& what, const std::filesystem::path& path) {
  if (index < 0 || static_cast<std::size_t>(index) >= list.size()) {
    fail(path, what + " " + std::to_string(index) + " does not exist (" + std::to_string(list.size()) + " defined)");
  }
  return list[static_cast<std::size_t>(index)];
}

// a + b and a * b, failing with `what` on overflow (crafted offsets and counts near 2^64).
uint64_t add_checked(uint64_t a, uint64_t b, const std::string& what, const std::filesystem::path& path) {
  uint64_t r = 0;
  if (__builtin_add_overflow(a, b, &r)) fail(path, what + " overflows 64 bits");
  return r;
}
uint64_t mul_checked(uint64_t a, uint64_t b, const std::string& what, const std::filesystem::path& path) {
  uint64_t r = 0;
  if (__builtin_mul_overflow(a, b, &r)) fail(path, what + " overflows 64 bits");
  return r;
}

// Decodes accessor `index` into floats, checking its type has `components` per element and
// that it holds `expected` elements where given (every attribute has one per splat). Every
// size is checked against the bytes that exist before anything is allocated; an accessor
// without a buffer view (all zeros) must have an expected count to be bounded by.
std::vector<float> read_accessor(const tinygltf::Model& model, int index, int components, const std::string& what,
                                 const std::filesystem::path& path, std::optional<std::size_t> expected = {}) {
  const tinygltf::Accessor& a = element(model.accessors, index, what + ": accessor", path);
  const std::string name = what + ": accessor " + std::to_string(index);
  const int got = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type));
  if (got != components) {
    fail(path, name + " has " + std::to_string(got) + " components, expected " + std::to_string(components));
  }
  if (expected && a.count != *expected) {
    fail(path, name + " has " + std::to_string(a.count) + " elements, expected " + std::to_string(*expected) + " (one per splat)");
  }
  const uint64_t values = mul_checked(a.count, static_cast<uint64_t>(components), name + " count", path);
  if (a.bufferView < 0) {
    if (!expected) fail(path, name + " has no buffer view (no data)");
    return std::vector<float>(values, 0.f);  // glTF: an accessor without a view is all zeros
  }
  const tinygltf::BufferView& view = element(model.bufferViews, a.bufferView, name + ": buffer view", path);
  const tinygltf::Buffer& buffer = element(model.buffers, view.buffer, name + ": buffer", path);
  const int component_size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.componentType));
  if (component_size <= 0) fail(path, name + ": unsupported component type " + std::to_string(a.componentType));
  const uint64_t element_size = static_cast<uint64_t>(component_size) * static_cast<uint64_t>(components);
  const uint64_t stride = view.byteStride > 0 ? view.byteStride : element_size;
  if (stride < element_size) fail(path, name + ": byte stride " + std::to_string(stride) + " is smaller than an element");
  if (add_checked(view.byteOffset, view.byteLength, name + ": view end", path) > buffer.data.size()) {
    fail(path, name + ": its buffer view ends past its buffer's " + std::to_string(buffer.data.size()) + " bytes");
  }
  if (a.count > 0) {
    const uint64_t span = add_checked(mul_checked(stride, a.count - 1, name + " extent", path), element_size, name + " extent", path);
    if (add_checked(a.byteOffset, span, name + " end", path) > view.byteLength) {
      fail(path, name + " reads past the end of its buffer view");
    }
  }
  const std::size_t start = static_cast<std::size_t>(view.byteOffset + a.byteOffset);
  std::vector<float> out(values, 0.f);
  for (std::size_t e = 0; e < a.count; ++e) {
    for (int c = 0; c < components; ++c) {
      const double v = decode_component(buffer.data.data() + start + e * stride +
                                            static_cast<std::size_t>(c * component_size),
                                        a.componentType, a.normalized);
      if (!std::isfinite(v)) {
        fail(path, what + " of splat " + std::to_string(e) + " is " + std::to_string(v) + ", expected a finite value");
      }
      out[e * static_cast<std::size_t>(components) + static_cast<std::size_t>(c)] = static_cast<float>(v);
    }
  }
  return out;
}

// File access for .gltf files: only files inside the glTF's own folder (no absolute paths,
// no "..", no symbolic link that leads out).
struct FolderJail {
  std::filesystem::path root;  // canonical
  bool inside(const std::string& file) const {
    std::error_code ec;
    const std::filesystem::path resolved = std::filesystem::weakly_canonical(file, ec);
    if (ec) return false;
    const auto [root_end, ignored] = std::mismatch(root.begin(), root.end(), resolved.begin(), resolved.end());
    return root_end == root.end();
  }
};
bool any_exists(const std::string& file, void*) {
  return tinygltf::FileExists(file, nullptr);  // jailed_read refuses, saying why
}
bool jailed_read(std::vector<unsigned char>* out, std::string* err, const std::string& file, void* jail) {
  if (!static_cast<FolderJail*>(jail)->inside(file)) {
    if (err) *err += "'" + file + "' is outside the glTF's folder; only files beside it may be read";
    return false;
  }
  return tinygltf::ReadWholeFile(out, err, file, nullptr);
}
bool no_writes(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "writing is not allowed while reading";
  return false;
}
// Images are never decoded: splats do not use them, and a crafted header could ask for gigabytes.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

Eigen::Matrix4d node_local_matrix(const tinygltf::Node& node) {
  if (node.matrix.size() == 16) return Eigen::Map<const Eigen::Matrix4d>(node.matrix.data());
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  if (node.translation.size() == 3) t.translate(Eigen::Vector3d(node.translation[0], node.translation[1], node.translation[2]));
  if (node.rotation.size() == 4) t.rotate(Eigen::Quaterniond(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]));
  if (node.scale.size() == 3) t.scale(Eigen::Vector3d(node.scale[0], node.scale[1], node.scale[2]));
  return t.matrix();
}

std::string string_or(const tinygltf::Value& obj, const char* key, const std::string& fallback) {
  if (!obj.IsObject() || !obj.Has(key) || !obj.Get(key).IsString()) return fallback;
  return obj.Get(key).Get<std::string>();
}

// Whether write_gltf marked this node's transform as its axis rotation (gslam's world to glTF).
bool gslam_axis_node(const tinygltf::Node& node) {
  return node.extras.IsObject() && node.extras.Has(kGslamExtras) &&
         string_or(node.extras.Get(kGslamExtras), kNodeRotation, "") == kWorldToGltf;
}

GltfSplatPrimitive decode_primitive(const tinygltf::Model& model, const tinygltf::Primitive& prim,
                                    const Eigen::Matrix4d& world, const std::string& name,
                                    const std::filesystem::path& path,
                                    std::vector<std::string>& notices) {
  GltfSplatPrimitive out;
  out.name = name;
  const std::string where = "splat primitive '" + name + "'";
  auto attribute = [&](const std::string& key) -> int {
    const auto it = prim.attributes.find(key);
    return it == prim.attributes.end() ? -1 : it->second;
  };
  auto required = [&](const std::string& key) {
    const int index = attribute(key);
    if (index < 0) fail(path, where + " has no " + key + " attribute");
    return index;
  };
  if (prim.mode != TINYGLTF_MODE_POINTS) fail(path, where + " has mode " + std::to_string(prim.mode) + ", expected 0 (POINTS)");
  out.positions = read_accessor(model, required("POSITION"), 3, where + " POSITION", path);
  const std::size_t n = out.positions.size() / 3;
  out.rotations_xyzw = read_accessor(model, required(std::string(kPrefix) + "ROTATION"), 4, where + " ROTATION", path, n);
  out.log_scales = read_accessor(model, required(std::string(kPrefix) + "SCALE"), 3, where + " SCALE", path, n);
  out.opacities = read_accessor(model, required(std::string(kPrefix) + "OPACITY"), 1, where + " OPACITY", path, n);

  // SH degree: the highest degree whose coefficients are all present; partial degrees fail.
  std::vector<std::vector<float>> coeffs;
  for (int degree = 0; degree <= splat::kMaxShDegree; ++degree) {
    const int first = degree * degree, count = 2 * degree + 1;
    int present = 0;
    for (int c = 0; c < count; ++c) {
      present += attribute(std::string(kPrefix) + "SH_DEGREE_" + std::to_string(degree) + "_COEF_" + std::to_string(c)) >= 0;
    }
    if (present == 0) break;
    if (present != count) fail(path, where + " defines " + std::to_string(present) + " of the " + std::to_string(count) + " SH degree " + std::to_string(degree) + " coefficients");
    for (int c = 0; c < count; ++c) {
      const std::string key = std::string(kPrefix) + "SH_DEGREE_" + std::to_string(degree) + "_COEF_" + std::to_string(c);
      coeffs.push_back(read_accessor(model, required(key), 3, where + " " + key, path, n));
    }
    out.sh_degree = degree;
    (void)first;
  }
  if (coeffs.empty()) {
    const int color = attribute("COLOR_0");
    if (color < 0) fail(path, where + " has neither SH_DEGREE_0_COEF_0 nor COLOR_0");
    const auto& accessor = element(model.accessors, color, where + " COLOR_0: accessor", path);
    const int components = accessor.type == TINYGLTF_TYPE_VEC3 ? 3 : 4;
    const std::vector<float> rgba = read_accessor(model, color, components, where + " COLOR_0", path, n);
    std::vector<float> dc(n * 3);
    // COLOR_0 holds the diffuse colour SH_0 * C0 + 0.5 (linear or display: read_gltf_splats
    // decides for the whole file and inverts it).
    for (std::size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) dc[i * 3 + c] = rgba[i * components + c];
    coeffs.push_back(dc);
    out.sh_from_color0 = true;
    notices.push_back(where + ": no SH_DEGREE_0_COEF_0, diffuse colour taken from COLOR_0");
  }
  const std::size_t k = coeffs.size();
  out.sh.resize(n * k * 3);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t c = 0; c < k; ++c)
      for (int ch = 0; ch < 3; ++ch) out.sh[(i * k + c) * 3 + ch] = coeffs[c][i * 3 + ch];

  // Classes per Gaussian: _LABEL_0.. with _LABEL_PROBABILITY_0.., in pairs.
  int top = 0;
  while (top < kMaxLabels && attribute(kLabel + std::to_string(top)) >= 0) ++top;
  if (top > 0) {
    out.labels.top = top;
    out.labels.ids.resize(n * std::size_t(top));
    out.labels.probabilities.resize(n * std::size_t(top));
    for (int t = 0; t < top; ++t) {
      const std::string id_key = kLabel + std::to_string(t), p_key = kLabelProbability + std::to_string(t);
      if (attribute(p_key) < 0) fail(path, where + " has " + id_key + " but no " + p_key);
      const std::vector<float> ids = read_accessor(model, required(id_key), 1, where + " " + id_key, path, n);
      const std::vector<float> ps = read_accessor(model, required(p_key), 1, where + " " + p_key, path, n);
      for (std::size_t i = 0; i < n; ++i) {
        if (!(ids[i] >= 0 && ids[i] <= 65535 && ids[i] == std::floor(ids[i])) || !(ps[i] >= 0 && ps[i] <= 1)) {
          fail(path, where + " Gaussian " + std::to_string(i) + ": " + id_key + " " + std::to_string(ids[i]) + ", " +
                         p_key + " " + std::to_string(ps[i]) + " (expected a class id 0..65535 and a probability)");
        }
        out.labels.ids[i * std::size_t(top) + std::size_t(t)] = static_cast<uint16_t>(ids[i]);
        out.labels.probabilities[i * std::size_t(top) + std::size_t(t)] = ps[i];
      }
    }
  }

  const auto ext_it = prim.extensions.find(kExtension);
  const tinygltf::Value ext = ext_it == prim.extensions.end() ? tinygltf::Value() : ext_it->second;
  out.kernel = string_or(ext, "kernel", "ellipse");
  out.color_space = string_or(ext, "colorSpace", "srgb_rec709_display");
  if (out.kernel != "ellipse") notices.push_back(where + ": unknown kernel '" + out.kernel + "', rendered as 'ellipse'");
  if (out.color_space != "srgb_rec709_display" && out.color_space != "lin_rec709_display") {
    notices.push_back(where + ": unknown colorSpace '" + out.color_space + "', treated as srgb_rec709_display");
  }

  // Node transform: rotation and uniform scale are folded into the splats.
  if (!world.isIdentity(1e-12)) {
    const Eigen::Matrix3d linear = world.topLeftCorner<3, 3>();
    const double scale = std::cbrt(linear.determinant());
    const Eigen::Matrix3d rotation = linear / scale;
    if (!(scale > 0) || (rotation * rotation.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-5) {
      fail(path, where + ": node transform is not a rotation with uniform scale");
    }
    const Eigen::Quaterniond node_q(rotation);
    for (std::size_t i = 0; i < n; ++i) {
      Eigen::Vector4d p(out.positions[i * 3], out.positions[i * 3 + 1], out.positions[i * 3 + 2], 1);
      const Eigen::Vector4d q_world = world * p;
      for (int a = 0; a < 3; ++a) out.positions[i * 3 + a] = static_cast<float>(q_world[a]);
      const float* r = &out.rotations_xyzw[i * 4];
      const Eigen::Quaterniond q = node_q * Eigen::Quaterniond(r[3], r[0], r[1], r[2]);
      out.rotations_xyzw[i * 4] = static_cast<float>(q.x());
      out.rotations_xyzw[i * 4 + 1] = static_cast<float>(q.y());
      out.rotations_xyzw[i * 4 + 2] = static_cast<float>(q.z());
      out.rotations_xyzw[i * 4 + 3] = static_cast<float>(q.w());
    }
    out.node_scale = scale;
  }
  return out;
}

// Walks each node once: glTF nodes form disjoint trees, so a node reached twice (a cycle, or a
// graph sharing children, which would be walked exponentially often) is an error.
void visit_nodes(const tinygltf::Model& model, int index, const Eigen::Matrix4d& parent,
                 const std::filesystem::path& path, GltfSplatScene& scene, std::vector<uint8_t>& visited, int depth) {
  const tinygltf::Node& node = element(model.nodes, index, "node", path);
  if (visited[static_cast<std::size_t>(index)]) {
    fail(path, "node " + std::to_string(index) + " is reached twice; glTF nodes must form trees");
  }
  visited[static_cast<std::size_t>(index)] = 1;
  if (depth > 64) fail(path, "node hierarchy deeper than 64");
  // gslam's axis rotation is left out, so its maps read back in the frame they were made in.
  const Eigen::Matrix4d world = gslam_axis_node(node) ? parent : Eigen::Matrix4d(parent * node_local_matrix(node));
  if (node.mesh >= 0) {
    const tinygltf::Mesh& mesh = element(model.meshes, node.mesh, "node " + std::to_string(index) + ": mesh", path);
    for (const auto& prim : mesh.primitives) {
      const bool splat = prim.extensions.count(kExtension) > 0 ||
                         prim.attributes.count(std::string(kPrefix) + "ROTATION") > 0;
      if (!splat) continue;
      const std::string name = !node.name.empty() ? node.name : mesh.name;
      scene.primitives.push_back(decode_primitive(model, prim, world, name, path, scene.notices));
    }
  }
  for (int child : node.children) visit_nodes(model, child, world, path, scene, visited, depth + 1);
}

}  // namespace

GltfSplatScene read_gltf_splats(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) fail(path, "cannot open file");
  tinygltf::TinyGLTF loader;
  FolderJail jail{std::filesystem::weakly_canonical(std::filesystem::absolute(path).parent_path())};
  loader.SetFsCallbacks({&any_exists, &tinygltf::ExpandFilePath, &jailed_read, &no_writes, &jail});
  loader.SetImageLoader(&skip_image, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  const bool binary = path.extension() == ".glb";
  const bool ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, path.string())
                         : loader.LoadASCIIFromFile(&model, &err, &warn, path.string());
  if (!ok) {
    std::string msg = err.empty() ? "malformed glTF" : err;
    std::replace(msg.begin(), msg.end(), '\n', ' ');
    fail(path, msg);
  }
  GltfSplatScene scene;
  std::vector<int> roots;
  if (!model.scenes.empty()) {
    roots = element(model.scenes, model.defaultScene >= 0 ? model.defaultScene : 0, "scene", path).nodes;
  } else {
    // No scene: every node that is no other node's child is a root.
    std::vector<uint8_t> child(model.nodes.size(), 0);
    for (const tinygltf::Node& node : model.nodes) {
      for (int c : node.children) {
        if (c >= 0 && static_cast<std::size_t>(c) < child.size()) child[static_cast<std::size_t>(c)] = 1;
      }
    }
    for (int i = 0; i < static_cast<int>(model.nodes.size()); ++i) {
      if (!child[static_cast<std::size_t>(i)]) roots.push_back(i);
    }
  }
  std::vector<uint8_t> visited(model.nodes.size(), 0);
  for (int root : roots) visit_nodes(model, root, Eigen::Matrix4d::Identity(), path, scene, visited, 0);
  if (scene.primitives.empty()) fail(path, "has no KHR_gaussian_splatting primitive");
  // SCALE and COLOR_0 were read as stored; the file's draft decides what they mean.
  for (const GltfSplatPrimitive& p : scene.primitives) {
    scene.older_draft = scene.older_draft || std::any_of(p.log_scales.begin(), p.log_scales.end(), [](float v) { return v < 0; });
  }
  if (scene.older_draft) {
    scene.notices.push_back("negative SCALE values: read as log-scales (and COLOR_0 as display values), as drafts "
                            "of KHR_gaussian_splatting before April 2026 wrote them");
  }
  constexpr float kMinScale = 1e-12f;  // a linear 0 (allowed) as a finite log
  for (GltfSplatPrimitive& p : scene.primitives) {
    const float log_node_scale = static_cast<float>(std::log(p.node_scale));
    for (float& v : p.log_scales) v = (scene.older_draft ? v : std::log(std::max(v, kMinScale))) + log_node_scale;
    if (!p.sh_from_color0) continue;
    for (std::size_t i = 0; i < p.sh.size(); i += 3) {  // DC alone
      for (int c = 0; c < 3; ++c) {
        const float display = scene.older_draft ? p.sh[i + c] : linear_to_srgb(std::clamp(p.sh[i + c], 0.f, 1.f));
        p.sh[i + c] = static_cast<float>((display - 0.5) / kShC0);
      }
    }
  }
  return scene;
}

splat::Gaussians to_gaussians(const GltfSplatScene& scene) {
  splat::Gaussians g;
  std::size_t total = 0;
  for (const auto& p : scene.primitives) {
    g.sh_degree = std::max(g.sh_degree, p.sh_degree);
    total += p.opacities.size();
  }
  g.resize(total);
  const std::size_t k = static_cast<std::size_t>(splat::sh_coeff_count(g.sh_degree));
  std::size_t o = 0;
  for (const auto& p : scene.primitives) {
    const std::size_t pk = static_cast<std::size_t>(splat::sh_coeff_count(p.sh_degree));
    for (std::size_t i = 0; i < p.opacities.size(); ++i, ++o) {
      for (int a = 0; a < 3; ++a) {
        g.means[o * 3 + a] = p.positions[i * 3 + a];
        g.log_scales[o * 3 + a] = p.log_scales[i * 3 + a];
      }
      const float* r = &p.rotations_xyzw[i * 4];
      g.rotations[o * 4] = r[3];
      g.rotations[o * 4 + 1] = r[0];
      g.rotations[o * 4 + 2] = r[1];
      g.rotations[o * 4 + 3] = r[2];
      const double opacity = std::clamp(static_cast<double>(p.opacities[i]), 1e-6, 1 - 1e-6);
      g.opacity_logits[o] = static_cast<float>(std::log(opacity / (1 - opacity)));
      for (std::size_t c = 0; c < pk * 3; ++c) g.sh[o * k * 3 + c] = p.sh[i * pk * 3 + c];
    }
  }
  return g;
}

splat::GaussianLabels to_labels(const GltfSplatScene& scene) {
  splat::GaussianLabels out;
  if (scene.primitives.empty()) return out;
  out.top = scene.primitives.front().labels.top;
  for (const auto& p : scene.primitives) {
    if (p.labels.top != out.top) return {};  // some primitives unlabelled, or labelled otherwise
    out.ids.insert(out.ids.end(), p.labels.ids.begin(), p.labels.ids.end());
    out.probabilities.insert(out.probabilities.end(), p.labels.probabilities.begin(), p.labels.probabilities.end());
  }
  return out;
}

namespace {

// Appends raw floats as a buffer view plus an accessor; returns the accessor index.
int add_float_accessor(tinygltf::Model& model, const std::vector<float>& data, int type, std::size_t count,
                       bool with_bounds) {
  tinygltf::Buffer& buffer = model.buffers[0];
  const std::size_t offset = buffer.data.size();
  buffer.data.resize(offset + data.size() * sizeof(float));
  std::memcpy(buffer.data.data() + offset, data.data(), data.size() * sizeof(float));
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = offset;
  view.byteLength = data.size() * sizeof(float);
  view.target = TINYGLTF_TARGET_ARRAY_BUFFER;
  model.bufferViews.push_back(view);
  tinygltf::Accessor accessor;
  accessor.bufferView = static_cast<int>(model.bufferViews.size() - 1);
  accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  accessor.count = count;
  accessor.type = type;
  if (with_bounds && count > 0) {  // glTF requires min/max on POSITION
    const int comps = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(type));
    accessor.minValues.assign(static_cast<std::size_t>(comps), INFINITY);
    accessor.maxValues.assign(static_cast<std::size_t>(comps), -INFINITY);
    for (std::size_t i = 0; i < count; ++i)
      for (int c = 0; c < comps; ++c) {
        const double v = data[i * static_cast<std::size_t>(comps) + static_cast<std::size_t>(c)];
        accessor.minValues[static_cast<std::size_t>(c)] = std::min(accessor.minValues[static_cast<std::size_t>(c)], v);
        accessor.maxValues[static_cast<std::size_t>(c)] = std::max(accessor.maxValues[static_cast<std::size_t>(c)], v);
      }
  }
  model.accessors.push_back(accessor);
  return static_cast<int>(model.accessors.size() - 1);
}

}  // namespace

Eigen::Quaterniond gltf_rotation_for_up(const Eigen::Vector3d& world_up) {
  if (!world_up.allFinite() || !(world_up.norm() > 0)) {
    throw splat::Error("gltf_rotation_for_up: the up vector is zero or not finite");
  }
  // glTF's axes in the world frame: Y = up, -Z = the world's +z levelled (or, where +z is
  // near vertical, its -y: the top of the first image), X = Y x Z.
  const Eigen::Vector3d y = world_up.normalized();
  Eigen::Vector3d forward = Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitZ().dot(y) * y;
  if (forward.norm() < 0.1) forward = -Eigen::Vector3d::UnitY() + Eigen::Vector3d::UnitY().dot(y) * y;
  const Eigen::Vector3d z = -forward.normalized();
  Eigen::Matrix3d world_from_gltf;
  world_from_gltf << y.cross(z), y, z;
  return Eigen::Quaterniond(world_from_gltf.transpose()).normalized();
}

void write_gltf(const std::filesystem::path& path, const splat::Gaussians& g, const Eigen::Quaterniond& gltf_from_world,
                const splat::GaussianLabels* labels) {
  splat::validate(splat::GaussiansView(g), "write_gltf " + path.string());
  if (labels && !labels->empty() && labels->size() != g.size()) {
    throw splat::Error("write_gltf " + path.string() + ": labels for " + std::to_string(labels->size()) +
                       " Gaussians, the map has " + std::to_string(g.size()));
  }
  if (!gltf_from_world.coeffs().allFinite() || std::abs(gltf_from_world.norm() - 1) > 1e-6) {
    throw splat::Error("write_gltf " + path.string() + ": the node rotation is not a unit quaternion");
  }
  const std::size_t n = g.size();
  const std::size_t k = static_cast<std::size_t>(splat::sh_coeff_count(g.sh_degree));
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "gslam";
  model.extensionsUsed = {kExtension};
  model.buffers.resize(1);

  std::vector<float> rotations(n * 4), opacities(n), colors(n * 4), scales(n * 3);
  for (std::size_t i = 0; i < n * 3; ++i) scales[i] = std::exp(g.log_scales[i]);
  for (std::size_t i = 0; i < n; ++i) {
    const float* q = &g.rotations[i * 4];
    double norm = std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3]);
    if (norm == 0) norm = 1;  // a zero quaternion stays zero (the renderer culls it)
    rotations[i * 4] = static_cast<float>(q[1] / norm);
    rotations[i * 4 + 1] = static_cast<float>(q[2] / norm);
    rotations[i * 4 + 2] = static_cast<float>(q[3] / norm);
    rotations[i * 4 + 3] = static_cast<float>(q[0] / norm);
    const double opacity = 1 / (1 + std::exp(-static_cast<double>(g.opacity_logits[i])));
    opacities[i] = static_cast<float>(opacity);
    for (int c = 0; c < 3; ++c) {
      const double display = std::clamp(g.sh[i * k * 3 + c] * kShC0 + 0.5, 0.0, 1.0);
      colors[i * 4 + c] = srgb_to_linear(static_cast<float>(display));
    }
    colors[i * 4 + 3] = opacities[i];
  }
  tinygltf::Primitive prim;
  prim.mode = TINYGLTF_MODE_POINTS;
  prim.attributes["POSITION"] = add_float_accessor(model, g.means, TINYGLTF_TYPE_VEC3, n, true);
  prim.attributes[std::string(kPrefix) + "ROTATION"] = add_float_accessor(model, rotations, TINYGLTF_TYPE_VEC4, n, false);
  prim.attributes[std::string(kPrefix) + "SCALE"] = add_float_accessor(model, scales, TINYGLTF_TYPE_VEC3, n, false);
  prim.attributes[std::string(kPrefix) + "OPACITY"] = add_float_accessor(model, opacities, TINYGLTF_TYPE_SCALAR, n, false);
  prim.attributes["COLOR_0"] = add_float_accessor(model, colors, TINYGLTF_TYPE_VEC4, n, false);
  for (int degree = 0; degree <= g.sh_degree; ++degree) {
    for (int c = 0; c < 2 * degree + 1; ++c) {
      const std::size_t coeff = static_cast<std::size_t>(degree * degree + c);
      std::vector<float> values(n * 3);
      for (std::size_t i = 0; i < n; ++i)
        for (int ch = 0; ch < 3; ++ch) values[i * 3 + ch] = g.sh[(i * k + coeff) * 3 + ch];
      prim.attributes[std::string(kPrefix) + "SH_DEGREE_" + std::to_string(degree) + "_COEF_" + std::to_string(c)] =
          add_float_accessor(model, values, TINYGLTF_TYPE_VEC3, n, false);
    }
  }
  if (labels && !labels->empty()) {
    const std::size_t top = static_cast<std::size_t>(labels->top);
    for (std::size_t t = 0; t < top; ++t) {
      std::vector<float> ids(n), probabilities(n);
      for (std::size_t i = 0; i < n; ++i) {
        ids[i] = labels->ids[i * top + t];
        probabilities[i] = labels->probabilities[i * top + t];
      }
      prim.attributes[kLabel + std::to_string(t)] = add_float_accessor(model, ids, TINYGLTF_TYPE_SCALAR, n, false);
      prim.attributes[kLabelProbability + std::to_string(t)] =
          add_float_accessor(model, probabilities, TINYGLTF_TYPE_SCALAR, n, false);
    }
  }
  tinygltf::Value::Object ext;
  ext["kernel"] = tinygltf::Value(std::string("ellipse"));
  ext["colorSpace"] = tinygltf::Value(std::string("srgb_rec709_display"));
  ext["projection"] = tinygltf::Value(std::string("perspective"));
  ext["sortingMethod"] = tinygltf::Value(std::string("cameraDistance"));
  prim.extensions[kExtension] = tinygltf::Value(ext);
  tinygltf::Mesh mesh;
  mesh.name = "gaussians";
  mesh.primitives.push_back(prim);
  model.meshes.push_back(mesh);
  tinygltf::Node node;
  node.mesh = 0;
  node.name = "gaussians";
  if (!gltf_from_world.isApprox(Eigen::Quaterniond::Identity(), 1e-12)) {
    node.rotation = {gltf_from_world.x(), gltf_from_world.y(), gltf_from_world.z(), gltf_from_world.w()};
    tinygltf::Value::Object mark;
    mark[kNodeRotation] = tinygltf::Value(std::string(kWorldToGltf));
    tinygltf::Value::Object extras;
    extras[kGslamExtras] = tinygltf::Value(mark);
    node.extras = tinygltf::Value(extras);
  }
  model.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes = {0};
  model.scenes.push_back(scene);
  model.defaultScene = 0;

  const bool binary = path.extension() != ".gltf";
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToFile(&model, tmp.string(), /*embedImages=*/true,
                                     /*embedBuffers=*/true, /*prettyPrint=*/!binary, binary)) {
      fail(tmp, "cannot write glTF");
    }
  });
}

}  // namespace app
