// photometric.response: the camera response G between irradiance and pixel value (DSO's model
// I(x) = G(t V(x) B(x)), Engel et al. 2018, sec. 2.1).
//
// Contract (rsvio/interfaces/photometric.h)
// - Calibrated (the dataset ships pcalib.txt, SensorSetup::photometric.inverse_response: G^-1 with one
//   entry per raw value, 256 or 65536, strictly increasing): the table is rescaled to [0, 255] as DSO
//   does (G^-1 <- 255 (G^-1 - G^-1[0]) / (G^-1[N-1] - G^-1[0])), and correct() maps every working
//   value x (raw value scaled to 0..255) through it with linear interpolation between raw values:
//   k = x (N - 1) / 255. numParams() = 0, predict() is the identity. Apply before photometric.vignette.
// - Estimated (no calibration, or mode "estimate"): a gamma-like response on the 0..255 scale,
//     G(B) = 255 (B / 255)^g,  g > 0 (g = 1: linear),
//   with g offered for estimation through numParams()/params()/setParams(); correct() leaves the image
//   as it is and predict(B) = G(B) with d G / d B = g G / B and d G / d g = G ln(B / 255)
//   (B <= 0 predicts 0 with zero derivatives). The back end does not call these yet: the run warns
//   (Odometry) and g stays at its initial value.
#pragma once
#include <cmath>
#include <string>
#include <vector>

#include "rsvio/core/error.h"
#include "rsvio/interfaces/photometric.h"

namespace rsvio {

class ResponseModel : public PhotometricModel {
 public:
  enum class Mode { Auto, Calibrated, Estimate };

  ResponseModel(Mode mode, double initial_gamma, std::string where = "photometric.response")
      : mode_(mode), gamma_(initial_gamma), where_(std::move(where)) {}

  void setSensors(const SensorSetup& s) override {
    const std::vector<float>& G = s.photometric.inverse_response;
    table_.clear();
    if (mode_ == Mode::Estimate) return;
    if (G.empty()) {
      if (mode_ == Mode::Calibrated)
        throw ConfigError(where_ + ".params.mode: \"calibrated\" but the dataset has no response calibration "
                                   "(pcalib.txt); use \"auto\" or \"estimate\"");
      return;
    }
    const std::string file = s.photometric.response_path.empty() ? "inverse response" : s.photometric.response_path;
    if (G.size() != 256 && G.size() != 65536)
      throw DataError(where_ + ": " + file + " has " + std::to_string(G.size()) + " entries, expected 256 or 65536");
    const double lo = G.front(), hi = G.back();
    if (!(hi > lo)) throw DataError(where_ + ": " + file + " is not increasing");
    table_.resize(G.size());
    for (size_t i = 0; i < G.size(); ++i) table_[i] = static_cast<float>(255.0 * (G[i] - lo) / (hi - lo));
  }

  bool isCalibrated() const { return !table_.empty(); }

  // Working value (raw scaled to 0..255) -> irradiance on the 0..255 scale.
  float inverse(float x) const {
    const float n1 = static_cast<float>(table_.size() - 1);
    float k = x * n1 / 255.f;
    if (!(k > 0.f)) return table_.front();
    if (k >= n1) return table_.back();
    const int i = static_cast<int>(k);
    const float a = k - i;
    return (1.f - a) * table_[i] + a * table_[i + 1];
  }

  void correct(cv::Mat& image, const Frame&) const override {
    if (table_.empty()) return;
    for (int y = 0; y < image.rows; ++y) {
      float* row = image.ptr<float>(y);
      for (int x = 0; x < image.cols; ++x) row[x] = inverse(row[x]);
    }
  }

  int numParams() const override { return isCalibrated() ? 0 : 1; }
  Eigen::VectorXd params() const override {
    if (isCalibrated()) return Eigen::VectorXd();
    Eigen::VectorXd p(1);
    p[0] = gamma_;
    return p;
  }
  void setParams(const Eigen::VectorXd& p) override {
    if (isCalibrated()) return;
    if (p.size() != 1 || !(p[0] > 0.0))
      throw Error(where_ + ": setParams expects one gamma > 0");
    gamma_ = p[0];
  }

  double predict(double value, const Vec2& uv, double* d_value, Eigen::VectorXd* d_params) const override {
    if (isCalibrated()) return PhotometricModel::predict(value, uv, d_value, d_params);
    if (d_params) d_params->setZero(1);
    if (!(value > 0.0)) {
      if (d_value) *d_value = 0.0;
      return 0.0;
    }
    const double G = 255.0 * std::pow(value / 255.0, gamma_);
    if (d_value) *d_value = gamma_ * G / value;
    if (d_params) (*d_params)[0] = G * std::log(value / 255.0);
    return G;
  }

 private:
  Mode mode_;
  double gamma_;
  std::string where_;
  std::vector<float> table_;
};

}  // namespace rsvio
