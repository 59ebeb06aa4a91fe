// Seeded random samples and edge cases shared by the Lie-group tests. Every test draws from its own
// generator with a fixed seed, so failures reproduce exactly.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "rsvio/lie/lie.h"

namespace rsvio {
namespace lie_test {

constexpr int kSamples = 2000;       // random samples per property
constexpr int kJacobianSamples = 500;  // random samples per numeric-Jacobian check
constexpr double kPi = lie::pi<double>();

using Rng = std::mt19937_64;

inline double uniform(Rng& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

inline Eigen::Vector3d randomUnit(Rng& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Vector3d v;
  do {
    v = Eigen::Vector3d(n(rng), n(rng), n(rng));
  } while (v.norm() < 1e-3);
  return v.normalized();
}

// Axis uniform on the sphere, angle uniform in [0, max_angle).
inline Eigen::Vector3d randomRotationVector(Rng& rng, double max_angle = kPi) {
  return randomUnit(rng) * uniform(rng, 0.0, max_angle);
}

inline Eigen::Vector3d randomVector(Rng& rng, double half_width) {
  return Eigen::Vector3d(uniform(rng, -half_width, half_width), uniform(rng, -half_width, half_width),
                         uniform(rng, -half_width, half_width));
}

// Angles where the implementation switches branches or loses precision if done naively.
inline std::vector<double> edgeAngles() {
  return {0.0,  1e-300, 1e-15, 1e-12, 1e-10 * (1 - 1e-9), 1e-10 * (1 + 1e-9), 1e-9, 1e-6, 1e-4, 1e-2,
          0.5 * (1 - 1e-12), 0.5 * (1 + 1e-12), 1.0 * (1 - 1e-12), 1.0 * (1 + 1e-12), 2.0, 3.0,
          kPi - 1e-3, kPi - 1e-6, kPi - 1e-9, kPi};
}

// Edge angles along the coordinate axes and two generic directions.
inline std::vector<Eigen::Vector3d> edgeRotationVectors() {
  const std::vector<Eigen::Vector3d> axes = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                             Eigen::Vector3d::UnitZ(), Eigen::Vector3d(1, -2, 0.5).normalized(),
                                             Eigen::Vector3d(-0.3, 0.1, -0.9).normalized()};
  std::vector<Eigen::Vector3d> out;
  for (const auto& a : axes)
    for (double t : edgeAngles()) out.push_back(a * t);
  return out;
}

}  // namespace lie_test
}  // namespace rsvio
