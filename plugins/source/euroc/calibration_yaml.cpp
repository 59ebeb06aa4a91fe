// EuRoC sensor.yaml and Kalibr camchain/IMU yaml (contract in calibration_yaml.h).
#include "calibration_yaml.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/SVD>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "rsvio/core/error.h"
#include "rsvio/io/csv.h"

namespace fs = std::filesystem;

namespace rsvio::euroc {
namespace {

// "path:line:col" of a node (yaml-cpp marks are 0-based; a node without a mark gives just "path").
std::string where(const std::string& path, const YAML::Node& node) {
  const YAML::Mark m = node.Mark();
  if (m.line < 0) return path;
  return path + ":" + std::to_string(m.line + 1) + ":" + std::to_string(m.column + 1);
}

DataError keyError(const std::string& path, const YAML::Node& node, const std::string& key, const std::string& msg) {
  return DataError(where(path, node) + ": key '" + key + "': " + msg);
}

std::string scalarText(const YAML::Node& n) {
  if (n.IsScalar()) return io::quoteFound(n.Scalar());
  if (n.IsSequence()) return "a list";
  if (n.IsMap()) return "a map";
  return "nothing";
}

YAML::Node loadYaml(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw DataError::at(path, 0, "calibration file not found");
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw DataError::at(path, 0, "cannot open calibration file");
  } catch (const YAML::Exception& e) {
    // yaml-cpp's message may end in the offending byte itself (a newline, a control byte): printable
    // escapes keep the message one line.
    std::string msg;
    for (const char c : e.msg) {
      const auto u = static_cast<unsigned char>(c);
      if (u >= 32 && u < 127) {
        msg += c;
      } else {
        char b[8];
        std::snprintf(b, sizeof(b), "\\x%02x", u);
        msg += b;
      }
    }
    // yaml-cpp's own position, passed on so the user lands on the offending character.
    if (e.mark.line >= 0)
      throw DataError(path + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1) +
                      ": invalid YAML: " + msg);
    throw DataError::at(path, 0, "invalid YAML: " + msg);
  }
}

void requireMap(const std::string& path, const YAML::Node& n, const std::string& what) {
  if (!n.IsMap())
    throw DataError(where(path, n) + ": expected " + what + " to be a map of keys, found " + scalarText(n));
}

// The child `key` of map `parent` (undefined node when absent; const access never inserts).
YAML::Node child(const YAML::Node& parent, const std::string& key) {
  const YAML::Node& p = parent;
  return p[key];
}

YAML::Node require(const std::string& path, const YAML::Node& parent, const std::string& key,
                   const std::string& context) {
  YAML::Node n = child(parent, key);
  if (!n.IsDefined() || n.IsNull())
    throw DataError(where(path, parent) + ": missing key '" + key + "'" + (context.empty() ? "" : " in " + context));
  return n;
}

double toDouble(const std::string& path, const YAML::Node& n, const std::string& key) {
  if (!n.IsScalar()) throw keyError(path, n, key, "expected a number, found " + scalarText(n));
  const auto v = io::parseDouble(n.Scalar());
  if (!v) throw keyError(path, n, key, "expected a number, found " + scalarText(n));
  if (!std::isfinite(*v)) throw keyError(path, n, key, "expected a finite number, found " + scalarText(n));
  return *v;
}

std::vector<double> toDoubles(const std::string& path, const YAML::Node& n, const std::string& key, int size,
                              const std::string& names) {
  if (!n.IsSequence()) throw keyError(path, n, key, "expected a list of numbers " + names + ", found " + scalarText(n));
  std::vector<double> v;
  for (size_t i = 0; i < n.size(); ++i) v.push_back(toDouble(path, n[i], key + "[" + std::to_string(i) + "]"));
  if (size >= 0 && static_cast<int>(v.size()) != size)
    throw keyError(path, n, key, "expected " + std::to_string(size) + " numbers " + names + ", found " +
                                     std::to_string(v.size()));
  return v;
}

// 4x4 transform from EuRoC's {rows, cols, data[16]}, Kalibr's 4 lists of 4, or a flat list of 16.
Eigen::Isometry3d toTransform(const std::string& path, const YAML::Node& n, const std::string& key) {
  std::vector<double> d;
  if (n.IsMap()) {
    const YAML::Node data = require(path, n, "data", "'" + key + "'");
    d = toDoubles(path, data, key + ".data", 16, "(row-major 4x4)");
  } else if (n.IsSequence() && n.size() == 4 && n[0].IsSequence()) {
    for (size_t r = 0; r < 4; ++r) {
      const auto row = toDoubles(path, n[r], key + "[" + std::to_string(r) + "]", 4, "(one row of a 4x4 matrix)");
      d.insert(d.end(), row.begin(), row.end());
    }
  } else {
    d = toDoubles(path, n, key, 16, "(a 4x4 matrix)");
  }
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = d[4 * r + c];
  if ((m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6)
    throw keyError(path, n, key, "last row of the 4x4 transform must be [0, 0, 0, 1]");
  const Eigen::Matrix3d R = m.topLeftCorner<3, 3>();
  const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  // Published files print rotations to ~8 digits; anything far off is a wrong matrix, not rounding.
  if (err > 1e-4 || R.determinant() < 0) {
    char buf[120];
    std::snprintf(buf, sizeof(buf), "rotation part is not a rotation (max |R^T R - I| = %.3g, det = %.3g)", err,
                  R.determinant());
    throw keyError(path, n, key, buf);
  }
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = svd.matrixU() * svd.matrixV().transpose();
  T.translation() = m.topRightCorner<3, 1>();
  return T;
}

std::string distortionName(const std::string& path, const YAML::Node& n, const std::string& key) {
  if (!n.IsScalar()) throw keyError(path, n, key, "expected a distortion model name, found " + scalarText(n));
  const std::string s = n.Scalar();
  if (s == "radial-tangential" || s == "radtan" || s == "plumb_bob") return "radtan";
  if (s == "equidistant" || s == "equi" || s == "fisheye") return "equidistant";
  if (s == "none" || s.empty()) return "none";
  throw keyError(path, n, key, "unsupported distortion model " + io::quoteFound(s) +
                                   " (supported: radial-tangential/radtan, equidistant/equi, none)");
}

void readDistortion(const std::string& path, const YAML::Node& cam, const std::string& model_key,
                    const std::string& coeff_key, CameraCalibration& c) {
  const YAML::Node model = child(cam, model_key);
  const YAML::Node coeffs = child(cam, coeff_key);
  if (!model.IsDefined() || model.IsNull()) {
    if (coeffs.IsDefined() && coeffs.IsSequence() && coeffs.size() > 0)
      throw DataError(where(path, coeffs) + ": key '" + coeff_key + "' given without '" + model_key + "'");
    c.distortion = "none";
    c.distortion_coeffs.resize(0);
    return;
  }
  c.distortion = distortionName(path, model, model_key);
  if (c.distortion == "none") {
    // Writers often pad "none" with zeros; any non-zero coefficient contradicts the model name.
    if (coeffs.IsDefined() && !coeffs.IsNull())
      for (double k : toDoubles(path, coeffs, coeff_key, -1, "[]"))
        if (k != 0.0) throw keyError(path, coeffs, coeff_key, "non-zero coefficients with distortion model 'none'");
    c.distortion_coeffs.resize(0);
    return;
  }
  const std::string names = c.distortion == "radtan" ? "[k1, k2, p1, p2]" : "[k1, k2, k3, k4]";
  const auto v = toDoubles(path, require(path, cam, coeff_key, ""), coeff_key, 4, names);
  c.distortion_coeffs = Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

void readIntrinsicsAndSize(const std::string& path, const YAML::Node& cam, const std::string& ctx,
                           CameraCalibration& c) {
  const YAML::Node model = child(cam, "camera_model");
  if (model.IsDefined() && !model.IsNull()) {
    if (!model.IsScalar() || model.Scalar() != "pinhole")
      throw keyError(path, model, "camera_model", "unsupported camera model " + scalarText(model) + " (supported: pinhole)");
  }
  const auto k = toDoubles(path, require(path, cam, "intrinsics", ctx), "intrinsics", 4, "[fu, fv, cu, cv]");
  const YAML::Node intr = child(cam, "intrinsics");
  if (!(k[0] > 0 && k[1] > 0)) throw keyError(path, intr, "intrinsics", "focal lengths fu, fv must be > 0");
  c.intrinsics = Eigen::Vector4d(k[0], k[1], k[2], k[3]);
  const YAML::Node res = require(path, cam, "resolution", ctx);
  const auto wh = toDoubles(path, res, "resolution", 2, "[width, height]");
  if (!(wh[0] >= 1 && wh[1] >= 1 && wh[0] == std::floor(wh[0]) && wh[1] == std::floor(wh[1]) && wh[0] < 1e5 &&
        wh[1] < 1e5))
    throw keyError(path, res, "resolution", "expected two positive integers [width, height]");
  c.width = static_cast<int>(wh[0]);
  c.height = static_cast<int>(wh[1]);
}

void readShutter(const std::string& path, const YAML::Node& cam, CameraCalibration& c) {
  struct Key {
    const char* name;
    double to_s;
  };
  static const Key kKeys[] = {{"line_delay", 1.0}, {"line_delay_s", 1.0}, {"line_delay_us", 1e-6}, {"line_delay_ns", 1e-9}};
  for (const Key& k : kKeys) {
    const YAML::Node n = child(cam, k.name);
    if (!n.IsDefined() || n.IsNull()) continue;
    const double v = toDouble(path, n, k.name) * k.to_s;
    if (v < 0 || v > 1e-3) throw keyError(path, n, k.name, "line delay must be in [0, 1 ms] per row");
    c.line_delay_s = v;
  }
  const YAML::Node r = child(cam, "readout");
  if (r.IsDefined() && !r.IsNull()) {
    if (!r.IsScalar() || (r.Scalar() != "top_down" && r.Scalar() != "bottom_up"))
      throw keyError(path, r, "readout", "expected top_down or bottom_up, found " + scalarText(r));
    c.readout = r.Scalar();
  }
}

double optionalPositive(const std::string& path, const YAML::Node& parent, const std::string& key, double def,
                        bool* found) {
  const YAML::Node n = child(parent, key);
  if (found) *found = n.IsDefined() && !n.IsNull();
  if (!n.IsDefined() || n.IsNull()) return def;
  const double v = toDouble(path, n, key);
  if (!(v > 0)) throw keyError(path, n, key, "must be > 0");
  return v;
}

ImuCalibration readImuNoise(const std::string& path, const YAML::Node& m, const char* rate_key,
                            std::vector<std::string>& warnings) {
  ImuCalibration out;
  std::string missing;
  auto get = [&](const char* key, double& dst) {
    bool found = false;
    dst = optionalPositive(path, m, key, dst, &found);
    if (!found) missing += std::string(missing.empty() ? "" : ", ") + key;
  };
  get("gyroscope_noise_density", out.noise.gyro_noise_density);
  get("gyroscope_random_walk", out.noise.gyro_random_walk);
  get("accelerometer_noise_density", out.noise.accel_noise_density);
  get("accelerometer_random_walk", out.noise.accel_random_walk);
  if (!missing.empty()) warnings.push_back(path + ": missing " + missing + "; using rsvio's defaults (EuRoC's ADIS16448 values)");
  out.noise.rate_hz = optionalPositive(path, m, rate_key, out.noise.rate_hz, &out.rate_found);
  return out;
}

// T_cam_imu of camera k, else chained through T_cn_cnm1 (which maps camera k-1's points into camera k)
// from the nearest camera before it that has one. (Nodes are never reassigned: yaml-cpp's Node::operator=
// rebinds the node inside the tree.)
std::optional<Eigen::Isometry3d> camImu(const std::string& path, const YAML::Node& root, const YAML::Node& ck, int k) {
  const YAML::Node tci = child(ck, "T_cam_imu");
  if (tci.IsDefined() && !tci.IsNull()) return toTransform(path, tci, "T_cam_imu");
  const YAML::Node tcc = child(ck, "T_cn_cnm1");
  if (k <= 0 || !tcc.IsDefined() || tcc.IsNull()) return std::nullopt;
  const YAML::Node prev = child(root, "cam" + std::to_string(k - 1));
  if (!prev.IsDefined() || !prev.IsMap()) return std::nullopt;
  const auto T_prev_imu = camImu(path, root, prev, k - 1);
  if (!T_prev_imu) return std::nullopt;
  return toTransform(path, tcc, "T_cn_cnm1") * *T_prev_imu;
}

}  // namespace

CameraCalibration readEurocCameraYaml(const std::string& path, std::vector<std::string>& warnings,
                                      bool* rate_hz_found) {
  const YAML::Node root = loadYaml(path);
  requireMap(path, root, "a camera sensor.yaml");
  CameraCalibration c;
  readIntrinsicsAndSize(path, root, "", c);
  readDistortion(path, root, "distortion_model", "distortion_coefficients", c);
  const YAML::Node tbs = child(root, "T_BS");
  if (tbs.IsDefined() && !tbs.IsNull()) {
    c.T_B_C = toTransform(path, tbs, "T_BS");
  } else {
    warnings.push_back(path + ": no T_BS; the camera-body extrinsic is taken as identity");
  }
  bool found = false;
  c.rate_hz = optionalPositive(path, root, "rate_hz", c.rate_hz, &found);
  if (rate_hz_found) *rate_hz_found = found;
  readShutter(path, root, c);
  const YAML::Node off = child(root, "time_offset_s");
  if (off.IsDefined() && !off.IsNull()) c.time_offset_s = toDouble(path, off, "time_offset_s");
  return c;
}

CameraCalibration readKalibrCamchain(const std::string& path, const std::string& camera,
                                     std::vector<std::string>& warnings) {
  const YAML::Node root = loadYaml(path);
  requireMap(path, root, "a Kalibr camchain");
  const YAML::Node cam = child(root, camera);
  if (!cam.IsDefined() || cam.IsNull()) {
    std::string found;
    for (const auto& kv : root)
      if (kv.first.IsScalar()) found += (found.empty() ? "" : ", ") + kv.first.Scalar();
    throw DataError::at(path, 0, "no camera '" + camera + "' in the camchain (found: " + (found.empty() ? "none" : found) + ")");
  }
  requireMap(path, cam, "'" + camera + "'");
  CameraCalibration c;
  readIntrinsicsAndSize(path, cam, "'" + camera + "'", c);
  readDistortion(path, cam, "distortion_model", "distortion_coeffs", c);
  readShutter(path, cam, c);

  int idx = -1;
  if (camera.size() > 3 && camera.compare(0, 3, "cam") == 0) {
    const auto n = io::parseInt64(camera.substr(3));
    if (n) idx = static_cast<int>(*n);
  }
  const std::optional<Eigen::Isometry3d> T_c_i = camImu(path, root, cam, idx);
  if (T_c_i) {
    c.T_B_C = T_c_i->inverse();
  } else {
    warnings.push_back(path + ": no T_cam_imu for '" + camera +
                       "' (a camera-only calibration?); the camera-IMU extrinsic is taken as identity");
  }
  const YAML::Node shift = child(cam, "timeshift_cam_imu");
  if (shift.IsDefined() && !shift.IsNull()) c.time_offset_s = toDouble(path, shift, "timeshift_cam_imu");
  return c;
}

ImuCalibration readImuYaml(const std::string& path, std::vector<std::string>& warnings) {
  const YAML::Node root = loadYaml(path);
  requireMap(path, root, "an IMU calibration");
  const YAML::Node imu0 = child(root, "imu0");
  const YAML::Node m = imu0.IsDefined() && !imu0.IsNull() ? imu0 : root;
  requireMap(path, m, "'imu0'");
  const bool euroc = child(m, "rate_hz").IsDefined();
  ImuCalibration imu = readImuNoise(path, m, euroc ? "rate_hz" : "update_rate", warnings);
  const YAML::Node tbs = child(m, "T_BS");
  if (tbs.IsDefined() && !tbs.IsNull()) imu.T_B_S = toTransform(path, tbs, "T_BS");
  return imu;
}

std::string detectCalibrationFormat(const std::string& path, const std::string& camera) {
  const YAML::Node root = loadYaml(path);
  if (!root.IsMap()) return "";
  if (child(root, "intrinsics").IsDefined()) return "euroc";
  const YAML::Node cam = child(root, camera);
  if (cam.IsDefined() && cam.IsMap()) return "kalibr";
  for (const auto& kv : root)
    if (kv.first.IsScalar() && kv.first.Scalar().rfind("cam", 0) == 0 && kv.second.IsMap()) return "kalibr";
  return "";
}

}  // namespace rsvio::euroc
