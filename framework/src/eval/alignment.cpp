// Umeyama alignment (contract in rsvio/eval/alignment.h).
#include "rsvio/eval/alignment.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cctype>

#include "rsvio/core/error.h"

namespace rsvio::eval {

const char* alignModeName(AlignMode m) {
  switch (m) {
    case AlignMode::kSE3: return "se3";
    case AlignMode::kSim3: return "sim3";
    default: return "none";
  }
}

AlignMode parseAlignMode(const std::string& text, const std::string& option_name) {
  std::string t = text;
  std::transform(t.begin(), t.end(), t.begin(), [](unsigned char c) { return std::tolower(c); });
  if (t == "none") return AlignMode::kNone;
  if (t == "se3" || t == "se(3)") return AlignMode::kSE3;
  if (t == "sim3" || t == "sim(3)") return AlignMode::kSim3;
  throw ConfigError(option_name + " = '" + text + "': expected one of se3, sim3, none");
}

Alignment umeyamaAlignment(const Eigen::Matrix3Xd& p_est, const Eigen::Matrix3Xd& p_gt, AlignMode mode) {
  Alignment a;
  a.mode = mode;
  const Eigen::Index n = p_est.cols();
  if (p_gt.cols() != n) throw Error("alignment: estimate and ground truth have different numbers of positions");
  if (mode == AlignMode::kNone) {
    if (n < 1) throw Error("alignment: no associated pose pairs");
    return a;
  }
  if (n < 3) {
    throw Error(std::string("alignment ") + alignModeName(mode) + " needs at least 3 associated pose pairs, found " +
                std::to_string(n));
  }
  const Eigen::Vector3d mu_est = p_est.rowwise().mean();
  const Eigen::Vector3d mu_gt = p_gt.rowwise().mean();
  const Eigen::Matrix3Xd x = p_est.colwise() - mu_est;
  const Eigen::Matrix3Xd y = p_gt.colwise() - mu_gt;
  const double var_est = x.squaredNorm() / static_cast<double>(n);  // Umeyama eq. 36 (sigma_x^2)
  // Covariance Sigma_xy = 1/n sum (y - mu_y)(x - mu_x)^T (Umeyama eq. 38).
  const Eigen::Matrix3d sigma = y * x.transpose() / static_cast<double>(n);
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  // Eq. 39/43: flip the smallest singular direction when U V^T would be a reflection.
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) S(2, 2) = -1;
  a.R = svd.matrixU() * S * svd.matrixV().transpose();  // eq. 40
  if (mode == AlignMode::kSim3) {
    if (!(var_est > 1e-300)) throw Error("alignment sim3: all estimated positions are equal, scale is undefined");
    a.scale = (svd.singularValues().asDiagonal() * S).trace() / var_est;  // eq. 42
  }
  a.t = mu_gt - a.scale * a.R * mu_est;  // eq. 41
  return a;
}

}  // namespace rsvio::eval
