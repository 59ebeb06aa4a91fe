// Rolling-shutter projection of host-frame points (bearing, host row, inverse depth): agreement with
// the world-point form, Jacobians w.r.t. host pose, host twist, inverse depth and the (shared) line
// delay against numeric differences, the batch API, and RowTiming from the shutter plugins.
#include <gtest/gtest.h>

#include "rsvio/geometry/rs_projection.h"
#include "support/numeric_jacobian.h"
#include "support/plugin_contracts.h"

namespace rsvio::test {
namespace {

class RsHostProjectionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    CameraCalibration c = defaultContractCalibration();
    c.distortion = "equidistant";
    c.intrinsics = Eigen::Vector4d(160.0, 161.0, 159.5, 127.5);
    c.distortion_coeffs = Eigen::Vector4d(0.0035, 0.0067, -0.0087, 0.0029);
    cam_ = makePlugin<CameraModel>("camera.pinhole");
    cam_->setCalibration(c);
    timing_ = RowTiming::rolling(c.rowZero(), 4e-5, true);
    target_.T_c_w0 = SE3d(SO3d::exp(Vec3(0.1, -0.2, 0.05)), Vec3(0.3, -0.1, 0.2));
    target_.xi << 0.8, -0.3, 0.5, 0.6, -1.2, 0.4;
    host_.T_c_w0 = SE3d(SO3d::exp(Vec3(0.05, -0.1, 0.02)), Vec3(0.1, 0.0, 0.3));
    host_.xi << -0.5, 0.2, 0.3, -0.4, 0.9, -0.2;
  }

  // Host pixel -> (bearing, row).
  void hostPoint(const Vec2& px, Vec3& b, double& v_h) const {
    ASSERT_TRUE(cam_->unproject(px, b));
    v_h = px.y();
  }

  RsProjectionOptions exact(bool jac = true) const {
    RsProjectionOptions o;
    o.tolerance_px = 1e-11;
    o.max_iterations = 50;
    o.jacobians = jac;
    return o;
  }

  static RsFrame withWDot(RsFrame f, const Vec3& w_dot) {
    f.w_dot = w_dot;
    return f;
  }
  // Angular accelerations of a violent turn (rad/s^2): at the outer rows (5 ms) about 0.3 mrad of rotation.
  const Vec3 kHostWDot = Vec3(12.0, -20.0, 6.0), kTargetWDot = Vec3(-9.0, 15.0, 25.0);

  std::unique_ptr<CameraModel> cam_;
  RowTiming timing_;
  RsFrame target_, host_;
};

TEST_F(RsHostProjectionTest, EqualsTheWorldPointForm) {
  Vec3 b;
  double v_h;
  hostPoint(Vec2(70.0, 200.0), b, v_h);
  const double rho = 0.4;
  for (bool acc : {false, true}) {
    RsFrame host = host_, target = target_;
    if (acc) host.w_dot = kHostWDot, target.w_dot = kTargetWDot;
    const RsHostProjection r = projectRollingShutter(*cam_, timing_, host, target, b, v_h, rho);
    // The host saw the point at its row's time: X = T_h_w(t_h)^-1 (b / rho).
    const SE3d T_h_w = acc ? rsPoseAt(host, timing_.rowTime(v_h)) : SE3d::exp(host.xi * timing_.rowTime(v_h)) * host.T_c_w0;
    const Vec3 X = T_h_w.inverse() * Vec3(b / rho);
    const RsProjection w = projectRollingShutter(*cam_, timing_, target, X);
    ASSERT_TRUE(r.valid);
    EXPECT_LT((r.uv - w.uv).norm(), 1e-9);
    EXPECT_JACOBIAN_NEAR(r.d_uv_d_T0, w.d_uv_d_T0, 1e-9);
    EXPECT_JACOBIAN_NEAR(r.d_uv_d_xi, w.d_uv_d_xi, 1e-9);
  }
}

// With w_dot (RsFrame: the rows' rotation to second order) on host and target, every Jacobian is checked
// again: the twists' through A(t), the line delay's through A's own time derivative.
TEST_F(RsHostProjectionTest, JacobiansMatchNumeric) {
  for (bool acc : {false, true})
  for (bool top_down : {true, false}) {
    const RsFrame host_ = acc ? withWDot(this->host_, kHostWDot) : this->host_;
    const RsFrame target_ = acc ? withWDot(this->target_, kTargetWDot) : this->target_;
    const RowTiming tm = RowTiming::rolling(timing_.y0, 4e-5, top_down);
    for (const Vec2& px : {Vec2(70.0, 200.0), Vec2(250.0, 30.0), Vec2(159.5, 127.5), Vec2(0.0, 255.0)}) {
      for (double rho : {0.05, 0.5, 3.0}) {
        Vec3 b;
        double v_h;
        hostPoint(px, b, v_h);
        const RsHostProjection r = projectRollingShutter(*cam_, tm, host_, target_, b, v_h, rho, exact());
        if (!r.valid) continue;  // a corner of the wide-angle host may leave the target's view
        SCOPED_TRACE(::testing::Message() << "px " << px.transpose() << " rho " << rho << " top_down " << top_down
                                          << " w_dot " << acc);
        const auto uvAt = [&](const RowTiming& t, const RsFrame& h, const RsFrame& f, double r_) {
          return projectRollingShutter(*cam_, t, h, f, b, v_h, r_, exact(false)).uv;
        };
        const auto byHostPose = [&](const SE3d& T) { return uvAt(tm, RsFrame{T, host_.xi, host_.w_dot}, target_, rho); };
        const auto byHostTwist = [&](const Vec6& xi) {
          return uvAt(tm, RsFrame{host_.T_c_w0, xi, host_.w_dot}, target_, rho);
        };
        const auto byTargetPose = [&](const SE3d& T) {
          return uvAt(tm, host_, RsFrame{T, target_.xi, target_.w_dot}, rho);
        };
        const auto byTargetTwist = [&](const Vec6& xi) {
          return uvAt(tm, host_, RsFrame{target_.T_c_w0, xi, target_.w_dot}, rho);
        };
        const auto byIdepth = [&](double r_) { return uvAt(tm, host_, target_, r_); };
        const auto byDelay = [&](double ld) {
          RowTiming t = tm;
          t.line_delay_s = ld;
          return uvAt(t, host_, target_, rho);
        };
        EXPECT_JACOBIAN_NEAR_TOL(r.d_uv_d_Th0, numericJacobian(byHostPose, host_.T_c_w0, leftPlus<SE3d>, 6, 1e-5),
                                 1e-6, 1e-5);
        EXPECT_JACOBIAN_NEAR_TOL(r.d_uv_d_xi_h, numericJacobian(byHostTwist, host_.xi, vectorPlus, 6, 1e-5), 1e-6,
                                 1e-5);
        EXPECT_JACOBIAN_NEAR_TOL(r.d_uv_d_T0, numericJacobian(byTargetPose, target_.T_c_w0, leftPlus<SE3d>, 6, 1e-5),
                                 1e-6, 1e-5);
        EXPECT_JACOBIAN_NEAR_TOL(r.d_uv_d_xi, numericJacobian(byTargetTwist, target_.xi, vectorPlus, 6, 1e-5), 1e-6,
                                 1e-5);
        EXPECT_JACOBIAN_NEAR_TOL(r.d_uv_d_idepth, numericJacobian(byIdepth, rho, vectorPlus, 1, 1e-6 * rho), 1e-6,
                                 1e-5);
        EXPECT_JACOBIAN_NEAR_TOL(r.d_uv_d_line_delay, numericJacobian(byDelay, tm.line_delay_s, vectorPlus, 1, 1e-8),
                                 1e-6, 1e-2);
      }
    }
  }
}

// The identity the bundle adjustment's accumulation stands on (ba_accumulate.cpp, accumulateChunkRolling):
// the pixel depends on the central poses only through T_t^0 (T_h^0)^-1, so with left perturbations
// d uv / d host pose = -(d uv / d target pose) Adj(T_t^0 (T_h^0)^-1), with readout, twists, angular
// accelerations and either readout direction alike.
TEST_F(RsHostProjectionTest, HostPoseJacobianIsMinusTheTargetsThroughThePairAdjoint) {
  const Eigen::Matrix<double, 6, 6> A = (target_.T_c_w0 * host_.T_c_w0.inverse()).Adj();
  int checked = 0;
  for (bool acc : {false, true})
    for (bool top_down : {true, false}) {
      const RsFrame host = acc ? withWDot(host_, kHostWDot) : host_;
      const RsFrame target = acc ? withWDot(target_, kTargetWDot) : target_;
      const RowTiming tm = RowTiming::rolling(timing_.y0, 4e-5, top_down);
      for (const Vec2& px : {Vec2(70.0, 200.0), Vec2(250.0, 30.0), Vec2(159.5, 127.5)})
        for (double rho : {0.05, 0.5, 3.0}) {
          Vec3 b;
          double v_h;
          hostPoint(px, b, v_h);
          const RsHostProjection r = projectRollingShutter(*cam_, tm, host, target, b, v_h, rho, exact());
          if (!r.valid) continue;
          const Mat26 from_target = -r.d_uv_d_T0 * A;
          EXPECT_JACOBIAN_NEAR_TOL(r.d_uv_d_Th0, from_target, 1e-9, 1e-9);
          ++checked;
        }
    }
  EXPECT_GE(checked, 30);
}

TEST_F(RsHostProjectionTest, NonPositiveInverseDepthIsInvalid) {
  Vec3 b;
  double v_h;
  hostPoint(Vec2(100.0, 100.0), b, v_h);
  EXPECT_FALSE(projectRollingShutter(*cam_, timing_, host_, target_, b, v_h, 0.0).valid);
  EXPECT_FALSE(projectRollingShutter(*cam_, timing_, host_, target_, b, v_h, -0.3).valid);
  EXPECT_FALSE(projectRollingShutter(*cam_, timing_, host_, target_, b, v_h, std::nan("")).valid);
}

TEST_F(RsHostProjectionTest, BatchEqualsSinglePoints) {
  const int n = 40;
  Eigen::Matrix3Xd B(3, n);
  Eigen::VectorXd v_h(n), rho(n);
  for (int i = 0; i < n; ++i) {
    const Vec2 px(8.0 * i, 6.0 * i + 3.0);
    Vec3 b;
    ASSERT_TRUE(cam_->unproject(px, b));
    B.col(i) = b;
    v_h[i] = px.y();
    rho[i] = (i % 7 == 3) ? -1.0 : 0.1 + 0.05 * i;  // some invalid ones in between
  }
  std::vector<RsHostProjection> out;
  projectRollingShutter(*cam_, timing_, host_, target_, B, v_h, rho, out);
  ASSERT_EQ(out.size(), static_cast<size_t>(n));
  int n_valid = 0;
  for (int i = 0; i < n; ++i) {
    const RsHostProjection s = projectRollingShutter(*cam_, timing_, host_, target_, Vec3(B.col(i)), v_h[i], rho[i]);
    ASSERT_EQ(out[i].valid, s.valid) << i;
    if (!s.valid) continue;
    ++n_valid;
    EXPECT_EQ(out[i].uv, s.uv);
    EXPECT_EQ(out[i].d_uv_d_Th0, s.d_uv_d_Th0);
    EXPECT_EQ(out[i].d_uv_d_line_delay, s.d_uv_d_line_delay);
  }
  EXPECT_GT(n_valid, n / 2);
}

TEST_F(RsHostProjectionTest, GivenHostPointsGiveTheSameBitsAsComputedOnes) {
  // The bundle adjustment computes each point's host part once (rsHostPoint) and projects it into every
  // target with the overload that takes it; that must be the projection that computes it itself.
  const int n = 30;
  Eigen::Matrix3Xd B(3, n);
  Eigen::VectorXd v_h(n), rho(n);
  std::vector<RsHostPoint> hp(static_cast<size_t>(n));
  const TwistExp ex(host_.xi);
  for (int i = 0; i < n; ++i) {
    const Vec2 px(10.0 * i + 4.0, 8.0 * i + 2.0);
    Vec3 b;
    ASSERT_TRUE(cam_->unproject(px, b));
    B.col(i) = b;
    v_h[i] = px.y();
    rho[i] = (i % 9 == 4) ? 0.0 : 0.2 + 0.03 * i;
    if (rho[i] > 0) hp[static_cast<size_t>(i)] = rsHostPoint(ex, timing_.rowTime(v_h[i]), b, rho[i], true);
  }
  std::vector<RsHostProjection> computed, given;
  projectRollingShutter(*cam_, timing_, host_, target_, B, v_h, rho, computed);
  projectRollingShutter(*cam_, timing_, host_, target_, B, v_h, rho, hp, given);
  int n_valid = 0;
  for (int i = 0; i < n; ++i) {
    ASSERT_EQ(given[i].valid, computed[i].valid) << i;
    if (!computed[i].valid) continue;
    ++n_valid;
    EXPECT_EQ(given[i].uv, computed[i].uv) << i;
    EXPECT_EQ(given[i].d_uv_d_Th0, computed[i].d_uv_d_Th0) << i;
    EXPECT_EQ(given[i].d_uv_d_xi_h, computed[i].d_uv_d_xi_h) << i;
    EXPECT_EQ(given[i].d_uv_d_idepth, computed[i].d_uv_d_idepth) << i;
    EXPECT_EQ(given[i].d_uv_d_line_delay, computed[i].d_uv_d_line_delay) << i;
    EXPECT_EQ(given[i].d_uv_d_xi, computed[i].d_uv_d_xi) << i;
  }
  EXPECT_GT(n_valid, n / 2);
  // A host part of another host twist is not the same projection (the given one is what is used).
  hp[1] = rsHostPoint(TwistExp(Vec6::Zero()), timing_.rowTime(v_h[1]), B.col(1), rho[1], true);
  projectRollingShutter(*cam_, timing_, host_, target_, B, v_h, rho, hp, given);
  EXPECT_GT((given[1].uv - computed[1].uv).norm(), 1e-3);
}

TEST_F(RsHostProjectionTest, RowTimingFromShutterPlugins) {
  CameraCalibration calib = cam_->calibration();
  calib.line_delay_s = 0.0;
  for (const char* readout : {"top_down", "bottom_up"}) {
    auto rs = makePlugin<ShutterModel>("shutter.rolling", {{"line_delay_us", 25.0}, {"readout", readout}});
    rs->setCalibration(calib);
    const RowTiming t = RowTiming::from(*rs, *cam_);
    EXPECT_EQ(t.y0, calib.rowZero());
    EXPECT_DOUBLE_EQ(t.line_delay_s, 25e-6);
    EXPECT_EQ(t.direction, std::string(readout) == "top_down" ? 1.0 : -1.0);
    for (double v : {0.0, 100.0, 255.0}) EXPECT_NEAR(t.rowTime(v), rs->rowTime(v), 1e-18);
  }
  auto gs = makePlugin<ShutterModel>("shutter.global");
  gs->setCalibration(calib);
  const RowTiming t = RowTiming::from(*gs, *cam_);
  EXPECT_EQ(t.dtDv(), 0.0);
  EXPECT_EQ(t.dRowTimeDLineDelay(10.0), 0.0);
}

}  // namespace
}  // namespace rsvio::test
