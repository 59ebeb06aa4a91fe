// Minimal T_BS reader and body-to-camera mapping (contract in rsvio/eval/extrinsic.h).
#include "rsvio/eval/extrinsic.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <vector>

#include "rsvio/core/error.h"

namespace rsvio::eval {

Eigen::Isometry3d readSensorYamlTBS(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw DataError::at(path, 0, "cannot open file (needed for T_BS)");
  std::string line;
  long line_no = 0, key_line = 0;
  // State: 0 looking for "T_BS:", 1 looking for "data:", 2 inside "[ ... ]".
  int state = 0;
  std::string numbers;
  while (std::getline(in, line)) {
    ++line_no;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line = line.substr(0, hash);
    if (state == 0) {
      const auto k = line.find("T_BS:");
      if (k != std::string::npos && line.find_first_not_of(" \t") == k) {
        state = 1;
        key_line = line_no;
      }
      continue;
    }
    if (state == 1) {
      const auto d = line.find("data:");
      if (d == std::string::npos) continue;
      const auto b = line.find('[', d);
      if (b == std::string::npos) throw DataError::at(path, line_no, "T_BS: expected 'data: [' followed by 16 numbers");
      line = line.substr(b + 1);
      state = 2;
    }
    const auto e = line.find(']');
    numbers += " " + line.substr(0, e);
    if (e != std::string::npos) break;
  }
  if (state == 0) throw DataError::at(path, 0, "key 'T_BS' not found");
  if (state != 2) throw DataError::at(path, key_line, "T_BS has no 'data: [...]' list");
  std::vector<double> v;
  for (char& c : numbers) {
    if (c == ',') c = ' ';
  }
  const char* s = numbers.c_str();
  while (true) {
    char* end = nullptr;
    const double x = std::strtod(s, &end);
    if (end == s) break;
    v.push_back(x);
    s = end;
  }
  while (*s == ' ' || *s == '\t' || *s == '\r') ++s;
  if (*s != '\0') throw DataError::at(path, key_line, std::string("T_BS data: not a number near '") + s + "'");
  if (v.size() != 16) {
    throw DataError::at(path, key_line, "T_BS data: expected 16 numbers (4x4 row-major), found " + std::to_string(v.size()));
  }
  Eigen::Matrix4d M;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) M(r, c) = v[4 * r + c];
  if (!M.allFinite()) throw DataError::at(path, key_line, "T_BS data: non-finite value");
  if ((M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-9) {
    throw DataError::at(path, key_line, "T_BS data: last row must be 0 0 0 1");
  }
  const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3 || R.determinant() < 0) {
    throw DataError::at(path, key_line, "T_BS data: the rotation block is not a rotation (orthonormal, det +1)");
  }
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = svd.matrixU() * svd.matrixV().transpose();
  T.translation() = M.topRightCorner<3, 1>();
  return T;
}

io::Trajectory mapBodyToCamera(const io::Trajectory& body_traj, const Eigen::Isometry3d& T_B_C) {
  io::Trajectory out = body_traj;
  out.frame = io::PoseFrame::kCamera;
  const Eigen::Quaterniond q_B_C(T_B_C.linear());
  for (auto& p : out.poses) {
    p.p_W_X = p.p_W_X + p.q_W_X * T_B_C.translation();
    p.q_W_X = (p.q_W_X * q_B_C).normalized();
  }
  return out;
}

}  // namespace rsvio::eval
