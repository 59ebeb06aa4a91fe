// The inertial terms of the window optimisation (contract in rsvio/backend/inertial_term.h).
#include "rsvio/backend/inertial_term.h"

#include <algorithm>
#include <functional>

#include "rsvio/imu/twist_prior.h"
#include "rsvio/imu/visual_inertial_factor.h"

namespace rsvio {

namespace {

enum Part { kPhoto = 0, kImu = 1, kGlobal = 2 };

// One Jacobian block of a residual: the columns `within` a keyframe's part (or the global block).
struct Col {
  const Keyframe* kf;  // null for the global block
  Part part;
  int within;
  Eigen::MatrixXd J;
};

// Row of (kf, part) in the system being filled; -1 when it is not in it.
using RowOf = std::function<int(const Keyframe*, Part)>;

double accumulate(const Eigen::VectorXd& r, const Eigen::MatrixXd& W, const std::vector<Col>& cols, const RowOf& rowOf,
                  Eigen::MatrixXd& H, Eigen::VectorXd& b) {
  const Eigen::VectorXd Wr = W * r;
  for (const Col& ci : cols) {
    const int oi = rowOf(ci.kf, ci.part);
    if (oi < 0) continue;
    const Eigen::MatrixXd JtW = ci.J.transpose() * W;
    b.segment(oi + ci.within, ci.J.cols()) -= ci.J.transpose() * Wr;
    for (const Col& cj : cols) {
      const int oj = rowOf(cj.kf, cj.part);
      if (oj < 0) continue;
      H.block(oi + ci.within, oj + cj.within, ci.J.cols(), cj.J.cols()) += JtW * cj.J;
    }
  }
  return r.dot(Wr);
}

Mat6 twistWeight(const InertialTermOptions& o, double scale) {
  Mat6 W = Mat6::Zero();
  const double it = (scale / o.twist_sigma_trans_m_s) * (scale / o.twist_sigma_trans_m_s);
  const double ir = 1.0 / (o.twist_sigma_rot_rad_s * o.twist_sigma_rot_rad_s);
  W.diagonal() << Vec3::Constant(it), Vec3::Constant(ir);
  return W * o.twist_weight;
}

// The IMU factor of j: residual, weight and Jacobian blocks.
bool imuFactorCols(const Keyframe& j, const GlobalStates& g, const SE3d& T_cm_i, const InertialTermOptions& o,
                   const StateLayout& layout, Vec15* r, Mat15* W, std::vector<Col>* cols) {
  if (!j.imu_term || !j.imu_prev || !j.imu_factor) return false;
  const Keyframe& i = *j.imu_prev;
  VisualInertialJacobians J;
  *r = visualInertialResidual(*j.imu_factor, visualInertialStateOf(i), visualInertialStateOf(j), g.state.T_wm_wf,
                              T_cm_i, g.state.time_offset_s, cols ? &J : nullptr);
  *W = o.imu_weight * j.imu_factor->information();
  if (!cols) return true;
  cols->clear();
  cols->push_back({&i, kPhoto, StateLayout::kPose, J.d_res_d_T_cf_wf_i});
  cols->push_back({&j, kPhoto, StateLayout::kPose, J.d_res_d_T_cf_wf_j});
  cols->push_back({&i, kImu, 0, J.d_res_d_vel_bias_i});
  cols->push_back({&j, kImu, 0, J.d_res_d_vel_bias_j});
  cols->push_back({nullptr, kGlobal, StateLayout::kGlobalRot, J.d_res_d_T_wm_wf});
  if (layout.estimate_time_offset) cols->push_back({nullptr, kGlobal, StateLayout::kGlobalOffset, J.d_res_d_offset});
  return true;
}

// Before the initialisation: the rotation rows of j's IMU factor on the pose columns (the contract).
bool gyroRotationCols(const Keyframe& j, const GlobalStates& g, const SE3d& T_cm_i, const InertialTermOptions& o,
                      Vec3* r, Mat3* W, std::vector<Col>* cols) {
  if (!(o.gyro_bias_sigma_before_init_rad_s > 0.0) || !j.imu_term || !j.imu_prev || !j.imu_factor) return false;
  const Keyframe& i = *j.imu_prev;
  VisualInertialJacobians J;
  const Vec15 r15 = visualInertialResidual(*j.imu_factor, visualInertialStateOf(i), visualInertialStateOf(j),
                                           g.state.T_wm_wf, T_cm_i, g.state.time_offset_s, cols ? &J : nullptr);
  *r = r15.head<3>();
  const ImuPreintegration& p = j.imu_factor->preintegration();
  const double sb = o.gyro_bias_sigma_before_init_rad_s * p.dt();
  const Mat3 cov = p.covariance().topLeftCorner<3, 3>() + sb * sb * Mat3::Identity();
  *W = o.imu_weight * cov.inverse();
  if (!cols) return true;
  cols->clear();
  cols->push_back({&i, kPhoto, StateLayout::kPose, J.d_res_d_T_cf_wf_i.topRows<3>()});
  cols->push_back({&j, kPhoto, StateLayout::kPose, J.d_res_d_T_cf_wf_j.topRows<3>()});
  return true;
}

// Before the initialisation: the rotation rows of k's twist energy on its twist (the contract). The
// prior's rotation -R_Cm_I (w - b_g) needs neither the pose nor T_Wm_Wf (twist_prior.h).
bool twistRotationCols(const Keyframe& k, const SE3d& T_cm_i, const InertialTermOptions& o, const StateLayout& layout,
                       Vec3* r, Mat3* W, std::vector<Col>* cols) {
  if (!layout.rolling || !k.twist_energy || !(o.twist_gyro_sigma_before_init_rad_s > 0.0)) return false;
  *r = imuTwistRotation(k.gyro_at_t, k.state.bias_gyro, T_cm_i) - k.state.twist.tail<3>();
  const double s = o.twist_gyro_sigma_before_init_rad_s;
  *W = (o.twist_weight / (s * s)) * Mat3::Identity();
  if (!cols) return true;
  cols->clear();
  Eigen::Matrix<double, 3, 6> J = Eigen::Matrix<double, 3, 6>::Zero();
  J.rightCols<3>() = -Mat3::Identity();
  cols->push_back({&k, kPhoto, StateLayout::kTwist, J});
  return true;
}

// The twist energy of k: residual, weight and Jacobian blocks.
bool twistCols(const Keyframe& k, const GlobalStates& g, const SE3d& T_cm_i, const InertialTermOptions& o,
               const StateLayout& layout, Vec6* r, Mat6* W, std::vector<Col>* cols) {
  if (!layout.rolling || !k.twist_energy) return false;
  TwistPriorJacobians J;
  *r = rsvio::twistResidual(k.state.twist, k.gyro_at_t, k.state.v_wm, k.state.bias_gyro, k.state.T_c_w,
                            g.state.T_wm_wf, T_cm_i, cols ? &J : nullptr);
  *W = twistWeight(o, g.state.T_wm_wf.scale());
  if (!cols) return true;
  cols->clear();
  cols->push_back({&k, kPhoto, StateLayout::kTwist, J.d_res_d_twist});
  cols->push_back({&k, kPhoto, StateLayout::kPose, J.d_res_d_T_cf_wf});
  cols->push_back({&k, kImu, StateLayout::kVel, J.d_res_d_v});
  cols->push_back({&k, kImu, StateLayout::kBiasGyro, J.d_res_d_bg});
  cols->push_back({nullptr, kGlobal, StateLayout::kGlobalRot, J.d_res_d_T_wm_wf});
  return true;
}

}  // namespace

VisualInertialKeyframe visualInertialStateOf(const Keyframe& k) {
  VisualInertialKeyframe v;
  v.T_cf_wf = k.state.T_c_w;
  v.v_wm = k.state.v_wm;
  v.bias.gyro = k.state.bias_gyro;
  v.bias.accel = k.state.bias_accel;
  return v;
}

double InertialTerm::linearize(const KeyframeList& window, const StateLayout& layout, Eigen::MatrixXd& H,
                               Eigen::VectorXd& b) const {
  if (!g_) return 0.0;
  const int n = static_cast<int>(window.size());
  const RowOf rowOf = [&](const Keyframe* kf, Part p) {
    if (p == kGlobal) return layout.globalOffset(n);
    if (kf->index < 0 || kf->index >= n || window[static_cast<size_t>(kf->index)].get() != kf) return -1;
    return p == kPhoto ? layout.photometricOffset(kf->index) : layout.imuOffset(kf->index, n);
  };
  double e = 0.0;
  std::vector<Col> cols;
  for (const auto& kf : window) {
    if (!layout.inertial) {
      Vec3 r;
      Mat3 W;
      if (gyroRotationCols(*kf, *g_, T_cm_i_, o_, &r, &W, &cols)) e += accumulate(r, W, cols, rowOf, H, b);
      if (twistRotationCols(*kf, T_cm_i_, o_, layout, &r, &W, &cols)) e += accumulate(r, W, cols, rowOf, H, b);
      continue;
    }
    Vec15 r;
    Mat15 W;
    if (imuFactorCols(*kf, *g_, T_cm_i_, o_, layout, &r, &W, &cols)) e += accumulate(r, W, cols, rowOf, H, b);
    Vec6 rt;
    Mat6 Wt;
    if (twistCols(*kf, *g_, T_cm_i_, o_, layout, &rt, &Wt, &cols)) e += accumulate(rt, Wt, cols, rowOf, H, b);
  }
  return e;
}

double InertialTerm::linearizeInvolving(const Keyframe& kf, const KeyframeList& window, const StateLayout& layout,
                                        std::vector<Keyframe*>* kfs, Eigen::MatrixXd* H, Eigen::VectorXd* b) const {
  kfs->clear();
  H->resize(0, 0);
  b->resize(0);
  if (!g_) return 0.0;
  // The terms: kf's factor and twist energy, and the factor of every keyframe whose imu_prev is kf.
  std::vector<const Keyframe*> factor_of, twist_of;
  // Before the initialisation a factor contributes only with the gyroscope's rotations on.
  const bool factors = layout.inertial || o_.gyro_bias_sigma_before_init_rad_s > 0.0;
  if (factors && kf.imu_term && kf.imu_prev && kf.imu_factor) factor_of.push_back(&kf);
  if (layout.rolling && kf.twist_energy && (layout.inertial || o_.twist_gyro_sigma_before_init_rad_s > 0.0))
    twist_of.push_back(&kf);
  for (const auto& w : window)
    if (factors && w.get() != &kf && w->imu_term && w->imu_prev == &kf && w->imu_factor) factor_of.push_back(w.get());
  auto addKf = [&](const Keyframe* k) {
    if (std::find(kfs->begin(), kfs->end(), k) == kfs->end()) kfs->push_back(const_cast<Keyframe*>(k));
  };
  for (const Keyframe* j : factor_of) {
    addKf(j->imu_prev);
    addKf(j);
  }
  for (const Keyframe* k : twist_of) addKf(k);
  if (kfs->empty()) return 0.0;
  std::sort(kfs->begin(), kfs->end(), [](const Keyframe* x, const Keyframe* y) { return x->index < y->index; });
  const int d = layout.stateDim(), kd = layout.kfDim();
  const int nk = static_cast<int>(kfs->size());
  const RowOf rowOf = [&](const Keyframe* k, Part p) {
    if (p == kGlobal) return nk * d;
    for (int i = 0; i < nk; ++i)
      if ((*kfs)[static_cast<size_t>(i)] == k) return i * d + (p == kPhoto ? 0 : kd);
    return -1;
  };
  H->setZero(nk * d + layout.globalDim(), nk * d + layout.globalDim());
  b->setZero(nk * d + layout.globalDim());
  double e = 0.0;
  std::vector<Col> cols;
  for (const Keyframe* j : factor_of) {
    if (!layout.inertial) {
      Vec3 r;
      Mat3 W;
      if (gyroRotationCols(*j, *g_, T_cm_i_, o_, &r, &W, &cols)) e += accumulate(r, W, cols, rowOf, *H, *b);
      continue;
    }
    Vec15 r;
    Mat15 W;
    if (imuFactorCols(*j, *g_, T_cm_i_, o_, layout, &r, &W, &cols)) e += accumulate(r, W, cols, rowOf, *H, *b);
  }
  for (const Keyframe* k : twist_of) {
    if (!layout.inertial) {
      Vec3 r;
      Mat3 W;
      if (twistRotationCols(*k, T_cm_i_, o_, layout, &r, &W, &cols)) e += accumulate(r, W, cols, rowOf, *H, *b);
      continue;
    }
    Vec6 r;
    Mat6 W;
    if (twistCols(*k, *g_, T_cm_i_, o_, layout, &r, &W, &cols)) e += accumulate(r, W, cols, rowOf, *H, *b);
  }
  return e;
}

bool InertialTerm::imuResidual(const Keyframe& j, Vec15* r, double* energy) const {
  if (!g_) return false;
  Mat15 W;
  StateLayout layout;
  layout.inertial = true;
  Vec15 rr;
  if (!imuFactorCols(j, *g_, T_cm_i_, o_, layout, &rr, &W, nullptr)) return false;
  if (r) *r = rr;
  if (energy) *energy = rr.dot(W * rr);
  return true;
}

bool InertialTerm::twistResidual(const Keyframe& k, Vec6* r, double* energy) const {
  if (!g_) return false;
  StateLayout layout;
  layout.rolling = layout.inertial = true;
  Mat6 W;
  Vec6 rr;
  if (!twistCols(k, *g_, T_cm_i_, o_, layout, &rr, &W, nullptr)) return false;
  if (r) *r = rr;
  if (energy) *energy = rr.dot(W * rr);
  return true;
}

}  // namespace rsvio
