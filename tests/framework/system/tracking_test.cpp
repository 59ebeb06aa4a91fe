// Tracking's rotation rate for a rolling-shutter frame's twist (framework/src/system/tracking.h): the
// twist retries re-estimate a lost frame's rotation from the pose its attempt reached, extrapolated to
// the frame's time. Exact for a rate that changes linearly about a fixed axis (each interval's mean
// rate is then the rate at its middle); the plain frame-to-frame rate lags by half an interval plus
// the time to the new frame.
#include <gtest/gtest.h>

#include "framework/photometric/test_camera.h"
#include "framework/src/system/tracking.h"

namespace rsvio {
namespace {

constexpr int64_t kT0 = 1'600'000'000'000'000'000;

struct RateFixture {
  test::PinholeK K;
  test::TestPinholeCamera camera{K};
  RowTiming timing = RowTiming::rolling(127.5, 100e-6, true);
  Tracking tracking{TrackerOptions(), camera, timing, {}};
  Vec3 axis = Vec3(0.3, -0.8, 0.52).normalized();
  double w0 = 0.4, alpha = 6.0;  // rad/s, rad/s^2 (a sudden turn of the fast preset)

  // R_c_w(t) = exp(theta(t) axis), theta = w0 t + alpha t^2 / 2: its left rate is (w0 + alpha t) axis.
  SE3d pose(double t) const {
    Vec6 xi = Vec6::Zero();
    xi.tail<3>() = (w0 * t + 0.5 * alpha * t * t) * axis;
    xi.head<3>() = Vec3(0.1, 0.0, -0.05);
    return SE3d::exp(xi);
  }
  Vec3 rate(double t) const { return (w0 + alpha * t) * axis; }
  static int64_t ns(double t) { return kT0 + static_cast<int64_t>(t * 1e9 + 0.5); }
};

TEST(Tracking, RotationRateAtExtrapolatesTheLastTwoIntervalRatesToTheFramesTime) {
  RateFixture f;
  for (double t : {0.0, 0.05, 0.10}) f.tracking.pushHistory(RateFixture::ns(t), f.pose(t), false);
  // The next frame at 0.15 s: the last interval's mean rate lags it by 75 ms, 0.45 rad/s here.
  const Vec3 lagging = f.tracking.velocityEstimate().tail<3>();
  EXPECT_GT((lagging - f.rate(0.15)).norm(), 0.4);
  EXPECT_LT((f.tracking.rotationRateAt(RateFixture::ns(0.15)) - f.rate(0.15)).norm(), 1e-6);
  // With the frame's own (tracked) pose the newest interval ends at the frame.
  const SE3d T = f.pose(0.15);
  EXPECT_LT((f.tracking.rotationRateAt(RateFixture::ns(0.15), &T) - f.rate(0.15)).norm(), 1e-6);
  // At the newest history entry's time: the rate there, not the interval's mean.
  EXPECT_LT((f.tracking.rotationRateAt(RateFixture::ns(0.10)) - f.rate(0.10)).norm(), 1e-6);
}

TEST(Tracking, RotationRateAtHandlesUnevenIntervalsAndShortHistories) {
  RateFixture f;
  EXPECT_EQ(f.tracking.rotationRateAt(RateFixture::ns(0.0)), Vec3::Zero());  // no history
  f.tracking.pushHistory(RateFixture::ns(0.0), f.pose(0.0), false);
  const SE3d T1 = f.pose(0.05);
  // One interval: its mean rate.
  EXPECT_LT((f.tracking.rotationRateAt(RateFixture::ns(0.05), &T1) - f.rate(0.025)).norm(), 1e-6);
  // A dropped frame: intervals of 50 and 100 ms.
  f.tracking.pushHistory(RateFixture::ns(0.05), T1, false);
  f.tracking.pushHistory(RateFixture::ns(0.15), f.pose(0.15), false);
  EXPECT_LT((f.tracking.rotationRateAt(RateFixture::ns(0.20)) - f.rate(0.20)).norm(), 1e-6);
}

}  // namespace
}  // namespace rsvio
