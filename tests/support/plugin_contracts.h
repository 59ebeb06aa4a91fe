// Contract tests every plugin of a kind runs: parametrised gtest over the plugins the host finds.
//
// Plugins are loaded exactly as the app loads them: a PluginHost over the build's plugin folder
// (RSVIO_PLUGIN_DIR), params validated against the plugin's own table with rsvio::validateParams,
// then host.create<I>(). A new plugin is picked up by the contract suites with no edit here.
//
// Fixtures carried by each plugin: plugins/<kind>/<name>/contract.json (optional for shutters and
// solvers, REQUIRED for cameras, which need a calibration they can represent):
//   {"cases": [{"name": "radtan", "params": {...},
//               "calibration": {"projection": "pinhole", "distortion": "radtan", "width": 320, "height": 256,
//                               "intrinsics": [fx, fy, cx, cy], "distortion_coeffs": [...],
//                               "line_delay_s": 2e-5, "readout": "top_down"}}]}
// Missing calibration fields take the values of defaultContractCalibration().
//
// The suites are instantiated once per kind in tests/plugins/<kind>/*_contract_test.cpp, e.g.
//   class CameraContract : public ::testing::TestWithParam<ContractCase> {};
//   TEST_P(CameraContract, RoundTrip) { checkCameraRoundTrip(*makeContractPlugin<CameraModel>(GetParam())); }
//   INSTANTIATE_TEST_SUITE_P(AllCameraPlugins, CameraContract,
//                            ::testing::ValuesIn(contractCases(PluginKind::Camera, true)), contractCaseName);
// so a new plugin of a kind runs them by being built; nothing to add. A new kind adds its checks here.
// Plugin-specific tests use makePlugin<I>(name, params) the same way.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/QR>
#include <Eigen/SparseCore>
#include <cctype>
#include <cmath>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "rsvio/config/validate.h"
#include "rsvio/core/error.h"
#include "rsvio/core/types.h"
#include "rsvio/interfaces/camera.h"
#include "rsvio/interfaces/shutter.h"
#include "rsvio/interfaces/solver.h"
#include "rsvio/plugin/host.h"
#include "support/numeric_jacobian.h"

namespace rsvio::test {

// One host per test process over the build's plugin folder (libraries stay loaded anyway).
inline PluginHost& contractHost() {
  static PluginHost host({RSVIO_PLUGIN_DIR});
  return host;
}

// Validates params against the plugin's table as a config slot would be, then creates the plugin.
// Throws ConfigError listing every problem.
template <class I>
std::unique_ptr<I> makePlugin(const std::string& name, const nlohmann::json& params = nlohmann::json::object(),
                              PluginHost& host = contractHost()) {
  const std::string path = name + ".params";
  std::vector<ConfigProblem> problems;
  const nlohmann::json effective = validateParams(params, host.info(name).params, path, problems);
  if (!problems.empty()) {
    std::string msg;
    for (const auto& p : problems) msg += (msg.empty() ? "" : "\n") + p.str();
    throw ConfigError(msg);
  }
  return host.create<I>(name, Params(effective, path), path);
}

// 320x256 pinhole without distortion, rolling shutter of 20 us per row read top-down.
inline CameraCalibration defaultContractCalibration() {
  CameraCalibration c;
  c.projection = "pinhole";
  c.distortion = "none";
  c.width = 320;
  c.height = 256;
  c.intrinsics = Eigen::Vector4d(250.0, 250.0, 159.5, 127.5);
  c.distortion_coeffs = Eigen::VectorXd();
  c.line_delay_s = 2e-5;
  c.readout = "top_down";
  return c;
}

inline CameraCalibration calibrationFromJson(const nlohmann::json& j) {
  CameraCalibration c = defaultContractCalibration();
  c.projection = j.value("projection", c.projection);
  c.distortion = j.value("distortion", c.distortion);
  c.width = j.value("width", c.width);
  c.height = j.value("height", c.height);
  if (j.contains("intrinsics")) {
    const auto v = j.at("intrinsics").get<std::vector<double>>();
    if (v.size() != 4) throw ConfigError("contract calibration: intrinsics needs 4 values");
    c.intrinsics = Eigen::Vector4d(v[0], v[1], v[2], v[3]);
  }
  if (j.contains("distortion_coeffs")) {
    const auto v = j.at("distortion_coeffs").get<std::vector<double>>();
    c.distortion_coeffs = Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
  }
  c.line_delay_s = j.value("line_delay_s", c.line_delay_s);
  c.readout = j.value("readout", c.readout);
  return c;
}

struct ContractCase {
  std::string plugin;  // "kind.name"
  std::string label;   // case name from contract.json, or "default"
  nlohmann::json params = nlohmann::json::object();
  CameraCalibration calib = defaultContractCalibration();
  std::string error;   // the case could not be set up; the test fails with this message
};

inline std::ostream& operator<<(std::ostream& os, const ContractCase& c) { return os << c.plugin << "/" << c.label; }

// plugins/<kind>/<name>/contract.json of "kind.name".
inline std::string contractFilePath(const std::string& plugin) {
  const auto dot = plugin.find('.');
  return std::string(RSVIO_SOURCE_DIR) + "/plugins/" + plugin.substr(0, dot) + "/" + plugin.substr(dot + 1) +
         "/contract.json";
}

// Every plugin of `kind` the host finds, times the cases of its contract.json. A missing file gives
// one "default" case, or, when require_file, a case that fails naming the file to write.
inline std::vector<ContractCase> contractCases(PluginKind kind, bool require_file = false) {
  std::vector<ContractCase> out;
  for (const auto& name : contractHost().available(kind)) {
    const std::string path = contractFilePath(name);
    std::ifstream in(path);
    if (!in) {
      ContractCase c{name, "default"};
      if (require_file) c.error = path + " is missing: every " + kindName(kind) + " plugin carries its contract cases";
      out.push_back(c);
      continue;
    }
    try {
      const nlohmann::json j = nlohmann::json::parse(in);
      for (const auto& jc : j.at("cases")) {
        ContractCase c{name, jc.value("name", "case" + std::to_string(out.size()))};
        c.params = jc.value("params", nlohmann::json::object());
        if (jc.contains("calibration")) c.calib = calibrationFromJson(jc.at("calibration"));
        out.push_back(c);
      }
    } catch (const std::exception& e) {
      out.push_back(ContractCase{name, "broken", nlohmann::json::object(), defaultContractCalibration(),
                                 path + ": " + e.what()});
    }
  }
  return out;
}

// gtest parameter names: "camera_pinhole_radtan".
inline std::string contractCaseName(const ::testing::TestParamInfo<ContractCase>& info) {
  std::string s = info.param.plugin + "_" + info.param.label;
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s;
}

// ---------------------------------------------------------------------------------------------
// Contract checks, one function per property; each uses only its kind's interface.
// ---------------------------------------------------------------------------------------------

// Builds the case's plugin (validated params) and gives it the case's calibration.
template <class I>
std::unique_ptr<I> makeContractPlugin(const ContractCase& c) {
  if (!c.error.empty()) throw Error(c.error);
  auto p = makePlugin<I>(c.plugin, c.params);
  p->setCalibration(c.calib);
  return p;
}

// ---- camera.* ---------------------------------------------------------------------------------

// A grid of pixels over the whole image, borders included.
inline Eigen::Matrix2Xd contractPixelGrid(const CameraModel& cam, int steps) {
  Eigen::Matrix2Xd px(2, (steps + 1) * (steps + 1));
  int k = 0;
  for (int j = 0; j <= steps; ++j)
    for (int i = 0; i <= steps; ++i)
      px.col(k++) = Eigen::Vector2d(i * (cam.width() - 1.0) / steps, j * (cam.height() - 1.0) / steps);
  return px;
}

// unproject then project at two depths gives the pixel back (1e-6 px); >= 90% of the image is valid;
// bearings are unit vectors; the single-point calls agree with the batch calls.
inline void checkCameraRoundTrip(const CameraModel& cam) {
  const Eigen::Matrix2Xd px = contractPixelGrid(cam, 16);
  Eigen::Matrix3Xd b;
  std::vector<uint8_t> valid;
  cam.unproject(px, b, valid);
  ASSERT_EQ(valid.size(), static_cast<size_t>(px.cols()));
  int n_valid = 0;
  for (Eigen::Index i = 0; i < px.cols(); ++i) n_valid += valid[static_cast<size_t>(i)] ? 1 : 0;
  EXPECT_GE(n_valid, 0.9 * px.cols()) << "most of the image must unproject";
  for (double depth : {0.5, 4.0}) {
    Eigen::Matrix2Xd back;
    std::vector<uint8_t> valid_back;
    cam.project(Eigen::Matrix3Xd(b * depth), back, valid_back);
    for (Eigen::Index i = 0; i < px.cols(); ++i) {
      if (!valid[static_cast<size_t>(i)]) continue;
      EXPECT_NEAR(b.col(i).norm(), 1.0, 1e-9);
      EXPECT_TRUE(valid_back[static_cast<size_t>(i)]) << "pixel " << px.col(i).transpose();
      EXPECT_LT((back.col(i) - px.col(i)).norm(), 1e-6) << "pixel " << px.col(i).transpose() << " depth " << depth;
      Vec2 uv1;
      Vec3 b1;
      EXPECT_TRUE(cam.project(Vec3(b.col(i) * depth), uv1));
      EXPECT_TRUE(cam.unproject(Vec2(px.col(i)), b1));
      EXPECT_LT((uv1 - back.col(i)).norm(), 1e-12);
      EXPECT_LT((b1 - b.col(i)).norm(), 1e-12);
    }
  }
}

// d uv / d p and d bearing / d uv against central differences over the image.
inline void checkCameraJacobians(const CameraModel& cam) {
  const Eigen::Matrix2Xd px = contractPixelGrid(cam, 6);
  Eigen::Matrix3Xd b;
  std::vector<uint8_t> valid;
  std::vector<Jac32> d_b_d_uv;
  cam.unproject(px, b, valid, &d_b_d_uv);
  Eigen::Matrix3Xd p = b * 2.0;
  p.row(0).array() += 0.05;  // off the unprojection rays, so d uv / d p is not only checked on them
  Eigen::Matrix2Xd uv;
  std::vector<uint8_t> valid_p;
  std::vector<Jac23> d_uv_d_p;
  cam.project(p, uv, valid_p, &d_uv_d_p);
  ASSERT_EQ(d_uv_d_p.size(), static_cast<size_t>(p.cols()));
  ASSERT_EQ(d_b_d_uv.size(), static_cast<size_t>(px.cols()));
  int checked = 0;
  for (Eigen::Index i = 0; i < px.cols(); ++i) {
    const size_t s = static_cast<size_t>(i);
    if (!valid[s] || !valid_p[s]) continue;
    const auto f_proj = [&](const Vec3& q) {
      Vec2 r;
      cam.project(q, r);
      return r;
    };
    EXPECT_JACOBIAN_NEAR_TOL(d_uv_d_p[s], numericJacobian(f_proj, Vec3(p.col(i)), vectorPlus, 3), 1e-6, 1e-6)
        << "at p = " << p.col(i).transpose();
    const auto f_unproj = [&](const Vec2& q) {
      Vec3 r;
      cam.unproject(q, r);
      return r;
    };
    EXPECT_JACOBIAN_NEAR_TOL(d_b_d_uv[s], numericJacobian(f_unproj, Vec2(px.col(i)), vectorPlus, 2, 1e-3), 1e-6,
                             1e-9)
        << "at uv = " << px.col(i).transpose();
    ++checked;
  }
  EXPECT_GE(checked, 0.9 * px.cols());
}

// Points behind the camera, on its plane or NaN are flagged per column of a mixed batch.
inline void checkCameraInvalidPoints(const CameraModel& cam) {
  Eigen::Matrix3Xd p(3, 6);
  p.col(0) = Vec3(0.0, 0.0, 1.0);
  p.col(1) = Vec3(0.1, 0.2, -1.0);
  p.col(2) = Vec3(0.0, 0.0, 0.0);
  p.col(3) = Vec3(0.3, -0.1, -0.01);
  p.col(4) = Vec3(std::nan(""), 0.0, 1.0);
  p.col(5) = Vec3(0.1, 0.1, 3.0);
  Eigen::Matrix2Xd uv;
  std::vector<uint8_t> valid;
  std::vector<Jac23> J;
  cam.project(p, uv, valid, &J);
  ASSERT_EQ(valid.size(), 6u);
  EXPECT_EQ(J.size(), 6u);
  const std::vector<uint8_t> expected = {1, 0, 0, 0, 0, 1};
  for (size_t i = 0; i < 6; ++i) EXPECT_EQ(valid[i] != 0, expected[i] != 0) << "column " << i;
  Vec2 q;
  EXPECT_FALSE(cam.project(Vec3(0.0, 0.0, -2.0), q));
}

// A calibration with a distortion name the plugin cannot know is refused with a ConfigError naming it.
inline void checkCameraRejectsUnknownDistortion(const ContractCase& c) {
  if (!c.error.empty()) throw Error(c.error);
  auto cam = makePlugin<CameraModel>(c.plugin, c.params);
  CameraCalibration calib = c.calib;
  calib.distortion = "no_such_distortion";
  try {
    cam->setCalibration(calib);
    ADD_FAILURE() << c.plugin << " accepted distortion \"no_such_distortion\"";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_distortion"), std::string::npos) << e.what();
  }
}

// ---- shutter.* --------------------------------------------------------------------------------

// rowTime(y0) = 0; rowTime is linear with slope rowTimeDerivative(); |slope| = lineDelay() >= 0; a
// global shutter has slope 0.
inline void checkShutterTiming(const ShutterModel& s, const CameraCalibration& calib) {
  const double y0 = calib.rowZero();
  const double slope = s.rowTimeDerivative();
  EXPECT_NEAR(s.rowTime(y0), 0.0, 1e-15);
  EXPECT_GE(s.lineDelay(), 0.0);
  EXPECT_NEAR(std::abs(slope), s.lineDelay(), 1e-18);
  for (double v : {-10.0, 0.0, 37.25, y0 + 1.0, calib.height - 1.0, calib.height + 20.0}) {
    EXPECT_NEAR(s.rowTime(v + 0.5) - s.rowTime(v - 0.5), slope, 1e-15) << "row " << v;
    EXPECT_NEAR(s.rowTime(v), slope * (v - y0), 1e-15) << "row " << v;
  }
  if (!s.isRolling()) {
    EXPECT_EQ(slope, 0.0);
    EXPECT_EQ(s.lineDelay(), 0.0);
  } else {
    EXPECT_GT(s.lineDelay(), 0.0) << "the contract calibration has a line delay";
  }
}

// setLineDelay changes a rolling shutter's slope (keeping its sign) and leaves a global one alone.
inline void checkShutterSetLineDelay(ShutterModel& s, const CameraCalibration& calib) {
  const double sign = s.rowTimeDerivative() < 0.0 ? -1.0 : 1.0;
  s.setLineDelay(3.5e-5);
  if (s.isRolling()) {
    EXPECT_DOUBLE_EQ(s.lineDelay(), 3.5e-5);
    EXPECT_DOUBLE_EQ(s.rowTimeDerivative(), sign * 3.5e-5);
  } else {
    EXPECT_EQ(s.lineDelay(), 0.0);
    EXPECT_EQ(s.rowTimeDerivative(), 0.0);
  }
  EXPECT_NEAR(s.rowTime(calib.rowZero()), 0.0, 1e-15);
}

// ---- solver.* ---------------------------------------------------------------------------------

inline Eigen::MatrixXd randomSpd(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < n * n; ++i) A.data()[i] = g(rng);
  return A * A.transpose() + 0.1 * n * Eigen::MatrixXd::Identity(n, n);
}

// Random SPD systems (dense and sparse) solved to 1e-9 relative.
inline void checkSolverSolvesSpd(SolverBackend& solver) {
  std::mt19937 rng(11);
  std::normal_distribution<double> g;
  for (int n : {1, 6, 40}) {
    const Eigen::MatrixXd H = randomSpd(n, 100u + static_cast<unsigned>(n));
    Eigen::VectorXd x_true(n);
    for (int i = 0; i < n; ++i) x_true[i] = g(rng);
    const Eigen::VectorXd b = H * x_true;
    Eigen::VectorXd x;
    SolverStats stats;
    ASSERT_TRUE(solver.solveDense(H, b, x, &stats)) << "n = " << n << ": " << stats.message;
    ASSERT_EQ(x.size(), n);
    EXPECT_LT((H * x - b).norm() / b.norm(), 1e-9) << "n = " << n;
    EXPECT_LT((x - x_true).norm() / x_true.norm(), 1e-9) << "n = " << n;
  }
  // Sparse: a banded SPD system of 60 unknowns.
  const int n = 60;
  std::vector<Eigen::Triplet<double>> trip;
  for (int i = 0; i < n; ++i) {
    trip.emplace_back(i, i, 4.0 + 0.01 * i);
    if (i + 1 < n) {
      trip.emplace_back(i, i + 1, -1.0);
      trip.emplace_back(i + 1, i, -1.0);
    }
    if (i + 7 < n) {
      trip.emplace_back(i, i + 7, 0.5);
      trip.emplace_back(i + 7, i, 0.5);
    }
  }
  Eigen::SparseMatrix<double> Hs(n, n);
  Hs.setFromTriplets(trip.begin(), trip.end());
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) b[i] = g(rng);
  Eigen::VectorXd x;
  SolverStats stats;
  ASSERT_TRUE(solver.solveSparse(Hs, b, x, &stats)) << stats.message;
  EXPECT_LT((Hs * x - b).norm() / b.norm(), 1e-9);
}

// Indefinite and exactly singular systems: false with a message, never a silent step.
inline void checkSolverRejectsIndefinite(SolverBackend& solver) {
  const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(randomSpd(5, 3)).householderQ();
  Eigen::VectorXd d(5);
  d << 3.0, 2.0, 1.0, -0.5, 4.0;
  const Eigen::MatrixXd indefinite = Q * d.asDiagonal() * Q.transpose();
  Eigen::MatrixXd singular = randomSpd(5, 4);
  singular.row(4).setZero();
  singular.col(4).setZero();
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(5);
  for (const Eigen::MatrixXd* H : std::vector<const Eigen::MatrixXd*>{&indefinite, &singular}) {
    SCOPED_TRACE(H == &indefinite ? "indefinite H (eigenvalue -0.5)" : "singular H (last row and column 0)");
    Eigen::VectorXd x;
    SolverStats stats;
    EXPECT_FALSE(solver.solveDense(*H, b, x, &stats)) << *H;
    EXPECT_FALSE(stats.message.empty());
    EXPECT_FALSE(solver.solveDense(*H, b, x, nullptr));
    EXPECT_FALSE(solver.solveSparse(Eigen::SparseMatrix<double>(H->sparseView()), b, x, &stats));
  }
}
}  // namespace rsvio::test
