// camera.pinhole: the thin virtual adapter over the typed PinholeModel (pinhole_model.h).
// The distortion is chosen by the calibration's `distortion` field; an unknown name is a ConfigError
// that names it (never a silent fallback to radtan).
#include <Eigen/Core>
#include <memory>
#include <string>

#include "pinhole_model.h"
#include "rsvio/core/error.h"
#include "rsvio/interfaces/camera.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

using pinhole::Distortion;
using Model = pinhole::PinholeModel<double>;

const char* kName = "camera.pinhole";

// Kalibr and OpenCV spell the same models differently; accept the well-known aliases.
bool parseDistortion(const std::string& name, Distortion& d, int& n_coeffs) {
  if (name == "none" || name.empty()) {
    d = Distortion::kNone;
    n_coeffs = 0;
  } else if (name == "radtan" || name == "radial-tangential" || name == "plumb_bob") {
    d = Distortion::kRadTan;
    n_coeffs = 4;
  } else if (name == "equidistant" || name == "fisheye") {
    d = Distortion::kEquidistant;
    n_coeffs = 4;
  } else {
    return false;
  }
  return true;
}

class PinholeCamera : public CameraModel {
 public:
  explicit PinholeCamera(const Params& p) : min_depth_m_(p.getDouble("min_depth_m")) {}

  void setCalibration(const CameraCalibration& calib) override {
    const std::string where = std::string(kName) + ": calibration";
    if (calib.projection != "pinhole") {
      throw ConfigError(where + " projection \"" + calib.projection + "\" is not supported (allowed: pinhole)");
    }
    Distortion d;
    int n = 0;
    if (!parseDistortion(calib.distortion, d, n)) {
      throw ConfigError(where + " distortion \"" + calib.distortion +
                        "\" is not supported (allowed: none, radtan, equidistant)");
    }
    const Eigen::VectorXd& c = calib.distortion_coeffs;
    Eigen::Vector4d k = Eigen::Vector4d::Zero();
    if (d == Distortion::kNone) {
      if (c.size() > 0 && c.cwiseAbs().maxCoeff() != 0.0) {
        throw ConfigError(where + " distortion \"none\" has non-zero coefficients");
      }
    } else if (c.size() == n) {
      k = c.head<4>();
    } else if (d == Distortion::kRadTan && c.size() == 5 && c[4] == 0.0) {
      k = c.head<4>();  // OpenCV's 5-coefficient form with k3 = 0
    } else {
      throw ConfigError(where + " distortion \"" + calib.distortion + "\" needs " + std::to_string(n) +
                        " coefficients, found " + std::to_string(c.size()));
    }
    const Eigen::Vector4d& K = calib.intrinsics;
    if (!(K[0] > 0.0 && K[1] > 0.0) || !K.allFinite() || !k.allFinite()) {
      throw ConfigError(where + " intrinsics must be finite with fx, fy > 0");
    }
    if (calib.width <= 0 || calib.height <= 0) {
      throw ConfigError(where + " image size must be positive, found " + std::to_string(calib.width) + "x" +
                        std::to_string(calib.height));
    }
    calib_ = calib;
    distortion_ = d;
    model_ = Model(K, k, min_depth_m_);
    has_calib_ = true;
  }

  const CameraCalibration& calibration() const override { return calib_; }

  using CameraModel::project;
  using CameraModel::unproject;

  void project(const Eigen::Matrix3Xd& p_c, Eigen::Matrix2Xd& uv, std::vector<uint8_t>& valid,
               std::vector<Jac23>* d_uv_d_p) const override {
    requireCalibration();
    switch (distortion_) {
      case Distortion::kNone: return projectBatch<Distortion::kNone>(p_c, uv, valid, d_uv_d_p);
      case Distortion::kRadTan: return projectBatch<Distortion::kRadTan>(p_c, uv, valid, d_uv_d_p);
      case Distortion::kEquidistant: return projectBatch<Distortion::kEquidistant>(p_c, uv, valid, d_uv_d_p);
    }
  }

  void unproject(const Eigen::Matrix2Xd& uv, Eigen::Matrix3Xd& bearing, std::vector<uint8_t>& valid,
                 std::vector<Jac32>* d_b_d_uv) const override {
    requireCalibration();
    switch (distortion_) {
      case Distortion::kNone: return unprojectBatch<Distortion::kNone>(uv, bearing, valid, d_b_d_uv);
      case Distortion::kRadTan: return unprojectBatch<Distortion::kRadTan>(uv, bearing, valid, d_b_d_uv);
      case Distortion::kEquidistant:
        return unprojectBatch<Distortion::kEquidistant>(uv, bearing, valid, d_b_d_uv);
    }
  }

 private:
  void requireCalibration() const {
    if (!has_calib_) throw Error(std::string(kName) + ": used before setCalibration()");
  }

  template <Distortion D>
  void projectBatch(const Eigen::Matrix3Xd& p_c, Eigen::Matrix2Xd& uv, std::vector<uint8_t>& valid,
                    std::vector<Jac23>* d_uv_d_p) const {
    const Eigen::Index n = p_c.cols();
    uv.resize(2, n);
    valid.assign(static_cast<size_t>(n), 0);
    if (d_uv_d_p) d_uv_d_p->resize(static_cast<size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) {
      Eigen::Vector2d q;
      Jac23* J = d_uv_d_p ? &(*d_uv_d_p)[static_cast<size_t>(i)] : nullptr;
      valid[static_cast<size_t>(i)] = model_.project<D>(p_c.col(i), q, J) ? 1 : 0;
      uv.col(i) = q;
    }
  }

  template <Distortion D>
  void unprojectBatch(const Eigen::Matrix2Xd& uv, Eigen::Matrix3Xd& bearing, std::vector<uint8_t>& valid,
                      std::vector<Jac32>* d_b_d_uv) const {
    const Eigen::Index n = uv.cols();
    bearing.resize(3, n);
    valid.assign(static_cast<size_t>(n), 0);
    if (d_b_d_uv) d_b_d_uv->assign(static_cast<size_t>(n), Jac32::Zero());
    for (Eigen::Index i = 0; i < n; ++i) {
      Eigen::Vector3d b = Eigen::Vector3d::Zero();
      Jac32* J = d_b_d_uv ? &(*d_b_d_uv)[static_cast<size_t>(i)] : nullptr;
      valid[static_cast<size_t>(i)] = model_.unproject<D>(uv.col(i), b, J) ? 1 : 0;
      bearing.col(i) = b;
    }
  }

  double min_depth_m_;
  CameraCalibration calib_;
  Distortion distortion_ = Distortion::kNone;
  Model model_;
  bool has_calib_ = false;
};

ParamTable pinholeParams() {
  return {paramDouble("min_depth_m", 1e-3, 1e-9, 1e3, "m",
                      "points closer than this along the optical axis are invalid (behind the camera)")};
}

void registerAll(PluginRegistrar& r) {
  r.add<CameraModel>({kName, PluginKind::Camera, "1.0.0",
                      "Pinhole camera of the raw image with distortion none, radtan (k1 k2 p1 p2) or "
                      "equidistant (Kannala-Brandt k1..k4), chosen by the calibration",
                      pinholeParams(), ""},
                     [](const Params& p) { return std::make_unique<PinholeCamera>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
