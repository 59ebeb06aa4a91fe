// photometric.vignette: vignetting V(x) between irradiance and the sensor (DSO's model
// I(x) = G(t V(x) B(x)), Engel et al. 2018, sec. 2.1).
//
// Contract (rsvio/interfaces/photometric.h)
// - Calibrated (the dataset ships vignette.png, SensorSetup::photometric.vignette, raw image size,
//   values in [0, 1]): correct() divides every working image by max(V, min_value), so the images
//   the estimator sees are free of vignetting; numParams() = 0 and predict() is the identity.
//   Run this model after photometric.response (irradiance is linear; the raw values are not).
// - Estimated (no calibration, or mode "estimate"): a radial polynomial
//     V(r) = 1 + v1 r^2 + v2 r^4 + v3 r^6,   r = |uv - c| / r_max,
//   c = the calibration's principal point (cx, cy), r_max = the largest distance from c to an image
//   corner, so r is in [0, 1] over the image. correct() leaves the image untouched; the back end
//   estimates (v1, v2, v3) through numParams()/params()/setParams() and predicts the value a
//   vignette-free scene value `value` takes at raw pixel uv:
//     predict(value, uv) = V(r(uv)) * value,  d/d value = V,  d/d v_k = value * r^(2k).
#pragma once
#include <algorithm>
#include <cmath>
#include <string>

#include "rsvio/core/error.h"
#include "rsvio/interfaces/photometric.h"

namespace rsvio {

class VignetteModel : public PhotometricModel {
 public:
  enum class Mode { Auto, Calibrated, Estimate, Fixed };  // Fixed: `initial` applied as a calibration

  VignetteModel(Mode mode, double min_value, const Eigen::Vector3d& initial, std::string where = "photometric.vignette")
      : mode_(mode), min_value_(min_value), v_(initial), where_(std::move(where)) {}

  void setSensors(const SensorSetup& s) override {
    const CameraCalibration& cam = s.camera;
    centre_ = Vec2(cam.intrinsics[2], cam.intrinsics[3]);
    if (cam.width > 0 && cam.height > 0) {
      double r2 = 0;
      for (double x : {0.0, cam.width - 1.0})
        for (double y : {0.0, cam.height - 1.0}) r2 = std::max(r2, (Vec2(x, y) - centre_).squaredNorm());
      inv_r_max_ = r2 > 0 ? 1.0 / std::sqrt(r2) : 1.0;
    }
    const cv::Mat& V = s.photometric.vignette;
    calibrated_ = false;
    if (mode_ == Mode::Estimate) return;
    if (mode_ == Mode::Fixed) {
      // The polynomial `initial` (e.g. what `rsvio diagnose` estimated) used as a calibration: every
      // working image is divided by max(V(r), min_value).
      if (cam.width <= 0 || cam.height <= 0) throw ConfigError(where_ + ".params.mode: \"fixed\" needs the image size");
      inv_vignette_.create(cam.height, cam.width, CV_32FC1);
      for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x)
          inv_vignette_.at<float>(y, x) = static_cast<float>(1.0 / std::max(vignette(Vec2(x, y)), min_value_));
      calibrated_ = true;
      return;
    }
    if (V.empty()) {
      if (mode_ == Mode::Calibrated)
        throw ConfigError(where_ + ".params.mode: \"calibrated\" but the dataset has no vignette calibration "
                                   "(vignette.png); use \"auto\" or \"estimate\"");
      return;
    }
    if (V.type() != CV_32FC1 || (cam.width > 0 && (V.cols != cam.width || V.rows != cam.height)))
      throw DataError(where_ + ": vignette " + (s.photometric.vignette_path.empty() ? "" : s.photometric.vignette_path + " ") +
                      "is " + std::to_string(V.cols) + "x" + std::to_string(V.rows) + ", the camera " +
                      std::to_string(cam.width) + "x" + std::to_string(cam.height));
    cv::max(V, min_value_, inv_vignette_);
    cv::divide(1.0, inv_vignette_, inv_vignette_);
    calibrated_ = true;
  }

  void correct(cv::Mat& image, const Frame&) const override {
    if (!calibrated_) return;
    if (image.size() != inv_vignette_.size())
      throw DataError(where_ + ": image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                      ", the vignette " + std::to_string(inv_vignette_.cols) + "x" + std::to_string(inv_vignette_.rows));
    cv::multiply(image, inv_vignette_, image);
  }

  bool isCalibrated() const { return calibrated_; }
  int numParams() const override { return calibrated_ ? 0 : 3; }
  Eigen::VectorXd params() const override { return calibrated_ ? Eigen::VectorXd() : Eigen::VectorXd(v_); }
  void setParams(const Eigen::VectorXd& p) override {
    if (calibrated_) return;
    if (p.size() != 3) throw Error(where_ + ": setParams expects 3 values, got " + std::to_string(p.size()));
    v_ = p;
  }

  double radius(const Vec2& uv) const { return (uv - centre_).norm() * inv_r_max_; }
  double vignette(const Vec2& uv) const {
    const double r2 = (uv - centre_).squaredNorm() * inv_r_max_ * inv_r_max_;
    return 1.0 + r2 * (v_[0] + r2 * (v_[1] + r2 * v_[2]));
  }

  double predict(double value, const Vec2& uv, double* d_value, Eigen::VectorXd* d_params) const override {
    if (calibrated_) return PhotometricModel::predict(value, uv, d_value, d_params);
    const double r2 = (uv - centre_).squaredNorm() * inv_r_max_ * inv_r_max_;
    const double V = 1.0 + r2 * (v_[0] + r2 * (v_[1] + r2 * v_[2]));
    if (d_value) *d_value = V;
    if (d_params) {
      d_params->resize(3);
      *d_params << value * r2, value * r2 * r2, value * r2 * r2 * r2;
    }
    return V * value;
  }

 private:
  Mode mode_;
  double min_value_;
  Eigen::Vector3d v_;
  std::string where_;
  bool calibrated_ = false;
  cv::Mat inv_vignette_;
  Vec2 centre_ = Vec2::Zero();
  double inv_r_max_ = 1.0;
};

}  // namespace rsvio
