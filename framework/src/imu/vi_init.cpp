#include "rsvio/imu/vi_init.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "rsvio/core/time.h"
#include "rsvio/imu/preintegration.h"
#include "rsvio/imu/visual_inertial_factor.h"

namespace rsvio {

namespace {

std::string fmt(const char* f, double a, double b = 0.0, double c = 0.0, double d = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), f, a, b, c, d);
  return buf;
}

struct Pose {
  Mat3 R_wc;  // camera -> W_f rotation
  Vec3 c;     // camera centre in W_f (free units)
  Mat3 R_wi;  // IMU -> W_f rotation
};

std::vector<ImuPreintegration> preintegrateAll(const std::vector<ViInitKeyframe>& kfs, const ImuBuffer& imu,
                                               const ImuNoise& noise, const ImuBias& bias, double offset) {
  std::vector<ImuPreintegration> pre;
  for (size_t k = 0; k + 1 < kfs.size(); ++k)
    pre.push_back(ImuPreintegration::fromBuffer(imu, kfs[k].t_ns, kfs[k + 1].t_ns, noise, bias, offset));
  return pre;
}

// Step 1: b_g from relative rotations (the IMU's rotations in W_f do not depend on the scale).
Vec3 estimateGyroBias(const std::vector<ImuPreintegration>& pre, const std::vector<Pose>& poses, ImuBias bias,
                      int iterations) {
  for (int it = 0; it < iterations; ++it) {
    Mat3 H = Mat3::Zero();
    Vec3 g = Vec3::Zero();
    for (size_t k = 0; k < pre.size(); ++k) {
      const ImuPreintegration::Delta d = pre[k].corrected(bias);
      const SO3d R_ij(Mat3(poses[k].R_wi.transpose() * poses[k + 1].R_wi));
      const Vec3 r = (d.R.inverse() * R_ij).log();
      const Mat3 J = -SO3d::leftJacobianInverse(r) * SO3d::rightJacobian(d.phi) * pre[k].d_R_d_bg();
      H += J.transpose() * J;
      g += J.transpose() * r;
    }
    bias.gyro -= H.ldlt().solve(g);
  }
  return bias.gyro;
}

std::vector<Pose> posesOf(const std::vector<ViInitKeyframe>& kfs, const SE3d& T_cm_i) {
  std::vector<Pose> poses(kfs.size());
  const Mat3 R_ci = T_cm_i.rotationMatrix();
  for (size_t k = 0; k < kfs.size(); ++k) {
    const SE3d T_wf_cf = kfs[k].T_cf_wf.inverse();
    poses[k] = {T_wf_cf.rotationMatrix(), T_wf_cf.translation(), T_wf_cf.rotationMatrix() * R_ci};
  }
  return poses;
}

// estimateTimeOffset's cost of one candidate: the summed squared rotation residual after step 1's
// gyro bias fit; infinity where the IMU does not cover the keyframes at that offset.
double rotationCost(const std::vector<ViInitKeyframe>& kfs, const std::vector<Pose>& poses, const ImuBuffer& imu,
                    const ImuNoise& noise, ImuBias bias, double offset, int iterations) {
  const int64_t off_ns = sToNs(offset);
  if (!imu.covers(kfs.front().t_ns + off_ns, kfs.back().t_ns + off_ns)) return std::numeric_limits<double>::infinity();
  const std::vector<ImuPreintegration> pre = preintegrateAll(kfs, imu, noise, bias, offset);
  bias.gyro = estimateGyroBias(pre, poses, bias, iterations);
  double cost = 0.0;
  for (size_t k = 0; k < pre.size(); ++k) {
    const SO3d R_ij(Mat3(poses[k].R_wi.transpose() * poses[k + 1].R_wi));
    cost += (pre[k].corrected(bias).R.inverse() * R_ij).log().squaredNorm();
  }
  return cost;
}

// Whitening of one interval's (dv, dp) rows expressed in W_f axes: rows (vel; pos).
Eigen::Matrix<double, 6, 6> whitener(const ImuPreintegration& p, const Mat3& R_wi) {
  Eigen::Matrix<double, 6, 6> Rb = Eigen::Matrix<double, 6, 6>::Zero();
  Rb.block<3, 3>(0, 0) = R_wi;
  Rb.block<3, 3>(3, 3) = R_wi;
  Eigen::Matrix<double, 6, 6> C = Rb * p.covariance().block<6, 6>(3, 3) * Rb.transpose();
  C += 1e-12 * Eigen::Matrix<double, 6, 6>::Identity();
  const Eigen::Matrix<double, 6, 6> L = C.llt().matrixL();
  return L.inverse();
}

// Steps 2-3. Unknowns (V_0..V_{n-1} in W_f axes, metric; then gravity g_f (3) or its 2-dim tangent
// correction; then scale s). P_k = s c_k + R_wc,k t_ci is the IMU position in W_f axes, metres.
//   vel: V_j - V_i - g dt                          = R_i dv
//   pos: s (c_j - c_i) - V_i dt - 1/2 g dt^2       = R_i dp - (R_wc,j - R_wc,i) t_ci
struct LinearSystem {
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
};

LinearSystem buildLinear(const std::vector<ImuPreintegration>& pre, const std::vector<Pose>& poses, const Vec3& t_ci,
                         const ImuBias& bias, const Eigen::Matrix<double, 3, Eigen::Dynamic>& g_basis,
                         const Vec3& g_known) {
  const int n = static_cast<int>(poses.size());
  const int ng = static_cast<int>(g_basis.cols());
  const int dim = 3 * n + ng + 1;
  LinearSystem L{Eigen::MatrixXd::Zero(6 * (n - 1), dim), Eigen::VectorXd::Zero(6 * (n - 1))};
  for (int k = 0; k + 1 < n; ++k) {
    const double dt = pre[k].dt();
    const ImuPreintegration::Delta d = pre[k].corrected(bias);
    Eigen::Matrix<double, 6, Eigen::Dynamic> A = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, dim);
    Eigen::Matrix<double, 6, 1> b;
    const Mat3& Ri = poses[k].R_wi;
    A.block<3, 3>(0, 3 * k) = -Mat3::Identity();
    A.block<3, 3>(0, 3 * (k + 1)) = Mat3::Identity();
    A.block(0, 3 * n, 3, ng) = -g_basis * dt;
    b.head<3>() = Ri * d.v + g_known * dt;
    A.block<3, 3>(3, 3 * k) = -Mat3::Identity() * dt;
    A.block(3, 3 * n, 3, ng) = -0.5 * g_basis * dt * dt;
    A.block<3, 1>(3, 3 * n + ng) = poses[k + 1].c - poses[k].c;
    b.tail<3>() = Ri * d.p - (poses[k + 1].R_wc - poses[k].R_wc) * t_ci + 0.5 * g_known * dt * dt;
    const Eigen::Matrix<double, 6, 6> W = whitener(pre[k], Ri);
    L.A.middleRows<6>(6 * k) = W * A;
    L.b.segment<6>(6 * k) = W * b;
  }
  return L;
}

Eigen::Matrix<double, 3, 2> tangentBasis(const Vec3& g_dir) {
  Vec3 a = std::abs(g_dir.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 b1 = (a - g_dir * g_dir.dot(a)).normalized();
  Eigen::Matrix<double, 3, 2> B;
  B << b1, g_dir.cross(b1);
  return B;
}

// Step 4: Gauss-Newton on the full IMU factors over (omega_x, omega_y, sigma of T_Wm_Wf; v_k; b_g; b_a).
// omega_z (yaw about gravity) is the gauge and stays fixed.
void refineNonlinear(const std::vector<ImuPreintegration>& pre, const std::vector<ViInitKeyframe>& kfs,
                     const SE3d& T_cm_i, double offset, const ViInitOptions& opt, ViInitResult* res) {
  const int n = static_cast<int>(kfs.size());
  std::vector<ImuFactor> factors;
  for (const auto& p : pre) factors.emplace_back(p);
  std::vector<Mat15> sqrt_info;
  for (const auto& f : factors) sqrt_info.push_back(f.sqrtInformation());
  const double prior_w = 1.0 / opt.accel_bias_prior_sigma_m_s2;
  const int dim = 3 + 3 * n + 6;
  const int ib = 3 + 3 * n;  // first bias column

  auto cost = [&](const RxSO3d& S, const std::vector<Vec3>& v, const ImuBias& b) {
    double c = (prior_w * b.accel).squaredNorm();
    for (int k = 0; k + 1 < n; ++k) {
      const VisualInertialKeyframe ki{kfs[k].T_cf_wf, v[k], b}, kj{kfs[k + 1].T_cf_wf, v[k + 1], b};
      c += (sqrt_info[k] * visualInertialResidual(factors[k], ki, kj, S, T_cm_i, offset)).squaredNorm();
    }
    return c;
  };

  double c0 = cost(res->T_wm_wf, res->velocities_wm, res->bias);
  for (int it = 0; it < opt.nonlinear_iterations; ++it) {
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(dim, dim);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(dim);
    for (int k = 0; k + 1 < n; ++k) {
      const VisualInertialKeyframe ki{kfs[k].T_cf_wf, res->velocities_wm[k], res->bias};
      const VisualInertialKeyframe kj{kfs[k + 1].T_cf_wf, res->velocities_wm[k + 1], res->bias};
      VisualInertialJacobians J;
      const Vec15 r = sqrt_info[k] * visualInertialResidual(factors[k], ki, kj, res->T_wm_wf, T_cm_i, offset, &J);
      Eigen::Matrix<double, 15, Eigen::Dynamic> A = Eigen::Matrix<double, 15, Eigen::Dynamic>::Zero(15, dim);
      A.col(0) = J.d_res_d_T_wm_wf.col(0);
      A.col(1) = J.d_res_d_T_wm_wf.col(1);
      A.col(2) = J.d_res_d_T_wm_wf.col(3);
      A.middleCols<3>(3 + 3 * k) = J.d_res_d_vel_bias_i.leftCols<3>();
      A.middleCols<3>(3 + 3 * (k + 1)) = J.d_res_d_vel_bias_j.leftCols<3>();
      A.middleCols<6>(ib) = J.d_res_d_vel_bias_i.rightCols<6>() + J.d_res_d_vel_bias_j.rightCols<6>();
      A = sqrt_info[k] * A;
      H += A.transpose() * A;
      g += A.transpose() * r;
    }
    H.block<3, 3>(ib + 3, ib + 3) += prior_w * prior_w * Mat3::Identity();
    g.segment<3>(ib + 3) += prior_w * prior_w * res->bias.accel;
    const Eigen::VectorXd dx = H.ldlt().solve(-g);
    if (!dx.allFinite()) break;
    // Backtracking keeps the cost from increasing (the linear start can be far for weak excitation).
    bool accepted = false;
    for (double step = 1.0; step > 0.1 && !accepted; step *= 0.5) {
      const Eigen::VectorXd d = step * dx;
      Vec4 a;
      a << d[0], d[1], 0.0, d[2];
      const RxSO3d S = RxSO3d::exp(a) * res->T_wm_wf;
      std::vector<Vec3> v = res->velocities_wm;
      for (int k = 0; k < n; ++k) v[k] += d.segment<3>(3 + 3 * k);
      ImuBias b = res->bias;
      b.gyro += d.segment<3>(ib);
      b.accel += d.segment<3>(ib + 3);
      const double c1 = cost(S, v, b);
      if (c1 <= c0) {
        res->T_wm_wf = S;
        res->velocities_wm = v;
        res->bias = b;
        accepted = (c0 - c1) > 1e-10 * c0;
        c0 = c1;
        if (!accepted) return;  // converged
      }
    }
    if (!accepted) return;
  }
}

// Whitened IMU factor energy per interval at the result (poses fixed, one bias for all keyframes).
void measureFit(const std::vector<ImuPreintegration>& pre, const std::vector<ViInitKeyframe>& kfs,
                const SE3d& T_cm_i, double offset, ViInitResult* res) {
  double sum = 0.0, mx = 0.0;
  for (size_t k = 0; k + 1 < kfs.size(); ++k) {
    const ImuFactor f(pre[k]);
    const VisualInertialKeyframe ki{kfs[k].T_cf_wf, res->velocities_wm[k], res->bias};
    const VisualInertialKeyframe kj{kfs[k + 1].T_cf_wf, res->velocities_wm[k + 1], res->bias};
    const double e = (f.sqrtInformation() * visualInertialResidual(f, ki, kj, res->T_wm_wf, T_cm_i, offset)).squaredNorm();
    sum += e;
    mx = std::max(mx, e);
  }
  res->imu_chi2_mean = pre.empty() ? 0.0 : sum / static_cast<double>(pre.size());
  res->imu_chi2_max = mx;
}

}  // namespace

namespace {
ViInitResult solveInit(const std::vector<ViInitKeyframe>& kfs, const ImuBuffer& imu, const ImuNoise& noise,
                       const SE3d& T_cm_i, double offset, const ViInitOptions& opt);
}  // namespace

double estimateTimeOffset(const std::vector<ViInitKeyframe>& kfs, const ImuBuffer& imu, const ImuNoise& noise,
                          const SE3d& T_cm_i, double offset0, double range_s, const ImuBias& bias0,
                          int gyro_bias_iterations, double* cost_curvature) {
  if (cost_curvature) *cost_curvature = 0.0;
  if (kfs.size() < 3 || !(range_s > 0.0)) return offset0;
  const std::vector<Pose> poses = posesOf(kfs, T_cm_i);
  auto cost = [&](double o) { return rotationCost(kfs, poses, imu, noise, bias0, o, gyro_bias_iterations); };
  // A coarse grid of 11 over the range, then 7 around the best at a fifth of the step, twice.
  double step = range_s / 5.0, best = offset0, f_best = std::numeric_limits<double>::infinity();
  for (int round = 0, half = 5; round < 3; ++round, step /= 5.0, half = 3) {
    const double centre = best;
    for (int i = -half; i <= half; ++i) {
      const double o = centre + i * step;
      const double f = cost(o);
      if (f < f_best) {
        f_best = f;
        best = o;
      }
    }
  }
  if (!std::isfinite(f_best)) return offset0;
  step *= 5.0;  // the last round's step: a parabola through the best and its neighbours
  const double fm = cost(best - step), fp = cost(best + step);
  const double curv = (fm + fp - 2.0 * f_best) / (step * step);
  if (!std::isfinite(curv) || !(curv > 0.0)) return best;
  if (cost_curvature) *cost_curvature = curv;
  const double shift = (fm - fp) / (2.0 * curv * step);  // vertex offset from best, in seconds
  return best + std::clamp(shift, -step, step);
}

ViInitResult initializeVisualInertial(const std::vector<ViInitKeyframe>& kfs, const ImuBuffer& imu,
                                      const ImuNoise& noise, const SE3d& T_cm_i, double offset,
                                      const ViInitOptions& opt) {
  if (!(opt.min_interval_s > 0.0) || kfs.size() < 2) return solveInit(kfs, imu, noise, T_cm_i, offset, opt);
  const int n = static_cast<int>(kfs.size());
  const double duration = nsToS(kfs.back().t_ns - kfs.front().t_ns);
  if (n < opt.min_keyframes || duration < opt.min_duration_s) return solveInit(kfs, imu, noise, T_cm_i, offset, opt);
  // Pick back from the newest keyframe, each at least min_interval_s before the last one picked.
  std::vector<int> picked{n - 1};
  for (int k = n - 2; k >= 0; --k)
    if (nsToS(kfs[picked.back()].t_ns - kfs[k].t_ns) >= opt.min_interval_s - 1e-9) picked.push_back(k);
  std::reverse(picked.begin(), picked.end());
  if (static_cast<int>(picked.size()) < opt.min_subset_keyframes) {
    ViInitResult res;
    res.duration_s = duration;
    res.status = fmt("waiting for data: %.0f keyframes at least min_interval_s %.2f s apart over %.2f s, need %.0f",
                     picked.size(), opt.min_interval_s, duration, opt.min_subset_keyframes);
    return res;
  }
  std::vector<ViInitKeyframe> sub;
  for (int k : picked) sub.push_back(kfs[k]);
  ViInitOptions so = opt;
  so.min_keyframes = std::min(opt.min_keyframes, opt.min_subset_keyframes);
  ViInitResult r = solveInit(sub, imu, noise, T_cm_i, offset, so);
  r.duration_s = duration;
  if (!r.success) return r;
  // Every keyframe's velocity from the nearest picked one (earlier if any), through the IMU.
  const std::vector<Vec3> v_sub = r.velocities_wm;
  r.velocities_wm.assign(n, Vec3::Zero());
  const Vec3 g_wm(0.0, 0.0, -kGravityNorm);
  const Mat3 R_ci = T_cm_i.rotationMatrix();
  size_t p = 0;
  for (int k = 0; k < n; ++k) {
    while (p + 1 < picked.size() && picked[p + 1] <= k) ++p;
    const int a = picked[p];
    if (a == k) {
      r.velocities_wm[k] = v_sub[p];
      continue;
    }
    const int i = std::min(a, k), j = std::max(a, k);  // propagate over [t_i, t_j], forwards or backwards
    const ImuPreintegration pre = ImuPreintegration::fromBuffer(imu, kfs[i].t_ns, kfs[j].t_ns, noise, r.bias, offset);
    const ImuPreintegration::Delta d = pre.corrected(r.bias);
    const Mat3 R_wm_i = (r.T_wm_wf.so3() * SO3d(kfs[i].T_cf_wf.so3().inverse().matrix() * R_ci)).matrix();
    const Vec3 dv = g_wm * pre.dt() + R_wm_i * d.v;
    r.velocities_wm[k] = a == i ? Vec3(v_sub[p] + dv) : Vec3(v_sub[p] - dv);
  }
  return r;
}

namespace {
ViInitResult solveInit(const std::vector<ViInitKeyframe>& kfs, const ImuBuffer& imu, const ImuNoise& noise,
                       const SE3d& T_cm_i, double offset, const ViInitOptions& opt) {
  ViInitResult res;
  const int n = static_cast<int>(kfs.size());
  res.duration_s = n > 1 ? nsToS(kfs.back().t_ns - kfs.front().t_ns) : 0.0;
  if (n < opt.min_keyframes || res.duration_s < opt.min_duration_s) {
    res.status = fmt("waiting for data: %.0f keyframes over %.2f s, need min_keyframes %.0f over min_duration_s %.2f",
                     n, res.duration_s, opt.min_keyframes, opt.min_duration_s);
    return res;
  }
  const int64_t off_ns = sToNs(offset);
  if (!imu.covers(kfs.front().t_ns + off_ns, kfs.back().t_ns + off_ns)) {
    res.status = "waiting for data: IMU samples do not cover the keyframes yet";
    return res;
  }

  const std::vector<Pose> poses = posesOf(kfs, T_cm_i);
  const Mat3 R_ci = T_cm_i.rotationMatrix();
  const Vec3 t_ci = T_cm_i.translation();

  // Step 1: gyroscope bias, then preintegrate at it.
  ImuBias bias = opt.initial_bias;
  bias.gyro = estimateGyroBias(preintegrateAll(kfs, imu, noise, bias, offset), poses, bias, opt.gyro_bias_iterations);
  const std::vector<ImuPreintegration> pre = preintegrateAll(kfs, imu, noise, bias, offset);

  // Step 2: accelerometer excitation, std of (v_j - v_i)/dt - g = R_i dv / dt in W_f axes.
  std::vector<Vec3> acc(n - 1);
  Vec3 mean = Vec3::Zero();
  for (int k = 0; k + 1 < n; ++k) {
    acc[k] = poses[k].R_wi * pre[k].corrected(bias).v / pre[k].dt();
    mean += acc[k] / (n - 1);
  }
  double var = 0.0;
  for (const Vec3& a : acc) var += (a - mean).squaredNorm() / (n - 1);
  res.accel_excitation_m_s2 = std::sqrt(var);
  if (res.accel_excitation_m_s2 < opt.min_accel_excitation_m_s2) {
    res.status = fmt("waiting for excitation: accelerometer excitation %.3g m/s^2 < min_accel_excitation_m_s2 %.3g "
                     "(scale and gravity need accelerated motion)",
                     res.accel_excitation_m_s2, opt.min_accel_excitation_m_s2);
    return res;
  }

  // Step 3: linear system in (V, g_f, s) and its conditioning.
  const LinearSystem L = buildLinear(pre, poses, t_ci, bias, Mat3::Identity(), Vec3::Zero());
  Eigen::VectorXd col_norm = L.A.colwise().norm().transpose();
  for (int i = 0; i < col_norm.size(); ++i) col_norm[i] = col_norm[i] > 0.0 ? col_norm[i] : 1.0;
  const Eigen::MatrixXd An = L.A * col_norm.cwiseInverse().asDiagonal();
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(An).singularValues();
  res.relative_singular_value = sv.size() > 0 && sv[0] > 0.0 ? sv[sv.size() - 1] / sv[0] : 0.0;
  if (!(res.relative_singular_value >= opt.min_relative_singular_value)) {
    res.status = fmt("waiting for excitation: scale/gravity/velocity system ill-conditioned, relative singular value "
                     "%.3g < min_relative_singular_value %.3g (too little camera translation?)",
                     res.relative_singular_value, opt.min_relative_singular_value);
    return res;
  }
  Eigen::VectorXd x = L.A.colPivHouseholderQr().solve(L.b);
  Vec3 g_f = x.segment<3>(3 * n);
  res.gravity_norm_linear_m_s2 = g_f.norm();
  if (std::abs(g_f.norm() / kGravityNorm - 1.0) > opt.max_gravity_norm_error) {
    res.status = fmt("rejected: linear gravity estimate |g| = %.3f m/s^2 differs from %.2f by more than "
                     "max_gravity_norm_error %.0f%% (biased accelerometer or wrong extrinsic/time offset?)",
                     g_f.norm(), kGravityNorm, 100.0 * opt.max_gravity_norm_error);
    return res;
  }
  // Gravity refinement on the sphere |g| = 9.81: g = 9.81 g_dir + B w, re-linearised a few times.
  Vec3 g_dir = g_f.normalized();
  for (int it = 0; it < opt.gravity_refinement_iterations; ++it) {
    const Eigen::Matrix<double, 3, 2> B = tangentBasis(g_dir);
    const LinearSystem Lr = buildLinear(pre, poses, t_ci, bias, B, kGravityNorm * g_dir);
    x = Lr.A.colPivHouseholderQr().solve(Lr.b);
    g_dir = (kGravityNorm * g_dir + B * x.segment<2>(3 * n)).normalized();
  }
  const double scale = x[x.size() - 1];
  if (!(scale > 0.0) || !std::isfinite(scale)) {
    res.status = fmt("rejected: estimated scale %.3g is not positive", scale);
    return res;
  }
  // R_g: the smallest rotation taking W_f's gravity direction to -z of W_m.
  const SO3d R_g(Eigen::Quaterniond::FromTwoVectors(g_dir, Vec3(0, 0, -1)).normalized());
  res.T_wm_wf = RxSO3d(scale, R_g);
  res.velocities_wm.resize(n);
  for (int k = 0; k < n; ++k) res.velocities_wm[k] = R_g * Vec3(x.segment<3>(3 * k));
  res.bias = bias;

  // Step 4: non-linear refinement on the full IMU factors.
  if (opt.refine_nonlinear) refineNonlinear(pre, kfs, T_cm_i, offset, opt, &res);
  measureFit(pre, kfs, T_cm_i, offset, &res);
  if (!(res.T_wm_wf.scale() > 0.0)) {
    res.status = "rejected: refinement produced a non-positive scale";
    return res;
  }
  res.success = true;
  const Vec3 g_dir_wf = res.T_wm_wf.so3().inverse() * Vec3(0, 0, -1);
  const double tilt_deg = std::acos(std::clamp(-g_dir_wf.z(), -1.0, 1.0)) * 180.0 / M_PI;
  res.status = fmt("initialised: scale %.4g m per unit, accelerometer excitation %.3g m/s^2, relative singular value "
                   "%.3g, gravity %.1f deg from W_f's -z",
                   res.T_wm_wf.scale(), res.accel_excitation_m_s2, res.relative_singular_value, tilt_deg);
  return res;
}

}  // namespace

}  // namespace rsvio
