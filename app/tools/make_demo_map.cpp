// Generates assets/demo_map.ply: a small procedural Gaussian map (a trefoil-knot tube over a
// checkered disc), so `scripts/run.sh` has a map to render with no third-party data.
// Deterministic: the same file on every machine.
#include <cmath>
#include <cstdio>
#include <random>

#include "io/ply_io.h"

namespace {

constexpr double kShC0 = 0.28209479177387814;

void add_splat(splat::Gaussians& g, const double p[3], double scale, const double rgb[3],
               double opacity, std::mt19937& rng) {
  std::normal_distribution<double> n01(0, 1);
  const std::size_t i = g.size();
  g.resize(i + 1);
  const int k = splat::sh_coeff_count(g.sh_degree);
  for (int a = 0; a < 3; ++a) {
    g.means[i * 3 + a] = static_cast<float>(p[a]);
    g.log_scales[i * 3 + a] = static_cast<float>(std::log(scale * (0.7 + 0.3 * std::abs(n01(rng)))));
  }
  for (int a = 0; a < 4; ++a) g.rotations[i * 4 + a] = static_cast<float>(n01(rng));
  g.opacity_logits[i] = static_cast<float>(std::log(opacity / (1 - opacity)));
  for (int c = 0; c < 3; ++c) g.sh[i * k * 3 + c] = static_cast<float>((rgb[c] - 0.5) / kShC0);
  // A little view-dependent sheen on degree 1.
  for (int c = 0; c < 3 * (k - 1); ++c) g.sh[i * k * 3 + 3 + c] = static_cast<float>(0.05 * n01(rng));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT.ply\n", argv[0]);
    return 2;
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u01(0, 1);
  splat::Gaussians g;
  g.sh_degree = 1;
  // Trefoil knot tube, coloured along its length.
  for (int s = 0; s < 9000; ++s) {
    const double t = 2 * M_PI * s / 9000.0;
    const double c[3] = {std::sin(t) + 2 * std::sin(2 * t), std::cos(t) - 2 * std::cos(2 * t), -std::sin(3 * t)};
    const double angle = 2 * M_PI * u01(rng), r = 0.28;
    const double p[3] = {0.3 * c[0] + r * 0.3 * std::cos(angle), 0.3 * c[1] + r * 0.3 * std::sin(angle),
                         0.45 + 0.3 * c[2] + 0.08 * std::cos(3 * angle)};
    const double rgb[3] = {0.5 + 0.45 * std::cos(t), 0.5 + 0.45 * std::cos(t + 2.1), 0.5 + 0.45 * std::cos(t + 4.2)};
    add_splat(g, p, 0.018, rgb, 0.85, rng);
  }
  // Checkered ground disc below it.
  for (int s = 0; s < 4000; ++s) {
    const double r = 1.3 * std::sqrt(u01(rng)), a = 2 * M_PI * u01(rng);
    const double p[3] = {r * std::cos(a), r * std::sin(a), -0.05};
    const bool dark = (static_cast<int>(std::floor(p[0] / 0.25)) + static_cast<int>(std::floor(p[1] / 0.25))) % 2 != 0;
    const double rgb[3] = {dark ? 0.2 : 0.85, dark ? 0.22 : 0.82, dark ? 0.25 : 0.75};
    add_splat(g, p, 0.03, rgb, 0.9, rng);
  }
  app::write_ply(argv[1], g);
  std::printf("wrote %zu Gaussians to %s\n", g.size(), argv[1]);
  return 0;
}
