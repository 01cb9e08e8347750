#include "tracking/rgbd_odometry.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <Eigen/Eigenvalues>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "splat/error.h"
#include "splat/field_check.h"
#include "splat/se3.h"
#include "tracking/log1p_float.h"

namespace tracking {

void OdometryConfig::validate(const std::string& prefix) const {
  const splat::FieldCheck check(prefix);
  if (iterations.empty() || iterations.size() > 6) {
    check.fail("iterations", "one count per pyramid level, 1 to 6 levels", std::to_string(iterations.size()) + " counts");
  }
  for (int n : iterations) check.at_least("iterations", n, 0);
  check.in_range("finest_width", finest_width, 16, 16384);
  check.at_least("max_points", max_points, 16);
  check.positive("depth_noise", depth_noise);
  check.positive("t_dof", t_dof);
  check.at_least("depth_weight", depth_weight, 0.0);
  check.at_least("blur_scale_px", blur_scale_px, 0.0);
  check.at_least("exposure", exposure, 0.0);
  check.positive("fade_per_blur_px", fade_per_blur_px);
  check.in_range("exposure_window", exposure_window, 2, 100000);
  check.at_least("rolling_shutter", rolling_shutter, 0.0);
  check.positive("min_depth", min_depth);
  check.positive("max_depth_slope", max_depth_slope);
  if (!(max_depth > min_depth)) check.fail("max_depth", "a number > min_depth", max_depth);
  check.at_least("min_step_translation", min_step_translation, 0.0);
  check.at_least("min_step_rotation", min_step_rotation, 0.0);
  check.in_range("min_overlap", min_overlap, 0.0, 1.0);
  check.in_range("min_conditioning", min_conditioning, 0.0, 1.0);
}

namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// Central differences of depth where both neighbours are measured, else 0 (a hole's edge is no
// surface gradient). OpenCV's filters would mix the holes' zeros in.
void depth_gradients(OdometryFrame::Level& l) {
  const int w = l.width, h = l.height;
  l.depth_dx.assign(l.depth.size(), 0.f);
  l.depth_dy.assign(l.depth.size(), 0.f);
  for (int y = 1; y + 1 < h; ++y) {
    for (int x = 1; x + 1 < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const float left = l.depth[i - 1], right = l.depth[i + 1], up = l.depth[i - w], down = l.depth[i + w];
      if (left > 0 && right > 0) l.depth_dx[i] = 0.5f * (right - left);
      if (up > 0 && down > 0) l.depth_dy[i] = 0.5f * (down - up);
    }
  }
}

// Picks the reference points of a level: measured pixels inside the depth range, the
// max_points with the largest gradients (intensity, plus depth relative to its noise).
void select_points(OdometryFrame::Level& l, const OdometryConfig& c) {
  std::vector<std::pair<float, int>> scored;
  scored.reserve(l.depth.size());
  for (int y = 1; y + 1 < l.height; ++y) {
    for (int x = 1; x + 1 < l.width; ++x) {
      const int i = y * l.width + x;
      const float z = l.depth[i];
      if (!(z >= c.min_depth && z <= c.max_depth)) continue;
      if (!l.ignore.empty() && l.ignore[i]) continue;
      // Not at a depth edge or next to a hole: there the depth is mixed or missing, colour and
      // depth disagree most (unregistered sensors, shadows), and the depth residual is ill-defined.
      const float slope = std::sqrt(l.depth_dx[i] * l.depth_dx[i] + l.depth_dy[i] * l.depth_dy[i]) / z;
      if (!(slope <= static_cast<float>(c.max_depth_slope))) continue;
      bool hole = false;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) hole = hole || !(l.depth[i + dy * l.width + dx] > 0);
      }
      if (hole) continue;
      const float noise = static_cast<float>(c.depth_noise) * z * z;
      const float gi = l.intensity_dx[i] * l.intensity_dx[i] + l.intensity_dy[i] * l.intensity_dy[i];
      const float gz = (l.depth_dx[i] * l.depth_dx[i] + l.depth_dy[i] * l.depth_dy[i]) / (noise * noise);
      scored.emplace_back(gi * 400.f + 0.01f * std::min(gz, 100.f), i);  // 1/20 intensity ~ 1 noise unit
    }
  }
  const std::size_t keep = std::min(scored.size(), static_cast<std::size_t>(c.max_points));
  std::nth_element(scored.begin(), scored.begin() + static_cast<std::ptrdiff_t>(keep), scored.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  scored.resize(keep);
  std::sort(scored.begin(), scored.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  l.points.clear();
  l.positions.clear();
  for (const auto& [score, i] : scored) {
    const float z = l.depth[i];
    const float u = static_cast<float>(i % l.width) + 0.5f, v = static_cast<float>(i / l.width) + 0.5f;
    l.points.push_back(i);
    l.positions.emplace_back(static_cast<float>((u - l.cx) / l.fx) * z, static_cast<float>((v - l.cy) / l.fy) * z, z);
  }
}

struct Sample {
  float intensity, gx, gy;
  float depth, zx, zy;  // depth 0: no depth residual here
};

// Bilinear sample at array coordinates (x, y) (pixel centres at integers), which must satisfy
// 0 <= x < w - 1 and 0 <= y < h - 1. Depth only where the four neighbours are measured and agree
// within 5% (across a depth edge an interpolated depth belongs to no surface).
Sample sample(const OdometryFrame::Level& l, float x, float y) {
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const float ax = x - static_cast<float>(x0), ay = y - static_cast<float>(y0);
  const std::size_t i = static_cast<std::size_t>(y0) * l.width + x0, j = i + l.width;
  const float w00 = (1 - ax) * (1 - ay), w10 = ax * (1 - ay), w01 = (1 - ax) * ay, w11 = ax * ay;
  auto lerp = [&](const std::vector<float>& v) { return w00 * v[i] + w10 * v[i + 1] + w01 * v[j] + w11 * v[j + 1]; };
  Sample s{lerp(l.intensity), lerp(l.intensity_dx), lerp(l.intensity_dy), 0, 0, 0};
  const float d00 = l.depth[i], d10 = l.depth[i + 1], d01 = l.depth[j], d11 = l.depth[j + 1];
  const float lo = std::min({d00, d10, d01, d11}), hi = std::max({d00, d10, d01, d11});
  if (lo > 0 && hi - lo < 0.05f * lo) {
    s.depth = lerp(l.depth);
    s.zx = lerp(l.depth_dx);
    s.zy = lerp(l.depth_dy);
  }
  return s;
}

// The scale of t-distributed residuals (DVO's fixed point), given their squares.
double t_scale(const std::vector<float>& squares, double dof) {
  if (squares.empty()) return 1;
  double variance = 0;
  for (float r2 : squares) variance += r2;
  variance = std::max(variance / static_cast<double>(squares.size()), 1e-12);
  for (int k = 0; k < 5; ++k) {
    double sum = 0;
    for (float r2 : squares) sum += r2 * (dof + 1) / (dof + r2 / variance);
    variance = std::max(sum / static_cast<double>(squares.size()), 1e-12);
  }
  return std::sqrt(variance);
}

struct Normal {
  Matrix6d h = Matrix6d::Zero();
  Vector6d b = Vector6d::Zero();
  double cost = 0;
  std::size_t seen = 0;  // points with a depth sample in the current frame
  double depth_median_square = 0;  // the median squared depth residual (in sensor noise units)
  // Per photometric term: the reference's intensity and the current frame's where it lands.
  std::vector<std::pair<float, float>> intensities;
};

// The colour camera's gain between the frames, I_cur = gain I_ref (exposure and gain changing
// between frames): the ratio of the intensities' sums, weighted by the t-distribution
// (outliers: occlusions, highlights, moving objects), a few rounds. A ratio of means, not a
// regression: the small misalignments of a pose not yet converged scatter both sides alike and
// leave it unbiased, where a fitted slope shrinks towards zero (and a fitted offset takes the
// rest). Under 16 pairs there is nothing to tell, and the gain stays `start`.
float fit_gain(const std::vector<std::pair<float, float>>& pairs, double dof, float start) {
  if (pairs.size() < 16) return start;
  float gain = start;
  std::vector<float> squares(pairs.size());
  for (int round = 0; round < 3; ++round) {
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const float r = pairs[k].second - gain * pairs[k].first;
      squares[k] = r * r;
    }
    const double inv_var = 1 / std::pow(t_scale(squares, dof), 2);
    double current = 0, reference = 0;
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const double w = (dof + 1) / (dof + squares[k] * inv_var);
      current += w * pairs[k].second;
      reference += w * pairs[k].first;
    }
    if (!(reference > 0) || !std::isfinite(current / reference)) return start;
    // An exposure changes by a few tens of percent between a frame and its keyframe; a ratio
    // past 2x either way is a wrong alignment's, not the camera's.
    gain = static_cast<float>(std::clamp(current / reference, 0.5, 2.0));
  }
  return gain;
}

// h += w j j^T on the upper triangle, as Eigen's selfadjointView<Upper>().rankUpdate(j, w) sums it
// (column c adds (w j_c) j_r to rows r <= c), unrolled: Eigen's loop over columns of 1..6 rows
// cost 6% of tracking.
inline void rank_update_upper(Eigen::Matrix<float, 6, 6>& h, const Eigen::Matrix<float, 6, 1>& j, float w) {
  for (int c = 0; c < 6; ++c) {
    const float s = w * j[c];
    for (int r = 0; r <= c; ++r) h(r, c) += s * j[r];
  }
}

// The rolling shutter's correction (OdometryConfig::rolling_shutter): a static point seen at row
// time s from the middle row's instant lies at p - s (omega x p + v) in the camera then.
struct RollingShutter {
  struct Twist {
    Eigen::Vector3f v, omega;
    explicit Twist(const Eigen::Matrix<double, 6, 1>& t) : v(t.head<3>().cast<float>()), omega(t.tail<3>().cast<float>()) {}
  };
  bool on = false;
  float seconds_per_row = 0, middle_row = 0;
  Twist reference, current;
  RollingShutter(const OdometryConfig& c, const FrameMotion& motion, int height)
      : on(c.rolling_shutter > 0 && (motion.reference.squaredNorm() > 0 || motion.current.squaredNorm() > 0)),
        seconds_per_row(static_cast<float>(c.rolling_shutter / height)),
        middle_row(0.5f * static_cast<float>(height)),
        reference(motion.reference),
        current(motion.current) {}
  // The row time of array row y (pixel centres at integers), from the middle row's.
  float seconds(float y) const { return (y + 0.5f - middle_row) * seconds_per_row; }
  static Eigen::Vector3f moved(const Twist& t, const Eigen::Vector3f& p, float s) { return p - s * (t.omega.cross(p) + t.v); }
  // Reference point k of `ref` in the current camera (rotation r, translation t) as the row it
  // lands on sees it: first as the reference's middle row saw it, then moved to the row where the
  // current frame's middle row would see it (a fraction of a row from where it lands). Behind
  // the camera: z = 0.
  Eigen::Vector3f seen(const Eigen::Matrix3f& r, const Eigen::Vector3f& t, const OdometryFrame::Level& ref,
                       std::size_t k, float fy, float cy) const {
    const float ref_row = static_cast<float>(ref.points[k] / ref.width);
    const Eigen::Vector3f middle = r * moved(reference, ref.positions[k], -seconds(ref_row)) + t;
    if (!(middle.z() > 0)) return Eigen::Vector3f::Zero();
    return moved(current, middle, seconds(fy * middle.y() / middle.z() + cy));
  }
};

// Reference point k in the current camera: rigidly, or as the row it lands on sees it
// (RollingShutter::seen); the global shutter's instance is the plain transform, unchanged.
template <bool kRolling>
inline Eigen::Vector3f project_reference(const Eigen::Matrix3f& r, const Eigen::Vector3f& t,
                                         const OdometryFrame::Level& ref, std::size_t k,
                                         const RollingShutter& rolling, float fy, float cy) {
  if constexpr (kRolling) {
    return rolling.seen(r, t, ref, k, fy, cy);
  } else {
    return r * ref.positions[k] + t;
  }
}

// One linearization of every reference point of a level at T_cur_ref. With `estimate`, the
// t-distribution scales are estimated from these residuals first; otherwise the given ones are
// used, so that costs at two poses compare. The cost is the mean robust cost per term.
template <bool kRolling>
Normal linearize_points(const OdometryFrame::Level& ref, const OdometryFrame::Level& cur,
                        const Eigen::Isometry3d& T, const OdometryConfig& c, float gain,
                        double& intensity_scale, double& depth_scale, bool estimate,
                        const RollingShutter& rolling) {
  const Eigen::Matrix3f r = T.linear().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  const float fx = static_cast<float>(cur.fx), fy = static_cast<float>(cur.fy);
  const float cx = static_cast<float>(cur.cx) - 0.5f, cy = static_cast<float>(cur.cy) - 0.5f;
  const std::size_t n = ref.points.size();
  struct Term {
    Eigen::Matrix<float, 6, 1> j;
    float r;
  };
  std::vector<Term> photometric, geometric;
  photometric.reserve(n);
  geometric.reserve(n);
  Normal out;
  if (c.estimate_brightness) out.intensities.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3f p = project_reference<kRolling>(r, t, ref, k, rolling, fy, cy);
    if (!(p.z() > static_cast<float>(c.min_depth))) continue;
    const float inv_z = 1.f / p.z();
    const float x = fx * p.x() * inv_z + cx, y = fy * p.y() * inv_z + cy;
    if (!(x >= 0 && y >= 0 && x < static_cast<float>(cur.width - 1) && y < static_cast<float>(cur.height - 1))) continue;
    if (!cur.ignore.empty() && cur.ignore[static_cast<std::size_t>(y + 0.5f) * cur.width + static_cast<std::size_t>(x + 0.5f)]) {
      continue;
    }
    const Sample s = sample(cur, x, y);
    // d(pixel)/d(p) and d(p)/d(xi) = [I | -[p]x] for the left perturbation.
    const float dux_dx = fx * inv_z, dux_dz = -fx * p.x() * inv_z * inv_z;
    const float duy_dy = fy * inv_z, duy_dz = -fy * p.y() * inv_z * inv_z;
    auto chain = [&](float gu, float gv, float gz_direct) {
      // g . d(pixel)/dp + gz_direct * d(p.z)/dp, as a gradient with respect to p...
      const Eigen::Vector3f g(gu * dux_dx, gv * duy_dy, gu * dux_dz + gv * duy_dz + gz_direct);
      // ...then through d(p)/d(xi): translation part g, rotation part p x g.
      Eigen::Matrix<float, 6, 1> j;
      j.head<3>() = g;
      j.tail<3>() = p.cross(g);
      return j;
    };
    const float reference_intensity = ref.intensity[ref.points[k]];
    const float r_intensity = s.intensity - gain * reference_intensity;
    photometric.push_back({chain(s.gx, s.gy, 0.f), r_intensity});
    if (c.estimate_brightness) out.intensities.emplace_back(reference_intensity, s.intensity);
    if (s.depth > 0) {
      ++out.seen;
      const float noise = static_cast<float>(c.depth_noise) * p.z() * p.z();
      geometric.push_back({chain(s.zx, s.zy, -1.f) / noise, (s.depth - p.z()) / noise});
    }
  }
  // Points that leave the image (or land on no depth) cost as much as a residual of three
  // scales: otherwise a step that pushes points out of view would look like an improvement.
  const double lost_cost = std::log1p(9 / c.t_dof);
  auto accumulate = [&](const std::vector<Term>& terms, double weight, double& scale,
                        double* median_square) {
    std::vector<float> squares(terms.size());
    for (std::size_t k = 0; k < terms.size(); ++k) squares[k] = terms[k].r * terms[k].r;
    if (estimate) scale = t_scale(squares, c.t_dof);
    const double inv_var = 1 / (scale * scale);
    Eigen::Matrix<float, 6, 6> h = Eigen::Matrix<float, 6, 6>::Zero();
    Eigen::Matrix<float, 6, 1> b = Eigen::Matrix<float, 6, 1>::Zero();
    double cost = 0;
    const float inv_var_f = static_cast<float>(inv_var), dof = static_cast<float>(c.t_dof);
    for (std::size_t k = 0; k < terms.size(); ++k) {
      const float u = squares[k] * inv_var_f;
      const float w = (dof + 1) / (dof + u) * inv_var_f;
      rank_update_upper(h, terms[k].j, w);
      b += w * terms[k].r * terms[k].j;
      cost += log1p_nonnegative(u / dof);  // the t-distribution's negative log-likelihood, up to constants
    }
    out.h += weight * h.selfadjointView<Eigen::Upper>().toDenseMatrix().cast<double>();
    out.b += weight * b.cast<double>();
    cost += lost_cost * static_cast<double>(n - terms.size());
    out.cost += weight * cost / std::max<double>(1, static_cast<double>(n));
    if (median_square && !squares.empty()) {
      const auto middle = squares.begin() + static_cast<std::ptrdiff_t>(squares.size() / 2);
      std::nth_element(squares.begin(), middle, squares.end());
      *median_square = *middle;
    }
  };
  accumulate(photometric, 1.0, intensity_scale, nullptr);
  if (c.depth_weight > 0)
    accumulate(geometric, c.depth_weight, depth_scale, &out.depth_median_square);
  return out;
}

Normal linearize(const OdometryFrame::Level& ref, const OdometryFrame::Level& cur, const Eigen::Isometry3d& T,
                 const OdometryConfig& c, float gain, double& intensity_scale, double& depth_scale,
                 bool estimate, const RollingShutter& rolling) {
  return rolling.on ? linearize_points<true>(ref, cur, T, c, gain, intensity_scale, depth_scale, estimate, rolling)
                    : linearize_points<false>(ref, cur, T, c, gain, intensity_scale, depth_scale, estimate, rolling);
}

}  // namespace

std::vector<int> OdometryFrame::factors(int width, const OdometryConfig& config) {
  int finest = 1;
  while (width / finest > config.finest_width) finest *= 2;
  std::vector<int> out;
  for (std::size_t level = 0; level < config.iterations.size(); ++level) {
    out.insert(out.begin(), finest << level);
  }
  return out;
}

namespace {

// Adds `left_out` to the ignore mask of `scaled`, the frame downsampled by `factor`: each pixel
// takes the largest reason of the blocks its factor x factor pixels fall in, as downsampling the
// frame with them in its own mask would give.
void add_left_out(splat::RgbdFrame& scaled, const OdometryFrame::LeftOut& left_out, int factor,
                  int frame_width, int frame_height) {
  const int blocks_width = frame_width / left_out.factor,
            blocks_height = frame_height / left_out.factor;
  if (scaled.ignore.empty())
    scaled.ignore.assign(static_cast<std::size_t>(scaled.width()) * scaled.height(), 0);
  for (int y = 0; y < scaled.height(); ++y) {
    const int by0 = std::min(y * factor / left_out.factor, blocks_height - 1);
    const int by1 = std::min((y * factor + factor - 1) / left_out.factor, blocks_height - 1);
    for (int x = 0; x < scaled.width(); ++x) {
      const int bx0 = std::min(x * factor / left_out.factor, blocks_width - 1);
      const int bx1 = std::min((x * factor + factor - 1) / left_out.factor, blocks_width - 1);
      uint8_t& ignored = scaled.ignore[static_cast<std::size_t>(y) * scaled.width() + x];
      for (int by = by0; by <= by1; ++by) {
        for (int bx = bx0; bx <= bx1; ++bx)
          ignored =
              std::max(ignored, left_out.reasons[static_cast<std::size_t>(by) * blocks_width + bx]);
      }
    }
  }
}

}  // namespace

OdometryFrame::OdometryFrame(const splat::RgbdFrame& frame, const OdometryConfig& config,
                             const LeftOut& left_out)
    : timestamp_(frame.timestamp) {
  config.validate();
  const std::size_t pixels = static_cast<std::size_t>(frame.width()) * frame.height();
  if (frame.rgb.size() != pixels * 3 || frame.depth.size() != pixels || (!frame.ignore.empty() && frame.ignore.size() != pixels)) {
    throw splat::Error("OdometryFrame: frame images do not match its " + std::to_string(frame.width()) + "x" +
                       std::to_string(frame.height()) + " camera");
  }
  if (!left_out.reasons.empty() &&
      (left_out.factor < 1 || frame.width() / left_out.factor < 1 ||
       frame.height() / left_out.factor < 1 ||
       left_out.reasons.size() != static_cast<std::size_t>(frame.width() / left_out.factor) *
                                      static_cast<std::size_t>(frame.height() / left_out.factor))) {
    throw splat::Error("OdometryFrame: " + std::to_string(left_out.reasons.size()) +
                       " pixels left out at factor " + std::to_string(left_out.factor) +
                       " do not fit a " + std::to_string(frame.width()) + "x" +
                       std::to_string(frame.height()) + " frame");
  }
  // Each level from the previous one where the factors allow (box averages of box averages).
  splat::RgbdFrame scaled;
  int scaled_factor = 0;
  const std::vector<int> pyramid = factors(frame.width(), config);
  std::vector<int> order(pyramid.rbegin(), pyramid.rend());  // finest first
  std::vector<Level> finest_first;
  for (int factor : order) {
    if (scaled_factor > 0 && factor % scaled_factor == 0) {
      scaled = splat::downsample(scaled, factor / scaled_factor);
    } else {
      scaled = splat::downsample(frame, factor);
    }
    scaled_factor = factor;
    if (!left_out.reasons.empty())
      add_left_out(scaled, left_out, factor, frame.width(), frame.height());
    Level l;
    l.width = scaled.width();
    l.height = scaled.height();
    l.fx = scaled.camera.fx, l.fy = scaled.camera.fy, l.cx = scaled.camera.cx, l.cy = scaled.camera.cy;
    if (l.width < 4 || l.height < 4) {
      throw splat::Error("OdometryFrame: pyramid factor " + std::to_string(factor) + " leaves a " +
                         std::to_string(l.width) + "x" + std::to_string(l.height) + " image");
    }
    const cv::Mat rgb(l.height, l.width, CV_32FC3, scaled.rgb.data());
    cv::Mat grey;
    cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
    l.intensity.assign(grey.ptr<float>(), grey.ptr<float>() + grey.total());
    cv::Mat gx, gy;
    cv::Sobel(grey, gx, CV_32F, 1, 0, 3, 1.0 / 8, 0, cv::BORDER_REPLICATE);
    cv::Sobel(grey, gy, CV_32F, 0, 1, 3, 1.0 / 8, 0, cv::BORDER_REPLICATE);
    l.intensity_dx.assign(gx.ptr<float>(), gx.ptr<float>() + gx.total());
    l.intensity_dy.assign(gy.ptr<float>(), gy.ptr<float>() + gy.total());
    l.depth = scaled.depth;
    l.ignore = scaled.ignore;
    depth_gradients(l);
    select_points(l, config);
    finest_first.push_back(std::move(l));
  }
  levels_.assign(std::make_move_iterator(finest_first.rbegin()), std::make_move_iterator(finest_first.rend()));
}

OdometryFrame::OdometryFrame(const splat::RgbdFrame& frame, const OdometryConfig& config)
    : OdometryFrame(frame, config, LeftOut{}) {}

double blur_aware_depth_weight(const OdometryConfig& config, const OdometryFrame& current, double current_rate,
                               double reference_rate) {
  const double angular_rate = std::hypot(current_rate, reference_rate);
  if (!(config.blur_scale_px > 0) || !(angular_rate > 0) || current.levels().empty()) return config.depth_weight;
  const double blur = current.levels().back().fx * angular_rate * config.exposure;
  const double ratio = std::min(blur / config.blur_scale_px, 1e3);  // a wild rate is still a finite weight
  return config.depth_weight * (1 + ratio * ratio);
}

OdometryResult align_rgbd(const OdometryFrame& reference, const OdometryFrame& current,
                          const Eigen::Isometry3d& initial_T_cur_ref, const OdometryConfig& config,
                          const FrameMotion& motion) {
  config.validate();
  const std::size_t levels = config.iterations.size();
  if (reference.levels().size() != levels || current.levels().size() != levels ||
      reference.levels().back().width != current.levels().back().width) {
    throw splat::Error("align_rgbd: the frames were prepared for another pyramid (" +
                       std::to_string(reference.levels().size()) + " and " + std::to_string(current.levels().size()) +
                       " levels, expected " + std::to_string(levels) + ", of equal sizes)");
  }
  OdometryResult result;
  Eigen::Isometry3d T = initial_T_cur_ref;
  float gain = 1;
  for (std::size_t level = 0; level < levels; ++level) {
    const OdometryFrame::Level& ref = reference.levels()[level];
    const OdometryFrame::Level& cur = current.levels()[level];
    const bool finest = level + 1 == levels;
    const RollingShutter rolling(config, motion, cur.height);
    double intensity_scale = 0, depth_scale = 0;
    Normal normal = linearize(ref, cur, T, config, gain, intensity_scale, depth_scale, true, rolling);
    // The gain is held through each level's steps, so that the costs of two poses compare: fitted
    // here on the coarsest level, where each coarser level ends for the finer ones.
    if (config.estimate_brightness && level == 0) {
      gain = fit_gain(normal.intensities, config.t_dof, gain);
      normal = linearize(ref, cur, T, config, gain, intensity_scale, depth_scale, true, rolling);
    }
    double lambda = 0;  // Levenberg-Marquardt damping, raised only when a step fails
    for (int it = 0; it < config.iterations[level]; ++it) {
      Matrix6d h = normal.h;
      h.diagonal() *= 1 + lambda;
      const Vector6d delta = h.ldlt().solve(-normal.b);
      if (!delta.allFinite()) break;
      const Eigen::Isometry3d candidate = splat::orthonormalized(splat::se3_exp(delta) * T);
      Normal next =
          linearize(ref, cur, candidate, config, gain, intensity_scale, depth_scale, false, rolling);
      ++result.iterations;
      if (next.cost <= normal.cost) {
        T = candidate;
        normal = std::move(next);
        lambda *= 0.25;
        if (delta.head<3>().norm() < config.min_step_translation && delta.tail<3>().norm() < config.min_step_rotation) break;
      } else if (lambda > 1e4) {
        break;  // no step lowers the cost: converged as far as this level allows
      } else {
        lambda = lambda == 0 ? 1e-3 : lambda * 10;
      }
    }
    if (config.estimate_brightness && !finest)
      gain = fit_gain(normal.intensities, config.t_dof, gain);
    if (finest) {
      result.information = normal.h;
      result.overlap = ref.points.empty() ? 0 : static_cast<double>(normal.seen) / static_cast<double>(ref.points.size());
      result.intensity_scale = intensity_scale;
      result.depth_scale = depth_scale;
      result.depth_spread = 1.4826 * std::sqrt(normal.depth_median_square);  // a normal's sigma
      result.gain = gain;
    }
  }
  result.T_cur_ref = T;
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eigen(result.information);
  const double largest = eigen.eigenvalues().maxCoeff(), smallest = eigen.eigenvalues().minCoeff();
  if (!T.matrix().allFinite()) {
    result.reason = "the estimate is not finite";
  } else if (result.overlap < config.min_overlap) {
    result.reason = "overlap " + std::to_string(result.overlap) + " below " + std::to_string(config.min_overlap);
  } else if (!(largest > 0) || smallest < config.min_conditioning * largest) {
    result.reason = "degenerate: geometry and texture do not constrain every direction of motion";
  }
  result.converged = result.reason.empty();
  return result;
}

}  // namespace tracking
