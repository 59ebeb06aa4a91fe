// The inertial window terms (backend/inertial_term.h) and the visual-inertial parts of the window
// system: the assembled normal equations against numeric differences of the whitened residuals (every
// block pair against its own scale: poses, twists, velocities and biases, T_Wm_Wf, time offset), the
// terms handed to the marginalisation prior, the prior's inertial layout (setLayout keeps the energy,
// addTo puts a term back where it came from), and the steps of the bundle adjuster on the global block.
#include <gtest/gtest.h>

#include <functional>

#include <Eigen/Cholesky>

#include "ba_test_window.h"
#include "rsvio/backend/inertial_term.h"
#include "rsvio/backend/marginalization.h"
#include "rsvio/imu/imu_buffer.h"
#include "rsvio/imu/preintegration.h"
#include "rsvio/imu/twist_prior.h"
#include "rsvio/imu/visual_inertial_factor.h"
#include "rsvio/interfaces/solver.h"
#include "support/numeric_jacobian.h"
#include "support/plugin_contracts.h"

namespace rsvio {
namespace {

using test::tw;

// A smooth synthetic IMU stream (200 Hz) and three keyframes 0.15 s apart with generic states,
// linked as the estimator links them (each keyframe's factor from the one before).
struct InertialChain {
  KeyframeList window;
  StateLayout layout;
  GlobalStates globals;
  ImuBuffer buffer;
  SE3d T_cm_i = SE3d::exp(tw(0.03, -0.02, 0.01, 0.1, -0.05, 0.02));
  std::vector<std::shared_ptr<ImuFactor>> factors;

  explicit InertialChain(bool rolling, bool offset) {
    layout.rolling = rolling;
    layout.inertial = true;
    layout.estimate_time_offset = offset;
    for (int s = -10; s <= 120; ++s) {
      ImuSample m;
      m.t_ns = static_cast<int64_t>(s) * 5'000'000;
      const double t = s * 0.005;
      m.gyro_rad_s = Vec3(0.3 * std::sin(3 * t), -0.2 + 0.1 * t, 0.15 * std::cos(2 * t));
      m.accel_m_s2 = Vec3(0.5 * std::cos(t), 9.6 + 0.3 * std::sin(4 * t), -0.4 + 0.2 * t);
      buffer.add(m);
    }
    globals.state.T_wm_wf = RxSO3d(1.7, SO3d::exp(Vec3(0.2, -0.1, 0.4)));
    // The factors are preintegrated at this offset: their first-order offset model (preintegration.h)
    // is exact in the bias only there (its d/d offset uses bias-corrected readings).
    globals.state.time_offset_s = 0.004;
    ImuNoise noise;
    for (int i = 0; i < 3; ++i) {
      auto kf = std::make_unique<Keyframe>();
      kf->t_ns = 20'000'000 + static_cast<int64_t>(i) * 150'000'000;
      kf->kf_id = i;
      kf->state.T_c_w = SE3d::exp(tw(0.3 * i, -0.1 * i, 0.05 * i * i, 0.2 * i, -0.1, 0.05 * i));
      kf->state.twist = tw(0.5 + 0.1 * i, -0.3, 0.2, 0.4, -0.2 * i, 0.1);
      kf->state.v_wm = Vec3(0.4 - 0.1 * i, 0.2, -0.1 * i);
      kf->state.bias_gyro = Vec3(0.01, -0.02 * i, 0.005);
      kf->state.bias_accel = Vec3(0.05 * i, -0.03, 0.02);
      kf->gyro_at_t = buffer.interpolate(kf->t_ns + 4'000'000).gyro_rad_s;
      kf->twist_energy = rolling;
      window.push_back(std::move(kf));
    }
    reindex(window);
    for (int j = 1; j < 3; ++j) {
      ImuBias b;
      b.gyro = Vec3(0.012, -0.01, 0.004);
      b.accel = Vec3(0.04, -0.02, 0.01);
      auto f = std::make_shared<ImuFactor>(ImuPreintegration::fromBuffer(buffer, window[j - 1]->t_ns, window[j]->t_ns,
                                                                         noise, b, 0.004));
      factors.push_back(f);
      window[j]->imu_term = true;
      window[j]->imu_prev = window[j - 1].get();
      window[j]->imu_factor = f;
    }
  }

  int n() const { return static_cast<int>(window.size()); }
  int dim() const { return layout.windowDim(n()); }

  // Applies a window-system step to copies of the states and returns the states as they were.
  void apply(const Eigen::VectorXd& dx) {
    for (auto& kf : window) applyStep(kf->state, gatherState(dx, kf->index, n(), layout), layout);
    applyGlobalStep(globals.state, dx.segment(layout.globalOffset(n()), layout.globalDim()), layout);
  }
};

// Stacked whitened residuals of every term at the chain's current states.
Eigen::VectorXd whitened(const InertialChain& c, const InertialTermOptions& o) {
  std::vector<double> out;
  for (const auto& kf : c.window) {
    if (kf->imu_term) {
      const VisualInertialKeyframe a{kf->imu_prev->state.T_c_w, kf->imu_prev->state.v_wm,
                                     ImuBias{kf->imu_prev->state.bias_gyro, kf->imu_prev->state.bias_accel}};
      const VisualInertialKeyframe b{kf->state.T_c_w, kf->state.v_wm, ImuBias{kf->state.bias_gyro, kf->state.bias_accel}};
      const Vec15 r = visualInertialResidual(*kf->imu_factor, a, b, c.globals.state.T_wm_wf, c.T_cm_i,
                                             c.globals.state.time_offset_s);
      const Mat15 U = kf->imu_factor->sqrtInformation() * std::sqrt(o.imu_weight);
      const Vec15 w = U * r;
      out.insert(out.end(), w.data(), w.data() + 15);
    }
    if (c.layout.rolling && kf->twist_energy) {
      const Vec6 r = twistResidual(kf->state.twist, kf->gyro_at_t, kf->state.v_wm, kf->state.bias_gyro, kf->state.T_c_w,
                                   c.globals.state.T_wm_wf, c.T_cm_i);
      // The weight's scale is held at the linearisation (the contract): use the unperturbed one.
      const double s0 = 1.7;
      Vec6 sw;
      sw << Vec3::Constant(s0 / o.twist_sigma_trans_m_s), Vec3::Constant(1.0 / o.twist_sigma_rot_rad_s);
      const Vec6 w = (sw.array() * r.array()).matrix() * std::sqrt(o.twist_weight);
      out.insert(out.end(), w.data(), w.data() + 6);
    }
  }
  return Eigen::Map<Eigen::VectorXd>(out.data(), static_cast<Eigen::Index>(out.size()));
}

// Names of the blocks of the window system, for the per-block comparison.
struct Block {
  std::string name;
  int offset, size;
};

std::vector<Block> blocks(const InertialChain& c) {
  std::vector<Block> out;
  const StateLayout& L = c.layout;
  for (int k = 0; k < c.n(); ++k) {
    const std::string s = std::to_string(k);
    out.push_back({"pose" + s, L.photometricOffset(k) + StateLayout::kPose, 6});
    if (L.rolling) out.push_back({"twist" + s, L.photometricOffset(k) + StateLayout::kTwist, 6});
    out.push_back({"vel" + s, L.imuOffset(k, c.n()) + StateLayout::kVel, 3});
    out.push_back({"bg" + s, L.imuOffset(k, c.n()) + StateLayout::kBiasGyro, 3});
    out.push_back({"ba" + s, L.imuOffset(k, c.n()) + StateLayout::kBiasAccel, 3});
  }
  out.push_back({"T_wm_wf", L.globalOffset(c.n()), 4});
  if (L.estimate_time_offset) out.push_back({"offset", L.globalOffset(c.n()) + StateLayout::kGlobalOffset, 1});
  return out;
}

// The window system (H, b) against the numeric one, block by block, each against its own scale.
void expectBlocksNear(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, const Eigen::MatrixXd& H_num,
                      const Eigen::VectorXd& b_num, const std::vector<Block>& bl) {
  for (const Block& bi : bl) {
    EXPECT_JACOBIAN_NEAR_TOL(b.segment(bi.offset, bi.size), b_num.segment(bi.offset, bi.size), 1e-5,
                             1e-6 * std::max(1.0, b_num.segment(bi.offset, bi.size).cwiseAbs().maxCoeff()))
        << "b of " << bi.name;
    for (const Block& bj : bl) {
      const Eigen::MatrixXd hn = H_num.block(bi.offset, bj.offset, bi.size, bj.size);
      EXPECT_JACOBIAN_NEAR_TOL(H.block(bi.offset, bj.offset, bi.size, bj.size), hn, 1e-5,
                               1e-6 * std::max(1.0, hn.cwiseAbs().maxCoeff()))
          << "H of " << bi.name << " x " << bj.name;
    }
  }
}

void checkNormalEquations(bool rolling, bool offset) {
  InertialChain c(rolling, offset);
  InertialTermOptions o;
  o.imu_weight = 0.7;
  o.twist_weight = 1.3;
  const InertialTerm term(o, c.T_cm_i, &c.globals);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(c.dim(), c.dim());
  Eigen::VectorXd b = Eigen::VectorXd::Zero(c.dim());
  const double e = term.linearize(c.window, c.layout, H, b);
  const Eigen::VectorXd r0 = whitened(c, o);
  EXPECT_NEAR(e, r0.squaredNorm(), 1e-9 * std::max(1.0, e));
  // Numeric Jacobian of the whitened residuals w.r.t. the window system's perturbation.
  const Eigen::VectorXd x0 = Eigen::VectorXd::Zero(c.dim());
  auto f = [&](const Eigen::VectorXd& dx) {
    InertialChain copy(rolling, offset);
    copy.apply(dx);
    return whitened(copy, o);
  };
  const Eigen::MatrixXd J = test::numericJacobian(f, x0, test::vectorPlus, c.dim(), 1e-6);
  const Eigen::MatrixXd H_num = J.transpose() * J;
  const Eigen::VectorXd b_num = -J.transpose() * r0;
  expectBlocksNear(H, b, H_num, b_num, blocks(c));
  // Every block is reached: no block of the system is left without information.
  for (const Block& bi : blocks(c)) {
    EXPECT_GT(H.block(bi.offset, bi.offset, bi.size, bi.size).diagonal().minCoeff(), 0.0) << bi.name;
  }
}

TEST(InertialTerm, NormalEquationsMatchNumericDifferencesGlobalShutter) { checkNormalEquations(false, false); }
TEST(InertialTerm, NormalEquationsMatchNumericDifferencesRollingShutter) { checkNormalEquations(true, false); }
TEST(InertialTerm, NormalEquationsMatchNumericDifferencesWithTimeOffset) { checkNormalEquations(true, true); }

// The window system of a before-the-initialisation term (layout without the inertial blocks) on the
// rolling chain, checked against numeric differences of `whitened` block by block (poses and twists);
// returned for the test's own checks. The same options with the term's sigma at 0 add nothing.
struct BeforeInitSystem {
  InertialChain c{true, false};
  Eigen::MatrixXd H;
  Eigen::VectorXd b, r0;
  double e = 0.0;
  std::vector<Block> bl;  // pose k at 2k, twist k at 2k + 1
};

InertialChain beforeInitChain() {
  InertialChain c(true, false);
  c.layout.inertial = false;
  return c;
}

void checkBeforeInitTerm(const InertialTermOptions& o, const InertialTermOptions& off,
                         const std::function<Eigen::VectorXd(const InertialChain&)>& whitened, BeforeInitSystem* s) {
  s->c = beforeInitChain();
  const InertialChain& c = s->c;
  const int dim = c.dim();
  ASSERT_EQ(dim, 3 * c.layout.kfDim()) << "no inertial or global blocks before the initialisation";
  const InertialTerm term(o, c.T_cm_i, &c.globals);
  s->H = Eigen::MatrixXd::Zero(dim, dim);
  s->b = Eigen::VectorXd::Zero(dim);
  s->e = term.linearize(c.window, c.layout, s->H, s->b);
  s->r0 = whitened(c);
  EXPECT_GT(s->e, 0.0);
  EXPECT_NEAR(s->e, s->r0.squaredNorm(), 1e-9 * std::max(1.0, s->e));
  auto f = [&](const Eigen::VectorXd& dx) {
    InertialChain copy = beforeInitChain();
    copy.apply(dx);
    return whitened(copy);
  };
  const Eigen::VectorXd x0 = Eigen::VectorXd::Zero(dim);
  const Eigen::MatrixXd J = test::numericJacobian(f, x0, test::vectorPlus, dim, 1e-6);
  s->bl.clear();
  for (int k = 0; k < c.n(); ++k) {
    s->bl.push_back({"pose" + std::to_string(k), c.layout.photometricOffset(k) + StateLayout::kPose, 6});
    s->bl.push_back({"twist" + std::to_string(k), c.layout.photometricOffset(k) + StateLayout::kTwist, 6});
  }
  expectBlocksNear(s->H, s->b, J.transpose() * J, -J.transpose() * s->r0, s->bl);
  const InertialTerm none(off, c.T_cm_i, &c.globals);
  Eigen::MatrixXd H0 = Eigen::MatrixXd::Zero(dim, dim);
  Eigen::VectorXd b0 = Eigen::VectorXd::Zero(dim);
  EXPECT_EQ(none.linearize(c.window, c.layout, H0, b0), 0.0) << "off";
  EXPECT_EQ(H0.cwiseAbs().maxCoeff(), 0.0) << "off";
}

// Before the visual-inertial initialisation (layout without the inertial blocks), with the gyroscope's
// rotations on: each factor's rotation residual on the two poses, weight imu_weight (Cov_RR + (sigma_bg
// dt)^2 I)^-1 (inertial_term.h). The normal equations against numeric differences of the whitened
// rotation residuals, block by block; off (sigma 0) the term adds nothing. Shown once: the Jacobian of
// each factor's first pose negated fails b of poses 0 and 1 and H between consecutive poses.
TEST(InertialTerm, BeforeTheInitialisationTheGyroRotationsMatchNumericDifferences) {
  InertialTermOptions o;
  o.imu_weight = 0.7;
  o.gyro_bias_sigma_before_init_rad_s = 0.01;
  auto whitenedRot = [&](const InertialChain& ch) {
    std::vector<double> out;
    for (const auto& kf : ch.window) {
      if (!kf->imu_term) continue;
      const VisualInertialKeyframe a{kf->imu_prev->state.T_c_w, kf->imu_prev->state.v_wm,
                                     ImuBias{kf->imu_prev->state.bias_gyro, kf->imu_prev->state.bias_accel}};
      const VisualInertialKeyframe b{kf->state.T_c_w, kf->state.v_wm, ImuBias{kf->state.bias_gyro, kf->state.bias_accel}};
      const Vec3 r = visualInertialResidual(*kf->imu_factor, a, b, ch.globals.state.T_wm_wf, ch.T_cm_i,
                                            ch.globals.state.time_offset_s)
                         .head<3>();
      const ImuPreintegration& p = kf->imu_factor->preintegration();
      const double sb = o.gyro_bias_sigma_before_init_rad_s * p.dt();
      const Mat3 W = o.imu_weight * (p.covariance().topLeftCorner<3, 3>() + sb * sb * Mat3::Identity()).inverse();
      const Eigen::LLT<Mat3> llt(W);
      const Vec3 w = llt.matrixU() * r;  // U^T U = W
      out.insert(out.end(), w.data(), w.data() + 3);
    }
    return Eigen::VectorXd(Eigen::Map<Eigen::VectorXd>(out.data(), static_cast<Eigen::Index>(out.size())));
  };
  InertialTermOptions off = o;
  off.gyro_bias_sigma_before_init_rad_s = 0.0;
  BeforeInitSystem s;
  checkBeforeInitTerm(o, off, whitenedRot, &s);
  ASSERT_EQ(s.r0.size(), 6);
  for (int k = 0; k < s.c.n(); ++k)
    EXPECT_GT(s.H.block(s.bl[2 * k].offset + 3, s.bl[2 * k].offset + 3, 3, 3).diagonal().minCoeff(), 0.0)
        << "rotation of pose " << k;  // (upsilon; omega): the rotation is the second half

  // Marginalising keyframe 1 takes both factors through it, on the three poses.
  const InertialTerm term(o, s.c.T_cm_i, &s.c.globals);
  std::vector<Keyframe*> kfs;
  Eigen::MatrixXd Hm;
  Eigen::VectorXd bm;
  const double em = term.linearizeInvolving(*s.c.window[1], s.c.window, s.c.layout, &kfs, &Hm, &bm);
  EXPECT_EQ(kfs.size(), 3u);
  EXPECT_NEAR(em, s.e, 1e-9 * std::max(1.0, s.e));
  EXPECT_LT((Hm - s.H).cwiseAbs().maxCoeff(), 1e-9 * s.H.cwiseAbs().maxCoeff());
}

// Before the initialisation with imu.twist_gyro_sigma_before_init_rad_s: each keyframe's twist rotation
// is held to the gyroscope, r = -R_Cm_I (w - b_g) - xi_rot (the rotation rows of eq. 33, which need no
// pose, scale or gravity), weight twist_weight / sigma^2; numeric differences per block, the terms
// through a keyframe for the marginalisation, and nothing when off.
TEST(InertialTerm, BeforeTheInitialisationTheTwistRotationsFollowTheGyroscope) {
  InertialTermOptions o;
  o.twist_weight = 0.6;
  o.twist_gyro_sigma_before_init_rad_s = 0.03;
  auto whitenedTwistRot = [&](const InertialChain& ch) {
    std::vector<double> out;
    for (const auto& kf : ch.window) {
      const Vec6 r6 = twistResidual(kf->state.twist, kf->gyro_at_t, kf->state.v_wm, kf->state.bias_gyro,
                                    kf->state.T_c_w, ch.globals.state.T_wm_wf, ch.T_cm_i);
      const Vec3 w = std::sqrt(o.twist_weight) / o.twist_gyro_sigma_before_init_rad_s * r6.tail<3>();
      out.insert(out.end(), w.data(), w.data() + 3);
    }
    return Eigen::VectorXd(Eigen::Map<Eigen::VectorXd>(out.data(), static_cast<Eigen::Index>(out.size())));
  };
  InertialTermOptions off = o;
  off.twist_gyro_sigma_before_init_rad_s = 0.0;
  BeforeInitSystem s;
  checkBeforeInitTerm(o, off, whitenedTwistRot, &s);
  ASSERT_EQ(s.r0.size(), 9);
  for (int k = 0; k < s.c.n(); ++k)
    EXPECT_GT(s.H.block(s.bl[2 * k + 1].offset + 3, s.bl[2 * k + 1].offset + 3, 3, 3).diagonal().minCoeff(), 0.0)
        << "twist rotation of keyframe " << k;

  // Marginalising keyframe 1 takes its own twist term only (one keyframe).
  const InertialTerm term(o, s.c.T_cm_i, &s.c.globals);
  std::vector<Keyframe*> kfs;
  Eigen::MatrixXd Hm;
  Eigen::VectorXd bm;
  const double em = term.linearizeInvolving(*s.c.window[1], s.c.window, s.c.layout, &kfs, &Hm, &bm);
  ASSERT_EQ(kfs.size(), 1u);
  EXPECT_NEAR(em, s.r0.segment<3>(3).squaredNorm(), 1e-9 * std::max(1.0, em));
  const int o1 = s.c.layout.photometricOffset(1), kd = s.c.layout.kfDim();
  EXPECT_LT((Hm.topLeftCorner(kd, kd) - s.H.block(o1, o1, kd, kd)).cwiseAbs().maxCoeff(),
            1e-9 * s.H.cwiseAbs().maxCoeff());
}

// The terms that involve a keyframe, as the marginalisation takes them: keyframe 1's own factor and
// twist energy and keyframe 2's factor (from 1); scattered back into the window system they equal
// the window's linearisation minus the terms that do not involve keyframe 1 (the other twists).
TEST(InertialTerm, TermsInvolvingAKeyframeAreTheWindowsTermsThroughIt) {
  InertialChain c(true, true);
  const InertialTermOptions o;
  const InertialTerm term(o, c.T_cm_i, &c.globals);
  std::vector<Keyframe*> kfs;
  Eigen::MatrixXd Hk;
  Eigen::VectorXd bk;
  const double ek = term.linearizeInvolving(*c.window[1], c.window, c.layout, &kfs, &Hk, &bk);
  ASSERT_EQ(kfs.size(), 3u);
  // Without the twist energies of keyframes 0 and 2 the window's terms are exactly those involving 1.
  c.window[0]->twist_energy = false;
  c.window[2]->twist_energy = false;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(c.dim(), c.dim());
  Eigen::VectorXd b = Eigen::VectorXd::Zero(c.dim());
  const double e = term.linearize(c.window, c.layout, H, b);
  EXPECT_NEAR(ek, e, 1e-9 * e);
  MarginalizationPrior prior(c.layout);
  prior.setGlobals(&c.globals);
  prior.addTerm(kfs, Hk, bk, true);
  Eigen::MatrixXd Hp = Eigen::MatrixXd::Zero(c.dim(), c.dim());
  Eigen::VectorXd bp = Eigen::VectorXd::Zero(c.dim());
  prior.addTo(Hp, bp);  // at the linearisation point: the term itself
  EXPECT_JACOBIAN_NEAR_TOL(Hp, H, 1e-12, 1e-9 * H.cwiseAbs().maxCoeff());
  EXPECT_JACOBIAN_NEAR_TOL(bp, b, 1e-12, 1e-9 * b.cwiseAbs().maxCoeff());
  // A keyframe with no terms: none.
  c.window[0]->twist_energy = false;
  c.window[1]->imu_term = false;
  c.window[1]->twist_energy = false;
  term.linearizeInvolving(*c.window[0], c.window, c.layout, &kfs, &Hk, &bk);
  EXPECT_TRUE(kfs.empty());
}

// The prior's first-estimate behaviour with the global block: moved away from the linearisation point,
// the prior's gradient is b - H delta with delta including T_Wm_Wf's left log, and its energy matches.
TEST(InertialTerm, PriorWithGlobalBlockTracksTheGlobalDelta) {
  InertialChain c(false, true);
  const InertialTerm term(InertialTermOptions{}, c.T_cm_i, &c.globals);
  std::vector<Keyframe*> kfs;
  Eigen::MatrixXd Hk;
  Eigen::VectorXd bk;
  term.linearizeInvolving(*c.window[1], c.window, c.layout, &kfs, &Hk, &bk);
  MarginalizationPrior prior(c.layout);
  prior.setGlobals(&c.globals);
  prior.addTerm(kfs, Hk, bk, true);
  ASSERT_TRUE(c.globals.in_prior);
  EXPECT_NEAR(prior.energy(), 0.0, 1e-14 * prior.b().norm());  // at the linearisation point (round-off only)
  const RxSO3d T_lin = c.globals.state.T_wm_wf;
  const double off_lin = c.globals.state.time_offset_s;
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(c.dim());
  dx.segment(c.layout.globalOffset(3), 5) << 0.01, -0.02, 0.0, 0.03, 0.001;
  dx.segment(c.layout.imuOffset(1, 3), 3) << 0.02, 0.0, -0.01;
  c.apply(dx);
  const Eigen::VectorXd d = prior.delta();
  ASSERT_EQ(d.size(), prior.H().rows());
  Eigen::Matrix<double, 5, 1> dg;
  dg.head<4>() = (c.globals.state.T_wm_wf * T_lin.inverse()).log();
  dg[4] = c.globals.state.time_offset_s - off_lin;
  EXPECT_JACOBIAN_NEAR(d.tail(5), dg, 1e-12);
  EXPECT_JACOBIAN_NEAR(d.tail(5), dx.segment(c.layout.globalOffset(3), 5), 1e-9);
  // Energy of the quadratic model in that delta, and the window gradient b - H delta.
  const double e_model = d.dot(prior.H() * d) - 2.0 * prior.b().dot(d);
  Eigen::MatrixXd Hp = Eigen::MatrixXd::Zero(c.dim(), c.dim());
  Eigen::VectorXd bp = Eigen::VectorXd::Zero(c.dim());
  EXPECT_NEAR(prior.addTo(Hp, bp), e_model, 1e-12 * std::max(1.0, std::abs(e_model)));
  EXPECT_GT(std::abs(e_model), 1e-6);
  const Eigen::VectorXd g_prior = prior.b() - prior.H() * d;
  EXPECT_NEAR(bp[c.layout.globalOffset(3) + 3], g_prior[g_prior.size() - 2], 1e-12 * std::max(1.0, g_prior.norm()));
}

// The inertial state joins a visual prior: blocks grow, the visual information and energy stay.
TEST(InertialTerm, PriorSetLayoutKeepsTheVisualInformation) {
  StateLayout vis;
  vis.rolling = true;
  MarginalizationPrior prior(vis);
  KeyframeList w;
  for (int i = 0; i < 2; ++i) {
    w.push_back(std::make_unique<Keyframe>());
    w.back()->state.T_c_w = SE3d::exp(tw(0.1 * i, 0.2, -0.1, 0.05, 0.0, 0.1 * i));
  }
  reindex(w);
  std::vector<Keyframe*> kfs{w[0].get(), w[1].get()};
  Eigen::MatrixXd A = Eigen::MatrixXd::Random(28, 28);
  const Eigen::MatrixXd Ht = A * A.transpose();
  const Eigen::VectorXd bt = Eigen::VectorXd::Random(28);
  prior.addTerm(kfs, Ht, bt);
  w[1]->state.T_c_w = SE3d::exp(tw(0.01, 0, 0, 0, 0.02, 0)) * w[1]->state.T_c_w;
  const double e_vis = prior.energy();
  StateLayout vi = vis;
  vi.inertial = true;
  GlobalStates g;
  prior.setGlobals(&g);
  prior.setLayout(vi);
  EXPECT_EQ(prior.H().rows(), 2 * vi.stateDim() + vi.globalDim());
  EXPECT_NEAR(prior.energy(), e_vis, 1e-12 * std::abs(e_vis) + 1e-15);
  EXPECT_JACOBIAN_NEAR(prior.H().block(vi.stateDim(), vi.stateDim(), 14, 14), Ht.block(14, 14, 14, 14), 1e-12);
  EXPECT_EQ(prior.H().block(14, 0, 9, prior.H().cols()).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace rsvio

namespace rsvio {
namespace {

// With the inertial blocks the reduced camera system (Schur complement of the points) and the full
// system still give the same step, for a global and a rolling shutter: the points couple only to the
// photometric blocks, the inertial and global blocks only through the window terms.
void checkSchurAgainstFull(bool rolling) {
  test::TestWindow w(3, rolling, rolling ? 5e-5 : 0.0);
  w.addPoints(0, 200);
  w.addPoints(1, 150, 4);
  w.window[0]->gauge = true;
  InertialChain c(rolling, true);
  for (size_t k = 0; k < 3; ++k) {  // the chain's inertial states and factors on the rendered keyframes
    Keyframe& kf = *w.window[k];
    kf.t_ns = c.window[k]->t_ns;
    kf.state.v_wm = c.window[k]->state.v_wm;
    kf.state.bias_gyro = c.window[k]->state.bias_gyro;
    kf.state.bias_accel = c.window[k]->state.bias_accel;
    kf.gyro_at_t = c.window[k]->gyro_at_t;
    kf.twist_energy = rolling;
    if (k > 0) {
      kf.imu_term = true;
      kf.imu_prev = w.window[k - 1].get();
      kf.imu_factor = c.factors[k - 1];
    }
  }
  auto solver = test::makePlugin<SolverBackend>("solver.dense");
  BundleAdjustmentConfig cfg;
  cfg.layout = c.layout;
  BundleAdjuster ba(cfg, w.camera, w.timing, *solver);
  ba.setGlobals(&c.globals);
  const InertialTerm term(InertialTermOptions{}, c.T_cm_i, &c.globals);
  ba.setTerms({&term});
  MarginalizationPrior prior(cfg.layout);
  ba.linearize(w.window, prior);
  for (double lambda : {1e-4, 1e-2, 0.5}) {
    Eigen::VectorXd c1, p1, c2, p2;
    ASSERT_TRUE(ba.solveStep(lambda, false, &c1, &p1));
    ASSERT_TRUE(ba.solveStep(lambda, true, &c2, &p2));
    ASSERT_EQ(c1.size(), cfg.layout.windowDim(3));
    EXPECT_LT((c1 - c2).norm(), 1e-6 * (1.0 + c1.norm())) << "lambda " << lambda << "\n" << c1.transpose() << "\n" << c2.transpose();
    EXPECT_LT((p1 - p2).norm(), 1e-6 * (1.0 + p1.norm())) << "lambda " << lambda;
    EXPECT_GT(c1.tail(cfg.layout.globalDim()).norm(), 0.0);
  }
}

TEST(InertialTerm, SchurAndFullSystemGiveTheSameStepGlobalShutter) { checkSchurAgainstFull(false); }
TEST(InertialTerm, SchurAndFullSystemGiveTheSameStepRollingShutter) { checkSchurAgainstFull(true); }

}  // namespace
}  // namespace rsvio
