// A CameraModel for the front-end tests: the typed pinhole model of camera.pinhole behind a minimal
// adapter (no plugin loading, so these tests exercise the framework alone), plus a RowTiming helper.
#pragma once
#include <memory>

#include "plugins/camera/pinhole/pinhole_model.h"
#include "rsvio/geometry/rs_projection.h"
#include "rsvio/interfaces/camera.h"
#include "synthetic_scene.h"

namespace rsvio::test {

class TestPinholeCamera : public CameraModel {
 public:
  using Model = pinhole::PinholeModel<double>;
  using D = pinhole::Distortion;

  explicit TestPinholeCamera(const PinholeK& K) {
    calib_.width = K.width;
    calib_.height = K.height;
    calib_.intrinsics << K.fx, K.fy, K.cx, K.cy;
    model_ = Model(calib_.intrinsics, Eigen::Vector4d::Zero(), 0.01);
  }

  void setCalibration(const CameraCalibration& c) override { calib_ = c; }
  const CameraCalibration& calibration() const override { return calib_; }
  using CameraModel::project;
  using CameraModel::unproject;

  void project(const Eigen::Matrix3Xd& p_c, Eigen::Matrix2Xd& uv, std::vector<uint8_t>& valid,
               std::vector<Jac23>* d_uv_d_p) const override {
    const Eigen::Index n = p_c.cols();
    uv.resize(2, n);
    valid.resize(static_cast<size_t>(n));
    if (d_uv_d_p) d_uv_d_p->resize(static_cast<size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) {
      Eigen::Vector2d q;
      valid[static_cast<size_t>(i)] =
          model_.project<D::kNone>(p_c.col(i), q, d_uv_d_p ? &(*d_uv_d_p)[static_cast<size_t>(i)] : nullptr);
      uv.col(i) = q;
    }
  }
  void unproject(const Eigen::Matrix2Xd& uv, Eigen::Matrix3Xd& bearing, std::vector<uint8_t>& valid,
                 std::vector<Jac32>* d_b_d_uv) const override {
    const Eigen::Index n = uv.cols();
    bearing.resize(3, n);
    valid.resize(static_cast<size_t>(n));
    if (d_b_d_uv) d_b_d_uv->resize(static_cast<size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) {
      Eigen::Vector3d b;
      valid[static_cast<size_t>(i)] =
          model_.unproject<D::kNone>(uv.col(i), b, d_b_d_uv ? &(*d_b_d_uv)[static_cast<size_t>(i)] : nullptr);
      bearing.col(i) = b;
    }
  }

 private:
  CameraCalibration calib_;
  Model model_;
};

inline PoseCW toPoseCW(const SE3d& T) { return PoseCW{T.rotationMatrix(), T.translation()}; }

}  // namespace rsvio::test
