// Helpers for the evaluation tests: synthetic trajectories and a per-test temporary folder.
#pragma once
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "rsvio/io/trajectory.h"

namespace rsvio::test {

// A smooth 3D trajectory (a Lissajous curve with turning orientation), n poses every dt_ns from t0_ns.
inline io::Trajectory lissajous(size_t n, int64_t dt_ns, int64_t t0_ns = 1'000'000'000'000LL) {
  io::Trajectory t;
  t.frame = io::PoseFrame::kBody;
  for (size_t i = 0; i < n; ++i) {
    const double s = 1e-9 * static_cast<double>(i) * static_cast<double>(dt_ns);
    io::StampedPose p;
    p.t_ns = t0_ns + static_cast<int64_t>(i) * dt_ns;
    p.p_W_X = Eigen::Vector3d(2.0 * std::sin(0.7 * s), 1.5 * std::sin(1.1 * s + 0.3), 0.5 * std::cos(0.5 * s));
    p.q_W_X = Eigen::AngleAxisd(0.4 * s, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.2 * std::sin(s), Eigen::Vector3d::UnitX());
    t.poses.push_back(p);
  }
  return t;
}

// T_est_gt applied to a whole trajectory: p' = s R p + t, q' = R q (the estimate lives in another world).
inline io::Trajectory transformed(const io::Trajectory& in, double s, const Eigen::Quaterniond& R, const Eigen::Vector3d& t) {
  io::Trajectory out = in;
  for (auto& p : out.poses) {
    p.p_W_X = s * (R * p.p_W_X) + t;
    p.q_W_X = R * p.q_W_X;
  }
  return out;
}

class TempDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("rsvio_eval_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string write(const std::string& rel, const std::string& text) const {
    const auto p = dir_ / rel;
    std::filesystem::create_directories(p.parent_path());
    std::ofstream(p) << text;
    return p.string();
  }
  std::string path(const std::string& rel) const { return (dir_ / rel).string(); }
  std::filesystem::path dir_;
};

}  // namespace rsvio::test
