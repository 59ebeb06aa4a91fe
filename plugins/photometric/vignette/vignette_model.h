// photometric.vignette: vignetting V(x) between irradiance and the sensor (DSO's model
// I(x) = G(t V(x) B(x)), Engel et al. 2018, sec. 2.1).
//
// Contract (rsvio/interfaces/photometric.h)
// - Calibrated (the dataset ships vignette.png, SensorSetup::photometric.vignette, raw image size,
//   values in [0, 1]): correct() divides every working image by max(V, min_value), so the images
//   the estimator sees are free of vignetting; numParams() = 0 and predict() is the identity.
//   Run this model after photometric.response (irradiance is linear; the raw values are not).
// - Estimated online (no calibration with mode "auto", or mode "estimate"): a radial polynomial
//     V(r) = 1 + v1 r^2 + v2 r^4 + v3 r^6,   r = |uv - c| / r_max,
//   c = the calibration's principal point (cx, cy), r_max = the largest distance from c to an image
//   corner, so r is in [0, 1] over the image, starting at `initial`. correct() divides every working
//   image by max(V(r), min_value) with the current polynomial; refineFromResiduals() fits what the
//   residuals of images corrected with it still show (rsvio/photometric/vignette_fit.h, the rows' radii
//   rescaled from the half diagonal to r_max) and multiplies it in: V <- V * V_fit, refitted as one
//   polynomial. A fit that explains less than `min_gain` of the residuals' robust energy, or leaves V
//   implausible, changes nothing.
//   numParams() = 3 (params() is the current polynomial); predict() is the identity (the images carry
//   the correction).
// - Fixed (mode "fixed"): the polynomial `initial` divides every image, nothing is estimated.
#pragma once
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "rsvio/core/error.h"
#include "rsvio/interfaces/photometric.h"
#include "rsvio/photometric/vignette_fit.h"

namespace rsvio {

class VignetteModel : public PhotometricModel {
 public:
  enum class Mode { Auto, Calibrated, Estimate, Fixed };  // Fixed: `initial` applied as a calibration

  VignetteModel(Mode mode, double min_value, const Eigen::Vector3d& initial, std::string where = "photometric.vignette",
                size_t min_rows = 3000, double min_gain = 0.05)
      : mode_(mode), min_value_(min_value), v_(initial), where_(std::move(where)), min_rows_(min_rows),
        min_gain_(min_gain) {}

  void setSensors(const SensorSetup& s) override {
    const CameraCalibration& cam = s.camera;
    centre_ = Vec2(cam.intrinsics[2], cam.intrinsics[3]);
    if (cam.width > 0 && cam.height > 0) {
      double r2 = 0;
      for (double x : {0.0, cam.width - 1.0})
        for (double y : {0.0, cam.height - 1.0}) r2 = std::max(r2, (Vec2(x, y) - centre_).squaredNorm());
      inv_r_max_ = r2 > 0 ? 1.0 / std::sqrt(r2) : 1.0;
    }
    half_diag_ = 0.5 * std::hypot(cam.width, cam.height);
    const cv::Mat& V = s.photometric.vignette;
    calibrated_ = false;
    estimating_ = false;
    if (mode_ == Mode::Fixed || mode_ == Mode::Estimate || (mode_ == Mode::Auto && V.empty())) {
      // Fixed: the polynomial `initial` (e.g. what `rsvio diagnose` estimated) used as a calibration.
      // Estimated: the same division with the current polynomial, refined online.
      if (cam.width <= 0 || cam.height <= 0)
        throw ConfigError(where_ + ".params.mode: a polynomial vignette needs the image size");
      if (!plausibleVignette(v_)) {
        std::ostringstream os;
        os << where_ << ".params.initial: V(r) = 1 + " << v_[0] << " r^2 + " << v_[1] << " r^4 + " << v_[2]
           << " r^6 leaves (0.05, 1.5) between the centre and the corner";
        throw ConfigError(os.str());
      }
      size_ = cv::Size(cam.width, cam.height);
      buildInverse();
      calibrated_ = mode_ == Mode::Fixed;
      estimating_ = !calibrated_;
      return;
    }
    if (V.empty())
      throw ConfigError(where_ + ".params.mode: \"calibrated\" but the dataset has no vignette calibration "
                                 "(vignette.png); use \"auto\" or \"estimate\"");
    if (V.type() != CV_32FC1 || (cam.width > 0 && (V.cols != cam.width || V.rows != cam.height)))
      throw DataError(where_ + ": vignette " + (s.photometric.vignette_path.empty() ? "" : s.photometric.vignette_path + " ") +
                      "is " + std::to_string(V.cols) + "x" + std::to_string(V.rows) + ", the camera " +
                      std::to_string(cam.width) + "x" + std::to_string(cam.height));
    cv::max(V, min_value_, inv_vignette_);
    cv::divide(1.0, inv_vignette_, inv_vignette_);
    calibrated_ = true;
  }

  void correct(cv::Mat& image, const Frame&) const override {
    if (!calibrated_ && !estimating_) return;
    if (image.size() != inv_vignette_.size())
      throw DataError(where_ + ": image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                      ", the vignette " + std::to_string(inv_vignette_.cols) + "x" + std::to_string(inv_vignette_.rows));
    cv::multiply(image, inv_vignette_, image);
  }

  bool isCalibrated() const { return calibrated_; }
  bool estimatesOnline() const override { return estimating_; }
  size_t minRowsForRefine() const override { return min_rows_; }
  int updates() const { return updates_; }

  bool refineFromResiduals(const std::vector<ObservationRow>& rows, std::string* note) override {
    if (!estimating_) return false;
    // Rows normalise the radius by the half diagonal, this model by r_max.
    const VignetteFit fit = fitVignettePlausible(rows, half_diag_ * inv_r_max_);
    // A refinement must explain min_gain of the residual energy: a fit to what the window's pose and
    // depth errors leave on vignetting-free images explains 0-4 % (clean 640x512 runs).
    if (fit.rows < min_rows_ || !(fit.cost < (1.0 - min_gain_) * fit.cost_null)) return false;
    const Eigen::Vector3d next = vignetteProduct(v_, fit.k);
    if (!plausibleVignette(next)) return false;
    v_ = next;
    buildInverse();
    ++updates_;
    if (note) {
      std::ostringstream os;
      os.precision(3);
      os << "V(r) = 1 + " << v_[0] << " r^2 + " << v_[1] << " r^4 + " << v_[2] << " r^6 (corner "
         << vignetteValue(v_, 1.0) << "), from " << fit.rows << " residuals that showed a corner of "
         << vignetteValue(fit.k, 1.0) << ", energy " << fit.cost_null << " -> " << fit.cost;
      *note = os.str();
    }
    return true;
  }

  int numParams() const override { return calibrated_ ? 0 : 3; }
  Eigen::VectorXd params() const override { return calibrated_ ? Eigen::VectorXd() : Eigen::VectorXd(v_); }
  void setParams(const Eigen::VectorXd& p) override {
    if (calibrated_) return;
    if (p.size() != 3) throw Error(where_ + ": setParams expects 3 values, got " + std::to_string(p.size()));
    v_ = p;
    if (estimating_) buildInverse();
  }

  double radius(const Vec2& uv) const { return (uv - centre_).norm() * inv_r_max_; }
  double vignette(const Vec2& uv) const { return vignetteValue(v_, radius(uv)); }

  // The images carry the correction (calibrated, fixed or estimated): the identity, with zero
  // derivatives for the polynomial's parameters when it is estimated.
  double predict(double value, const Vec2& /*uv*/, double* d_value, Eigen::VectorXd* d_params) const override {
    if (d_value) *d_value = 1.0;
    if (d_params) d_params->setZero(numParams());
    return value;
  }

 private:
  Mode mode_;
  double min_value_;
  Eigen::Vector3d v_;
  std::string where_;
  size_t min_rows_;
  double min_gain_;
  bool calibrated_ = false;
  bool estimating_ = false;
  int updates_ = 0;
  double half_diag_ = 1.0;
  cv::Size size_;
  cv::Mat inv_vignette_;

  void buildInverse() {
    inv_vignette_.create(size_.height, size_.width, CV_32FC1);
    for (int y = 0; y < size_.height; ++y)
      for (int x = 0; x < size_.width; ++x)
        inv_vignette_.at<float>(y, x) = static_cast<float>(1.0 / std::max(vignette(Vec2(x, y)), min_value_));
  }
  Vec2 centre_ = Vec2::Zero();
  double inv_r_max_ = 1.0;
};

}  // namespace rsvio
