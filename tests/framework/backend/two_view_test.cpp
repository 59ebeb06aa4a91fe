// The two-view start of the monocular initialiser (solveTwoView, rsvio/backend/mono_initializer.h) on
// exact rolling-shutter correspondences: a scene seen by two frames that move with one constant twist,
// projected through the framework's rolling-shutter solve (geometry/rs_projection.h), with pixel noise.
// Conventions: T_c_w(t) = exp(xi (t - t_ref)) T_c_w(t_ref), xi per second (translation; rotation); the
// reference's central pose is the world; row times from RowTiming (image timestamp at row y0).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "rsvio/backend/mono_initializer.h"
#include "support/plugin_contracts.h"

namespace rsvio::test {
namespace {

double rotationErrorDeg(const SE3d& a, const SE3d& b) { return (a.so3() * b.so3().inverse()).log().norm() * 180.0 / M_PI; }

double directionErrorDeg(const Vec3& a, const Vec3& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

// Errors of the corrected (3 rounds) and the uncorrected (0 rounds) two-view pose on the same pixels.
struct TwoViewErrors {
  double rot_c, rot_i, dir_c, dir_i;
  TwoViewResult corrected;
};

class TwoViewTest : public ::testing::Test {
 protected:
  void SetUp() override {
    CameraCalibration c = defaultContractCalibration();
    c.width = 640;
    c.height = 512;
    c.intrinsics = Eigen::Vector4d(420.0, 420.0, 319.5, 255.5);
    c.distortion = "none";
    c.distortion_coeffs = Eigen::VectorXd();
    cam_ = makePlugin<CameraModel>("camera.pinhole");
    cam_->setCalibration(c);
    rolling_ = RowTiming::rolling(c.rowZero(), 58.94e-6, true);  // 30 ms readout, as configs/sim/demo.json
    // Handheld motion: 0.6 m/s and about 40 deg/s.
    xi_ << 0.45, -0.1, 0.38, 0.25, -0.55, 0.2;
  }

  // Matched pixels of a random scene, 2-6 m in front of the reference, seen by both frames.
  void correspondences(const RowTiming& timing, std::vector<Vec2>* ref_px, std::vector<Vec2>* cur_px) const {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> ux(-0.7, 0.7), uy(-0.55, 0.55), uz(2.0, 6.0);
    std::normal_distribution<double> unit(0.0, 1.0);
    auto noise = [&](std::mt19937_64& g) { return noise_px_ * unit(g); };
    const RsFrame ref{SE3d(), xi_}, cur{SE3d::exp(xi_ * dt_), xi_};
    RsProjectionOptions o;
    o.tolerance_px = 1e-9;
    o.jacobians = false;
    while (ref_px->size() < 300) {
      const double z = uz(rng);
      const Vec3 X(ux(rng) * z, uy(rng) * z, z);
      const RsProjection a = projectRollingShutter(*cam_, timing, ref, X, o);
      const RsProjection b = projectRollingShutter(*cam_, timing, cur, X, o);
      if (!a.valid || !b.valid) continue;
      const Vec2 na(noise(rng), noise(rng)), nb(noise(rng), noise(rng));
      ref_px->push_back(a.uv + na);
      cur_px->push_back(b.uv + nb);
    }
  }

  // The rolling-shutter scene with this pixel noise, solved with and without the rounds.
  TwoViewErrors roundsOnScene(double noise_px);

  // n exact pixels of a random scene at depths [z0, z1] in front of the world origin, seen by frames a
  // and b (rolling-shutter solve to 1e-10 px).
  void exactPixels(const RsFrame& fa, const RsFrame& fb, double z0, double z1, size_t n, uint64_t seed,
                   std::vector<Vec2>* pa, std::vector<Vec2>* pb) const {
    RsProjectionOptions o;
    o.tolerance_px = 1e-10;
    o.jacobians = false;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> ux(-0.7, 0.7), uy(-0.55, 0.55), uz(z0, z1);
    while (pa->size() < n) {
      const double z = uz(rng);
      const Vec3 X(ux(rng) * z, uy(rng) * z, z);
      const RsProjection a = projectRollingShutter(*cam_, rolling_, fa, X, o);
      const RsProjection b = projectRollingShutter(*cam_, rolling_, fb, X, o);
      if (!a.valid || !b.valid) continue;
      pa->push_back(a.uv);
      pb->push_back(b.uv);
    }
  }

  std::unique_ptr<CameraModel> cam_;
  RowTiming rolling_;
  Vec6 xi_;
  double dt_ = 0.2;  // four frames at 20 Hz
  double noise_px_ = 0.3;
};


TwoViewErrors compareRounds(const std::vector<Vec2>& a, const std::vector<Vec2>& b, const CameraModel& cam,
                            const RowTiming& timing, double dt, const SE3d& truth) {
  TwoViewOptions corrected, ignored;
  corrected.rolling_shutter_iterations = 3;
  ignored.rolling_shutter_iterations = 0;
  const TwoViewResult rc = solveTwoView(a, b, cam, timing, dt, 1, corrected);
  const TwoViewResult ri = solveTwoView(a, b, cam, timing, dt, 1, ignored);
  EXPECT_TRUE(rc.found) << rc.status;
  EXPECT_TRUE(ri.found) << ri.status;
  TwoViewErrors e{rotationErrorDeg(rc.T_cur_ref, truth), rotationErrorDeg(ri.T_cur_ref, truth),
                  directionErrorDeg(rc.T_cur_ref.translation(), truth.translation()),
                  directionErrorDeg(ri.T_cur_ref.translation(), truth.translation()), rc};
  std::cout << "rotation error " << e.rot_c << " deg corrected, " << e.rot_i << " deg ignored; translation direction "
            << e.dir_c << " against " << e.dir_i << " deg\n";
  return e;
}

TwoViewErrors TwoViewTest::roundsOnScene(double noise_px) {
  noise_px_ = noise_px;
  std::vector<Vec2> a, b;
  correspondences(rolling_, &a, &b);
  return compareRounds(a, b, *cam_, rolling_, dt_, SE3d::exp(xi_ * dt_));
}

// Exact correspondences: the readout is the only error, and the rounds remove it (measured: rotation
// 2e-6 against 0.089 deg, direction 6e-4 against 0.49 deg). Moving the bearings with +tau instead of
// -tau fails both rolling tests (shown once: rotation 0.18 deg, direction 1.0 deg).
TEST_F(TwoViewTest, RollingShutterRoundsRemoveTheReadoutFromThePose) {
  const TwoViewErrors e = roundsOnScene(0.0);
  EXPECT_LT(e.rot_c, 1e-3);
  EXPECT_LT(e.dir_c, 1e-2);
  EXPECT_GT(e.rot_i, 0.03);  // the readout is a real error here: the rounds earn their place
  EXPECT_GT(e.dir_i, 0.2);
  // The twist handed on: per second, translation in the start's scale (median depth 1).
  const TwoViewResult& rc = e.corrected;
  const double s = rc.T_cur_ref.translation().norm() / SE3d::exp(xi_ * dt_).translation().norm();
  EXPECT_LT((rc.xi.tail<3>() - xi_.tail<3>()).norm(), 1e-3 * xi_.tail<3>().norm()) << rc.xi.transpose();
  EXPECT_LT((rc.xi.head<3>() / s - xi_.head<3>()).norm(), 1e-3 * xi_.head<3>().norm()) << rc.xi.transpose();
}

// With 0.3 px of pixel noise the readout's bias is below the noise's spread (measured: rotation 0.050
// against 0.099 deg, direction 1.44 against 1.67 deg): the rounds still help and stay within bounds.
TEST_F(TwoViewTest, RollingShutterRoundsHoldUnderPixelNoise) {
  const TwoViewErrors e = roundsOnScene(0.3);
  EXPECT_LT(e.rot_c, 0.1);
  EXPECT_LT(e.dir_c, 2.0);
  EXPECT_LT(e.rot_c, e.rot_i);
  EXPECT_LT(e.dir_c, e.dir_i);
  EXPECT_GT(e.corrected.inlier_ratio, 0.9);
}

TEST_F(TwoViewTest, GlobalShutterIsExactAndHasNoTwist) {
  const RowTiming global = RowTiming::global(rolling_.y0);
  std::vector<Vec2> a, b;
  correspondences(global, &a, &b);
  const TwoViewResult r = solveTwoView(a, b, *cam_, global, dt_, 1, TwoViewOptions{});
  ASSERT_TRUE(r.found) << r.status;
  const SE3d truth = SE3d::exp(xi_ * dt_);
  EXPECT_LT(rotationErrorDeg(r.T_cur_ref, truth), 0.1);
  EXPECT_LT(directionErrorDeg(r.T_cur_ref.translation(), truth.translation()), 1.5);
  EXPECT_TRUE(r.xi.isZero());
  EXPECT_GT(r.inlier_ratio, 0.95);
}

// The start's rotation rate changes by more than its mean between the two images (as on the demo
// sequences: the readout's shear then differs between them): ref turns at w_a, cur at w_b about
// another axis; the central poses are 0.35 s apart. Each image's bearings rotated with its own rate
// (use_rates) against the readout ignored and against the rounds with one constant twist for both.
TEST_F(TwoViewTest, EachImagesOwnRotationRateRemovesTheChangingReadoutShear) {
  Vec6 xa, xb;
  xa << 0.36, 0.0, 0.63, -0.44, 0.10, -0.14;
  xb << 0.71, 0.08, 0.66, 0.43, -0.92, -0.01;
  const double dt = 0.35;
  const SE3d T_cur = SE3d::exp(0.5 * (xa + xb) * dt);
  std::vector<Vec2> a, b;
  exactPixels(RsFrame{SE3d(), xa}, RsFrame{T_cur, xb}, 4.0, 12.0, 300, 3, &a, &b);
  TwoViewOptions own, ignored, rounds;
  own.use_rates = true;
  own.w_ref = xa.tail<3>();
  own.w_cur = xb.tail<3>();
  ignored.rolling_shutter_iterations = 0;
  rounds.rolling_shutter_iterations = 3;
  const TwoViewResult ro = solveTwoView(a, b, *cam_, rolling_, dt, 1, own);
  const TwoViewResult ri = solveTwoView(a, b, *cam_, rolling_, dt, 1, ignored);
  const TwoViewResult rr = solveTwoView(a, b, *cam_, rolling_, dt, 1, rounds);
  ASSERT_TRUE(ro.found) << ro.status;
  ASSERT_TRUE(ri.found) << ri.status;
  ASSERT_TRUE(rr.found) << rr.status;
  const double d_own = directionErrorDeg(ro.T_cur_ref.translation(), T_cur.translation());
  const double d_ign = directionErrorDeg(ri.T_cur_ref.translation(), T_cur.translation());
  const double d_rnd = directionErrorDeg(rr.T_cur_ref.translation(), T_cur.translation());
  std::cout << "translation direction error: own rates " << d_own << " deg, readout ignored " << d_ign
            << " deg, one constant twist " << d_rnd << " deg; rotation " << rotationErrorDeg(ro.T_cur_ref, T_cur)
            << " / " << rotationErrorDeg(ri.T_cur_ref, T_cur) << " / " << rotationErrorDeg(rr.T_cur_ref, T_cur)
            << " deg\n";
  // Measured: direction 0.27 deg (own rates) against 1.02 (ignored) and 0.42 (one twist); rotation
  // 0.033 against 0.50 and 0.51 deg. What is left is the readout's translational part (not corrected).
  // Rotating the bearings with +tau instead of -tau fails it (shown once: rotation 3.3 deg).
  EXPECT_LT(d_own, 0.5 * d_ign);
  EXPECT_LT(d_own, 0.8 * d_rnd);
  EXPECT_LT(rotationErrorDeg(ro.T_cur_ref, T_cur), 0.25 * rotationErrorDeg(ri.T_cur_ref, T_cur));
  // Each image's twist handed on: its own rate.
  EXPECT_TRUE(ro.xi_ref.tail<3>().isApprox(xa.tail<3>()));
  EXPECT_TRUE(ro.xi_cur.tail<3>().isApprox(xb.tail<3>()));
  EXPECT_NE(ro.status.find("each image's rotation rate"), std::string::npos) << ro.status;
}

// fitRotationRate on one frame interval (50 ms) of a pure rotation, each bearing read at its own row:
// exact; with the rows' times left out (dt_k = dt) it is 1 % off (shown once: 0.012 rad/s), so the test
// sees them. With the demo's translation (0.6 m/s, scene at 2-6 m) the neglected translation's flow
// moves the rate by 0.11 rad/s (measured), about an eighth of the rate.
TEST_F(TwoViewTest, FitRotationRateRecoversTheRateOfOneFrameInterval) {
  for (const bool translating : {false, true}) {
    Vec6 xi;
    xi << (translating ? Vec3(0.45, -0.1, 0.38) : Vec3::Zero()), Vec3(0.43, -0.92, -0.01);
    const double dt = 0.05;
    std::vector<Vec2> pa, pb;
    exactPixels(RsFrame{SE3d(), xi}, RsFrame{SE3d::exp(xi * dt), xi}, 2.0, 6.0, 200, 5, &pa, &pb);
    std::vector<Vec3> ba, bb;
    std::vector<double> ta, tb;
    for (size_t k = 0; k < pa.size(); ++k) {
      Eigen::Matrix2Xd u(2, 2);
      u << pa[k], pb[k];
      Eigen::Matrix3Xd bear;
      std::vector<uint8_t> valid;
      cam_->unproject(u, bear, valid);
      ba.push_back(bear.col(0).normalized());
      bb.push_back(bear.col(1).normalized());
      ta.push_back(rolling_.rowTime(pa[k].y()));
      tb.push_back(rolling_.rowTime(pb[k].y()));
    }
    Vec3 w;
    ASSERT_TRUE(fitRotationRate(ba, ta, bb, tb, dt, &w));
    const double err = (w - xi.tail<3>()).norm();
    std::cout << (translating ? "translating" : "pure rotation") << ": rate error " << err << " rad/s\n";
    EXPECT_LT(err, translating ? 0.2 : 1e-6);
  }
  std::vector<Vec3> few(5, Vec3::UnitZ());
  std::vector<double> t0(5, 0.0);
  Vec3 w;
  EXPECT_FALSE(fitRotationRate(few, t0, few, t0, 0.05, &w));
}

TEST_F(TwoViewTest, TooFewCorrespondencesAreRefusedWithAReason) {
  std::vector<Vec2> a(10, Vec2(100, 100)), b(10, Vec2(110, 100));
  const TwoViewResult r = solveTwoView(a, b, *cam_, rolling_, dt_, 1, TwoViewOptions{});
  EXPECT_FALSE(r.found);
  EXPECT_NE(r.status.find("too few"), std::string::npos);
}

}  // namespace
}  // namespace rsvio::test
