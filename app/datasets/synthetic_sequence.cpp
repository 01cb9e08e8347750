#include "datasets/synthetic_sequence.h"

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "io/atomic_file.h"
#include "io/image_io.h"
#include "io/trajectory.h"
#include "splat/error.h"
#include "splat/thread_pool.h"

namespace app {
namespace {

using Eigen::Vector3d;

// Class ids of the label images (labels/classes.json names them).
enum Label : uint16_t { kWall = 1, kFloor, kCeiling, kBall, kCabinet, kPerson, kChair, kCrate };

struct Hit {
  double t = std::numeric_limits<double>::infinity();
  Vector3d point, normal, color;
  uint16_t label = 0;
  bool moving = false;  // on an object that moves during the sequence
};

double checker(double a, double b, double size) {
  return (static_cast<long>(std::floor(a / size)) + static_cast<long>(std::floor(b / size))) % 2 == 0 ? 1.0 : 0.0;
}

// The room: the inside of a 5 x 3 x 5 m box (y down, floor at y = 1.5), textured walls, two
// spheres and two boxes. With `twin`, a second identical room continues it along x (10 m long,
// the same objects and textures 5 m on): two places that look alike and are not the same.
class Scene {
 public:
  explicit Scene(bool twin) : copies_(twin ? 2 : 1) {}
  void intersect(const Vector3d& o, const Vector3d& d, Hit& hit) const {
    room(o, d, hit, copies_);
    for (int copy = 0; copy < copies_; ++copy) {
      const Vector3d shift(kRoomLength * copy, 0, 0);
      sphere(o, d, Vector3d(-0.6, 0.9, 0.4) + shift, 0.6, hit, 0);
      sphere(o, d, Vector3d(0.9, 1.15, -0.5) + shift, 0.35, hit, 1);
      box(o, d, Vector3d(0.2, 0.7, 1.1) + shift, Vector3d(0.9, 1.5, 1.6) + shift, hit, kCabinet);
      box(o, d, Vector3d(-1.8, 0.3, -1.6) + shift, Vector3d(-1.1, 1.5, -0.9) + shift, hit, kCabinet);
    }
  }

 private:
  static constexpr double kRoomLength = 5.0;
  int copies_;

  static void room(const Vector3d& o, const Vector3d& d, Hit& hit, int copies) {
    const Vector3d lo(-2.5, -1.5, -2.5), hi(2.5 + kRoomLength * (copies - 1), 1.5, 2.5);
    for (int axis = 0; axis < 3; ++axis) {
      for (int side = 0; side < 2; ++side) {
        if (std::abs(d[axis]) < 1e-12) continue;
        const double plane = side ? hi[axis] : lo[axis];
        const double t = (plane - o[axis]) / d[axis];
        if (t <= 1e-6 || t >= hit.t) continue;
        const Vector3d hit_point = o + t * d;
        const int a = (axis + 1) % 3, b = (axis + 2) % 3;
        if (hit_point[a] < lo[a] || hit_point[a] > hi[a] || hit_point[b] < lo[b] || hit_point[b] > hi[b]) continue;
        hit.t = t;
        hit.point = hit_point;
        // Textured as in the first room: x folded back into it.
        Vector3d p = hit_point;
        p.x() = std::fmod(p.x() + 2.5, kRoomLength) - 2.5;
        hit.normal = Vector3d::Zero();
        hit.normal[axis] = side ? -1 : 1;
        hit.label = axis != 1 ? kWall : side ? kFloor : kCeiling;  // y down: the floor at +1.5
        hit.moving = false;
        // Each wall its own colours, tiled in 0.4 m squares with a fine stripe texture.
        const double c = checker(p[a], p[b], 0.4);
        const double stripe = 0.5 + 0.5 * std::sin(p[a] * 25.0) * std::sin(p[b] * 17.0);
        const Vector3d base[6] = {{0.8, 0.3, 0.2}, {0.2, 0.6, 0.8}, {0.9, 0.85, 0.6},
                                  {0.35, 0.35, 0.4}, {0.3, 0.7, 0.3}, {0.7, 0.5, 0.8}};
        hit.color = base[axis * 2 + side] * (0.55 + 0.35 * c) + Vector3d::Constant(0.1 * stripe);
      }
    }
  }

  // style 0 and 1: the two balls' colours; 2: skin (a head).
 public:
  static void sphere(const Vector3d& o, const Vector3d& d, const Vector3d& c, double r, Hit& hit, int style) {
    const Vector3d oc = o - c;
    const double b = oc.dot(d), disc = b * b - (oc.squaredNorm() - r * r);
    if (disc < 0) return;
    const double t = -b - std::sqrt(disc);
    if (t <= 1e-6 || t >= hit.t) return;
    hit.t = t;
    hit.point = o + t * d;
    hit.normal = (hit.point - c) / r;
    const double u = std::atan2(hit.normal.z(), hit.normal.x()), v = std::acos(std::clamp(hit.normal.y(), -1.0, 1.0));
    const double bands = checker(u * 4 / M_PI, v * 6 / M_PI, 1.0);
    hit.color = style == 0 ? Vector3d(0.9, 0.75 * bands + 0.1, 0.1)
                : style == 1 ? Vector3d(0.1, 0.4 + 0.4 * bands, 0.9)
                             : Vector3d(0.85, 0.65, 0.5) * (0.9 + 0.1 * bands);
    hit.label = style == 2 ? kPerson : kBall;
    hit.moving = style == 2;
  }

  // Returns whether it hit (nearer than before); colours it as the static boxes are.
  static bool box(const Vector3d& o, const Vector3d& d, const Vector3d& lo, const Vector3d& hi, Hit& hit,
                  uint16_t label) {
    double t0 = 1e-6, t1 = hit.t;
    int axis_hit = -1;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(d[a]) < 1e-12) {
        if (o[a] < lo[a] || o[a] > hi[a]) return false;
        continue;
      }
      double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
      if (ta > tb) std::swap(ta, tb);
      if (ta > t0) t0 = ta, axis_hit = a;
      t1 = std::min(t1, tb);
      if (t0 > t1) return false;
    }
    if (axis_hit < 0 || t0 >= hit.t) return false;
    hit.t = t0;
    hit.point = o + t0 * d;
    hit.normal = Vector3d::Zero();
    hit.normal[axis_hit] = d[axis_hit] > 0 ? -1 : 1;
    const int a = (axis_hit + 1) % 3, b = (axis_hit + 2) % 3;
    const double c = checker(hit.point[a], hit.point[b], 0.1);
    hit.color = Vector3d(0.25 + 0.6 * c, 0.2 + 0.3 * (axis_hit == 1), 0.6 - 0.4 * c);
    hit.label = label;
    hit.moving = label == kPerson || label == kChair || label == kCrate;
    return true;
  }
};

// What moves through the room with SyntheticOptions::movers, at `seconds` into the sequence: a
// person (1.78 m, 0.44 m wide) walking in at 1.3 m/s between the camera and the objects, standing
// a while and walking out again; a chair pushed a metre along the floor and left there; and a
// crate that appears on the floor. Positions for the arc path (the default), which looks across
// them; swept_by_movers() says where they have been.
class Movers {
 public:
  // The person: walks in along z = -0.5 from x = -2.2 at 0.3 s to x = 0.25 (short of the blue
  // ball), stands until 2.8 s, walks back out (gone at 4.7 s). Walked distance for the stride.
  static constexpr double kPersonZ = -0.5, kFrom = -2.2, kStop = 0.25, kSpeed = 1.3;
  static constexpr double kEnter = 0.3, kTurn = 2.8;
  static bool person_at(double seconds, double& x, double& walked) {
    const double in = (seconds - kEnter) * kSpeed, out = (seconds - kTurn) * kSpeed;
    if (in <= 0 || out >= kStop - kFrom) return false;
    walked = std::min(in, kStop - kFrom) + std::max(out, 0.0);
    x = out > 0 ? kStop - out : std::min(kFrom + in, kStop);
    return true;
  }
  // A person (1.78 m, 0.44 m wide) standing at (x, z) on the floor, `walked` metres into their
  // walk (the stride's bob), in a shirt of this colour and dark trousers. The shirt is striped
  // across, or `patterned` in squares that move with them.
  static void person(const Vector3d& o, const Vector3d& d, double x, double z, double walked,
                     const Vector3d& shirt, Hit& hit, bool patterned = false) {
    const double bob = 0.025 * std::abs(std::sin(walked * M_PI / 0.7));
    const Vector3d lo(x - 0.22, -0.05 + bob, z - 0.13), hi(x + 0.22, 1.5, z + 0.13);
    if (Scene::box(o, d, lo, hi, hit, kPerson)) {
      const double local_y = hit.point.y() - bob;
      // Along the shirt's front and round its sides, from the person's own left.
      const double across = patterned ? hit.point.x() - x + hit.point.z() - z + 1 : 0;
      hit.color = local_y < 0.75 ? shirt * (patterned ? 0.6 + 0.4 * checker(local_y, across, 0.08)
                                                      : 0.75 + 0.25 * checker(local_y, 0, 0.08))
                                 : Vector3d(0.12, 0.14, 0.3);
    }
    Scene::sphere(o, d, Vector3d(x, -0.17 + bob, z), 0.11, hit, 2);
  }
  static void intersect(const Vector3d& o, const Vector3d& d, double seconds, Hit& hit) {
    double x = 0, walked = 0;
    if (person_at(seconds, x, walked))
      person(o, d, x, kPersonZ, walked, Vector3d(0.75, 0.2, 0.25), hit);
    // The chair: pushed from x = 1.7 to 0.7 between 1.5 and 2.5 s.
    const double push = std::clamp(seconds - 1.5, 0.0, 1.0);
    const double chair_x = 1.7 - push;
    if (Scene::box(o, d, Vector3d(chair_x - 0.22, 0.6, 0.08), Vector3d(chair_x + 0.22, 1.5, 0.52), hit, kChair)) {
      hit.color = Vector3d(0.55, 0.35, 0.15) * (0.7 + 0.3 * checker(hit.point.x() + hit.point.z(), hit.point.y(), 0.15));
    }
    // The crate: there from 2.8 s on.
    if (seconds >= 2.8) Scene::box(o, d, Vector3d(-0.1, 1.2, -0.3), Vector3d(0.3, 1.5, 0.1), hit, kCrate);
  }
};

// SyntheticOptions::walkers: two people pacing to and fro across the arc's view for the whole
// sequence, as in TUM's fr3/walking sequences: one at 1.3 m/s where the movers' person walks, one
// at 1.1 m/s in the other direction about 0.6 m from the camera, where they fill up to two thirds
// of the image. Their torsos are flat and evenly striped along their walk, so most of each one's
// pixels look the same from frame to frame: only their outlines give their motion away (unless
// SyntheticOptions::patterned_walkers dresses them in patterns that move with them).
struct Walkers {
  // Pacing over `span` metres from x = `from` at `speed`, starting `start` metres into the walk.
  static double pacing(double seconds, double from, double span, double speed, double start) {
    const double d = std::fmod(seconds * speed + start, 2 * span);
    return from + (d < span ? d : 2 * span - d);
  }
  static void intersect(const Vector3d& o, const Vector3d& d, double seconds, bool patterned, Hit& hit) {
    Movers::person(o, d, pacing(seconds, -1.2, 2.2, 1.3, 0), Movers::kPersonZ, 1.3 * seconds,
                   Vector3d(0.75, 0.2, 0.25), hit, patterned);
    Movers::person(o, d, -pacing(seconds, -1.0, 2.2, 1.1, 1.2), -0.9, 1.1 * seconds,
                   Vector3d(0.2, 0.6, 0.3), hit, patterned);
  }
};

void trace(const Scene& scene, const SyntheticOptions& o, const Vector3d& origin, const Vector3d& direction,
           double seconds, Hit& hit) {
  scene.intersect(origin, direction, hit);
  if (o.movers) Movers::intersect(origin, direction, seconds, hit);
  if (o.walkers) Walkers::intersect(origin, direction, seconds, o.patterned_walkers, hit);
}

// Camera to world at `eye` looking at `target`, image rows level (world y is down).
Eigen::Isometry3d look_from(const Vector3d& eye, const Vector3d& target) {
  const Vector3d z = (target - eye).normalized();
  const Vector3d x = Vector3d(0, 1, 0).cross(z).normalized();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() << x, z.cross(x), z;
  pose.translation() = eye;
  return pose;
}

// Camera to world at time s in [0, 1]: a smooth arc through the room, looking at its middle.
Eigen::Isometry3d arc_pose(double s) {
  const double angle = -0.6 + 1.0 * s;
  const Vector3d eye(1.6 * std::sin(angle), 0.1 * std::sin(3 * s), -1.9 * std::cos(angle) + 0.3 * s);
  const Vector3d target(0.1 * std::sin(2 * s), 0.8, 0.3);
  return look_from(eye, target);
}

// `laps` turns of a 1.7 m circle about the room's middle at s in [0, 1], looking across the
// room past its middle (the objects, then the far wall), bobbing so that the laps differ a little.
Eigen::Isometry3d lap_pose(double s, int laps) {
  const double angle = 2 * M_PI * laps * s;
  const Vector3d eye(1.7 * std::sin(angle), -0.2 + 0.1 * std::sin(5 * angle), -1.7 * std::cos(angle));
  const Vector3d target(0.4 * std::cos(angle), 0.9, 0.4 * std::sin(angle));
  return look_from(eye, target);
}

// The path at `seconds` into the sequence, with the optional yaw shake about the camera's y axis.
// Along the twin rooms at s in [0, 1]: from x = -1.5 to 6.5 (into the second room), 1.2 m from
// the +z wall, looking across at the -z wall past the objects.
Eigen::Isometry3d corridor_pose(double s) {
  const Vector3d eye(-1.5 + 8.0 * s, -0.3, 1.3);
  const Vector3d target(eye.x() + 0.3, 0.8, -1.0);
  return look_from(eye, target);
}

Eigen::Isometry3d camera_pose(const SyntheticOptions& o, double seconds) {
  const double duration = (std::max(o.frames, o.path_frames) - 1) / o.fps;
  if (o.kidnap_frame > 0 && seconds >= o.kidnap_frame / o.fps - 1e-9) seconds -= (o.kidnap_frame - o.kidnap_to) / o.fps;
  const double s = duration > 0 ? std::clamp(seconds / duration, 0.0, 1.0) : 0.0;
  const Eigen::Isometry3d arc = o.twin_rooms ? corridor_pose(s) : o.laps > 0 ? lap_pose(s, o.laps) : arc_pose(s);
  if (o.shake_peak_rate <= 0) return arc;
  constexpr double kShakeHz = 1.5;
  const double yaw = o.shake_peak_rate / (2 * M_PI * kShakeHz) * std::sin(2 * M_PI * kShakeHz * seconds);
  return arc * Eigen::AngleAxisd(yaw, Vector3d::UnitY());
}

// Blobs of missing depth covering about `fraction` of the image: discs at random centres.
std::vector<uint8_t> hole_mask(int w, int h, double fraction, std::mt19937& rng) {
  std::vector<uint8_t> hole(static_cast<std::size_t>(w) * h, 0);
  if (fraction <= 0) return hole;
  const double radius = 0.03 * w;
  const int blobs = static_cast<int>(std::ceil(fraction * w * h / (M_PI * radius * radius)));
  std::uniform_real_distribution<double> ux(0, w), uy(0, h), ur(0.5 * radius, 1.5 * radius);
  for (int b = 0; b < blobs; ++b) {
    const double cx = ux(rng), cy = uy(rng), r = ur(rng);
    for (int y = std::max(0, int(cy - r)); y < std::min(h, int(cy + r) + 1); ++y) {
      for (int x = std::max(0, int(cx - r)); x < std::min(w, int(cx + r) + 1); ++x) {
        if ((x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r) hole[static_cast<std::size_t>(y) * w + x] = 1;
      }
    }
  }
  return hole;
}

// Whether pixel (x, y) lies on the outline of a moving object: it or a 4-neighbour is on one,
// and their depths differ by more than 10 cm.
bool edge_of_mover(const std::vector<double>& z, const std::vector<uint8_t>& moving, int w, int h, int x, int y) {
  const std::size_t i = static_cast<std::size_t>(y) * w + x;
  const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
  for (int k = 0; k < 4; ++k) {
    const int nx = x + dx[k], ny = y + dy[k];
    if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
    const std::size_t j = static_cast<std::size_t>(ny) * w + nx;
    if ((moving[i] || moving[j]) && std::abs(z[i] - z[j]) > 0.1) return true;
  }
  return false;
}

}  // namespace

bool swept_by_movers(const Eigen::Vector3d& p, double margin) {
  const auto inside = [&](const Vector3d& lo, const Vector3d& hi) {
    return (p.array() > lo.array() + margin).all() && (p.array() < hi.array() - margin).all();
  };
  const double z = Movers::kPersonZ;
  // The person's path, head included; the chair's path short of where it was left, as far as
  // the arc's camera sees it once the chair has moved (x < 1.3: beyond, no view shows it empty).
  return inside(Vector3d(Movers::kFrom - 0.22, -0.28, z - 0.13), Vector3d(Movers::kStop + 0.22, 1.5, z + 0.13)) ||
         inside(Vector3d(0.92, 0.6, 0.08), Vector3d(1.3, 1.5, 0.52));
}

double colour_gain(const SyntheticOptions& o, double seconds) {
  constexpr double kPeriod = 3;  // seconds: an auto exposure hunting slowly
  return std::exp(o.gain_swing * std::sin(2 * M_PI * seconds / kPeriod));
}

SyntheticOptions SyntheticOptions::hard_motion() {
  SyntheticOptions o;
  o.shake_peak_rate = 2.2;
  o.exposure = 1.0 / 60;
  o.blur_samples = 4;
  o.depth_noise = 0.0015;
  o.depth_holes = 0.05;
  return o;
}

namespace {

// Each pixel's viewing direction (x / z, y / z) through the lens of focal length `focal`, at its 4
// colour supersamples and then its centre (sample 4).
std::vector<Eigen::Vector2d> lens_directions(const SyntheticOptions& o, double focal, double cx, double cy) {
  std::vector<Eigen::Vector2d> at;
  at.reserve(static_cast<std::size_t>(o.width) * o.height * 5);
  for (int y = 0; y < o.height; ++y) {
    for (int x = 0; x < o.width; ++x) {
      for (int s = 0; s < 4; ++s) {
        at.emplace_back((x + 0.25 + 0.5 * (s % 2) - cx) / focal, (y + 0.25 + 0.5 * (s / 2) - cy) / focal);
      }
      at.emplace_back((x + 0.5 - cx) / focal, (y + 0.5 - cy) / focal);
    }
  }
  return o.distortion.any() ? undistort_normalized(o.distortion, at) : at;
}

// Seconds from the frame's middle row to row y's instant (SyntheticOptions::rolling_shutter).
double row_offset(const SyntheticOptions& o, int y) {
  return o.rolling_shutter * ((y + 0.5) / o.height - 0.5);
}

}  // namespace

void write_synthetic_sequence(const std::filesystem::path& dir, const SyntheticOptions& o) {
  if (o.frames < 1 || o.width < 8 || o.height < 8)
    throw splat::Error("synthetic sequence: bad size or frame count");
  if (o.path_frames != 0 && o.path_frames < o.frames) {
    throw splat::Error("synthetic sequence: path_frames " + std::to_string(o.path_frames) +
                       " must be 0 or at least frames (" + std::to_string(o.frames) + ")");
  }
  if (o.blur_samples < 1 || !(o.exposure >= 0) || !(o.depth_noise >= 0) ||
      !(o.depth_holes >= 0 && o.depth_holes < 1) || !(o.shake_peak_rate >= 0) || !(o.fps > 0) ||
      !(o.depth_lag >= 0 && o.depth_lag < 0.5 / o.fps) || !(o.rolling_shutter >= 0 && o.rolling_shutter <= 1 / o.fps) ||
      !(o.gain_swing >= 0 && o.gain_swing <= 2) || !(o.color_focal_ratio >= 0.5 && o.color_focal_ratio <= 2) ||
      !o.color_centre_shift.allFinite()) {
    throw splat::Error(
        "synthetic sequence: blur_samples >= 1, fps > 0 and non-negative exposure, noise, shake "
        "and holes below 1, depth lag under half a frame, a rolling shutter's readout within a frame, gain swing in [0, 2], colour focal ratio in [0.5, 2] "
        "expected");
  }
  if (o.distortion
          .any()) {  // a lens that folds the image over is refused before anything is written
    splat::Camera lens;
    lens.fx = lens.fy = o.focal, lens.cx = o.width / 2.0, lens.cy = o.height / 2.0;
    lens.width = o.width, lens.height = o.height;
    const Undistortion check(lens, o.distortion, "synthetic sequence");
  }
  std::mt19937 rng(o.seed);
  std::normal_distribution<double> gauss(0, 1);
  std::filesystem::create_directories(dir / "rgb");
  std::filesystem::create_directories(dir / "depth");
  if (o.labels) std::filesystem::create_directories(dir / "labels");
  const Scene scene(o.twin_rooms);
  splat::ThreadPool pool;
  const Vector3d light = Vector3d(0.4, -1.0, 0.3).normalized();  // from above (y down)
  std::vector<StampedPose> truth;
  std::string rgb_list = "# color images\n# timestamp filename\n", depth_list = "# depth maps\n# timestamp filename\n";
  const double cx = o.width / 2.0, cy = o.height / 2.0;
  const std::vector<Eigen::Vector2d> lens = lens_directions(o, o.focal, cx, cy);
  const bool unregistered = o.color_focal_ratio != 1 || !o.color_centre_shift.isZero();
  const std::vector<Eigen::Vector2d> color_lens =
      unregistered ? lens_directions(o, o.focal * o.color_focal_ratio, cx + o.color_centre_shift.x(),
                                     cy + o.color_centre_shift.y())
                   : std::vector<Eigen::Vector2d>{};
  const auto direction = [&](int x, int y, int sample) {
    const Eigen::Vector2d& n = lens[(static_cast<std::size_t>(y) * o.width + x) * 5 + sample];
    return Vector3d(n.x(), n.y(), 1.0);
  };
  const auto color_direction = [&](int x, int y, int sample) {
    if (!unregistered) return direction(x, y, sample);
    const Eigen::Vector2d& n = color_lens[(static_cast<std::size_t>(y) * o.width + x) * 5 + sample];
    return Vector3d(n.x(), n.y(), 1.0);
  };
  for (int f = 0; f < o.frames; ++f) {
    const double seconds = f / o.fps, timestamp = 1000.0 + seconds;
    const Eigen::Isometry3d pose = camera_pose(o, seconds);  // mid-exposure: the ground truth
    // Colour over the exposure: 2x2 supersamples per instant, the instants spread evenly.
    std::vector<std::pair<Eigen::Isometry3d, double>> instants;  // pose, seconds
    for (int k = 0; k < o.blur_samples; ++k) {
      const double at = seconds + (o.blur_samples > 1 ? (k + 0.5) / o.blur_samples - 0.5 : 0.0) * o.exposure;
      instants.emplace_back(camera_pose(o, at), at);
    }
    const std::vector<uint8_t> holes = hole_mask(o.width, o.height, o.depth_holes, rng);
    std::vector<float> rgb(static_cast<std::size_t>(o.width) * o.height * 3, 0.f);
    const double gain = colour_gain(o, seconds);
    splat::Image16 depth(o.width, o.height, 1), labels(o.width, o.height, 1);
    // Colour, row by row on every core (no random numbers: the same image on any machine).
    pool.parallel_for(static_cast<std::size_t>(o.height), [&](std::size_t row) {
      const int y = static_cast<int>(row);
      std::vector<std::pair<Eigen::Isometry3d, double>> row_instants;
      if (o.rolling_shutter > 0) {
        for (const auto& [at, at_seconds] : instants) {
          const double t = at_seconds + row_offset(o, y);
          row_instants.emplace_back(camera_pose(o, t), t);
        }
      }
      const auto& seen = o.rolling_shutter > 0 ? row_instants : instants;
      for (int x = 0; x < o.width; ++x) {
        Vector3d color = Vector3d::Zero();
        const double weight = 0.25 / static_cast<double>(seen.size());
        for (const auto& [at, at_seconds] : seen) {
          for (int s = 0; s < 4; ++s) {
            const Vector3d dir_cam = color_direction(x, y, s);
            Hit hit;
            trace(scene, o, at.translation(), (at.linear() * dir_cam).normalized(), at_seconds, hit);
            if (std::isfinite(hit.t)) color += weight * hit.color * (0.55 + 0.45 * std::max(0.0, hit.normal.dot(-light)));
          }
        }
        for (int c = 0; c < 3; ++c) {
          rgb[(static_cast<std::size_t>(y) * o.width + x) * 3 + c] =
              static_cast<float>(std::min(1.0, gain * color[c]));
        }
      }
    });
    // Depth and labels at the pixel centres, mid-exposure, at the depth camera's instant (row by
    // row on every core; the noise and dropouts after, in order, from the seeded generator): its
    // offset from the colour's sweeps the lag's range every 23 frames (two clocks a little apart).
    const double phase = std::fmod(f / 23.0 + 0.5, 1.0);
    const double depth_seconds = seconds + o.depth_lag * (2 * phase - 1), depth_timestamp = 1000.0 + depth_seconds;
    const Eigen::Isometry3d depth_pose = o.depth_lag > 0 ? camera_pose(o, depth_seconds) : pose;
    std::vector<double> z_true(static_cast<std::size_t>(o.width) * o.height, 0.0);
    std::vector<uint8_t> moving(z_true.size(), 0), grazing(z_true.size(), 0);
    pool.parallel_for(static_cast<std::size_t>(o.height), [&](std::size_t row) {
      const int y = static_cast<int>(row);
      const double row_seconds = (o.depth_lag > 0 ? depth_seconds : seconds) + row_offset(o, y);
      const Eigen::Isometry3d row_pose = o.rolling_shutter > 0 ? camera_pose(o, row_seconds) : depth_pose;
      const Eigen::Isometry3d world_to_depth = row_pose.inverse();
      for (int x = 0; x < o.width; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * o.width + x;
        const Vector3d ray = (row_pose.linear() * direction(x, y, 4)).normalized();
        Hit hit;
        trace(scene, o, row_pose.translation(), ray, row_seconds, hit);
        if (!std::isfinite(hit.t)) continue;
        z_true[i] = (world_to_depth * hit.point).z();
        labels.at(x, y) = hit.label;
        moving[i] = hit.moving;
        grazing[i] = std::abs(hit.normal.dot(ray)) < std::cos(80 * M_PI / 180);
      }
    });
    for (int y = 0; y < o.height; ++y) {
      for (int x = 0; x < o.width; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * o.width + x;
        if (z_true[i] <= 0 || holes[i] || (o.depth_holes > 0 && grazing[i])) continue;
        // A depth camera loses most pixels along a moving object's outline (mixed returns).
        if ((o.movers || o.walkers) && edge_of_mover(z_true, moving, o.width, o.height, x, y) &&
            std::uniform_real_distribution<>(0, 1)(rng) < 0.6) {
          continue;
        }
        double z = z_true[i];
        if (o.depth_noise > 0) z += o.depth_noise * z * z * gauss(rng);
        depth.at(x, y) = static_cast<uint16_t>(std::clamp(std::lround(z * 5000.0), 0L, 65535L));
      }
    }
    char name[64], depth_name[64];
    std::snprintf(name, sizeof(name), "%.6f.png", timestamp);
    std::snprintf(depth_name, sizeof(depth_name), "%.6f.png", o.depth_lag > 0 ? depth_timestamp : timestamp);
    // Each PNG compressed on its own core.
    pool.parallel_for(o.labels ? 3 : 2, [&](std::size_t image) {
      if (image == 0) write_png_rgb(dir / "rgb" / name, o.width, o.height, rgb);
      if (image == 1) write_png_gray16(dir / "depth" / depth_name, depth);
      if (image == 2) write_png_gray16(dir / "labels" / name, labels);
    });
    rgb_list += std::string(name, name + std::strlen(name) - 4) + " rgb/" + name + "\n";
    depth_list += std::string(depth_name, depth_name + std::strlen(depth_name) - 4) + " depth/" + depth_name + "\n";
    truth.push_back({timestamp, pose});
  }
  auto write_text = [&](const std::filesystem::path& path, const std::string& text) {
    write_atomically(path, [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << text; });
  };
  write_text(dir / "rgb.txt", rgb_list);
  write_text(dir / "depth.txt", depth_list);
  char intrinsics[128];
  const double stated = o.focal * (1 + o.focal_error);
  std::snprintf(intrinsics, sizeof(intrinsics), "%.6f %.6f %.6f %.6f", stated, stated, cx, cy);
  std::string intrinsics_line = intrinsics;
  for (double k : o.distortion.any() ? o.distortion.coefficients() : std::vector<double>{}) {
    std::snprintf(intrinsics, sizeof(intrinsics), " %.9g", k);
    intrinsics_line += intrinsics;
  }
  intrinsics_line += "\n";
  write_text(dir / "intrinsics.txt", intrinsics_line);
  write_tum_trajectory(dir / "groundtruth.txt", truth);
  if (!o.labels) return;
  write_text(dir / "labels" / "classes.json", R"({"classes": [
  {"id": 1, "name": "wall"}, {"id": 2, "name": "floor"}, {"id": 3, "name": "ceiling"},
  {"id": 4, "name": "ball"}, {"id": 5, "name": "cabinet"}, {"id": 6, "name": "person", "dynamic": true},
  {"id": 7, "name": "chair"}, {"id": 8, "name": "crate"}
]}
)");
}

}  // namespace app
