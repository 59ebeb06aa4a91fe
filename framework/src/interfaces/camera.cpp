// Single-point conveniences of CameraModel (interfaces/camera.h): one-column batches through the
// plugin's virtual batch calls. Meant for set-up code and tests, not for per-pixel loops.
#include "rsvio/interfaces/camera.h"

namespace rsvio {

bool CameraModel::project(const Vec3& p_c, Vec2& uv, Jac23* d_uv_d_p) const {
  Eigen::Matrix3Xd p(3, 1);
  p.col(0) = p_c;
  Eigen::Matrix2Xd q;
  std::vector<uint8_t> valid;
  std::vector<Jac23> J;
  project(p, q, valid, d_uv_d_p ? &J : nullptr);
  uv = q.col(0);
  if (d_uv_d_p) *d_uv_d_p = J[0];
  return valid[0] != 0;
}

bool CameraModel::unproject(const Vec2& uv, Vec3& bearing) const {
  Eigen::Matrix2Xd q(2, 1);
  q.col(0) = uv;
  Eigen::Matrix3Xd b;
  std::vector<uint8_t> valid;
  unproject(q, b, valid, nullptr);
  bearing = b.col(0);
  return valid[0] != 0;
}

}  // namespace rsvio
