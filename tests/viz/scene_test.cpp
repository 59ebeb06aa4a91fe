// 3D views rendered off-screen with DISPLAY unset: the PNGs have the asked size and show the trajectory's
// colours where the trajectory projects; a failed run still gives a picture of its error.
#include <gtest/gtest.h>

#include <cstdlib>
#include <opencv2/imgcodecs.hpp>

#include "rsvio/io/snapshot.h"
#include "rsvio/viz/colormap.h"
#include "rsvio/viz/display_guard.h"
#include "rsvio/viz/scene.h"
#include "run_fixture.h"

namespace rsvio::viz {
namespace {
using test::isSaturated;

constexpr int kW = 320, kH = 240;

// The longest horizontal run of saturated pixels in rows [r0, r1]: returns (row, first col, last col).
struct PixelRun {
  int row = -1, x0 = 0, x1 = -1;
  int length() const { return x1 - x0 + 1; }
};
PixelRun longestRun(const cv::Mat& img, int r0, int r1) {
  PixelRun best;
  for (int r = r0; r <= r1; ++r) {
    int start = -1;
    for (int c = 0; c <= img.cols; ++c) {
      const bool on = c < img.cols && isSaturated(img.at<cv::Vec3b>(r, c));
      if (on && start < 0) start = c;
      if (!on && start >= 0) {
        if (c - start > best.length()) best = {r, start, c - 1};
        start = -1;
      }
    }
  }
  return best;
}

class SceneTest : public ::testing::Test {
 protected:
  void SetUp() override { ::unsetenv("DISPLAY"); }
};

TEST_F(SceneTest, StraightTrajectoryTopViewWithoutGroundTruthIsPlainBlue) {
  test::TempDir tmp("scene_plain");
  test::RunSpec spec;  // along x from 0 to 9.95 m at y = z = 0
  spec.points = false;
  const auto run = test::makeRun(tmp.path, spec);
  const io::Snapshot snap = io::readSnapshot(run.string());
  ASSERT_FALSE(snap.errors.has_value());
  DisplayGuard guard;
  ASSERT_TRUE(guard.ok()) << guard.message();
  SceneOptions o;
  o.width = kW;
  o.height = kH;
  o.views = {View::kTop, View::kSide, View::kPerspective};
  o.show_frusta = false;  // keyframe frusta sit on the line and are drawn in their own colour
  const auto files = renderScenes(snap, o, (tmp.path / "fig").string());
  ASSERT_EQ(files.size(), 3u);
  for (const auto& f : files) {
    const cv::Mat img = cv::imread(f);
    ASSERT_FALSE(img.empty()) << f;
    EXPECT_EQ(img.cols, kW);
    EXPECT_EQ(img.rows, kH);
  }
  // Top view: the line y = 0 projects onto the middle rows and spans most of the width (no colour bar
  // without errors, so the scene has the whole width).
  const cv::Mat top = cv::imread(files[0]);
  const PixelRun run_px = longestRun(top, kH / 2 - 3, kH / 2 + 3);
  ASSERT_GT(run_px.length(), kW * 0.7) << "row " << run_px.row;
  for (double f : {0.1, 0.5, 0.9}) {
    const cv::Vec3b p = top.at<cv::Vec3b>(run_px.row, run_px.x0 + static_cast<int>(f * run_px.length()));
    // The estimate's plain colour (31, 119, 180) in BGR.
    EXPECT_NEAR(p[0], 180, 30) << f;
    EXPECT_NEAR(p[1], 119, 30) << f;
    EXPECT_NEAR(p[2], 31, 30) << f;
  }
  // Away from the line (a quarter of the height above it) the view is background, not trajectory.
  EXPECT_LT(longestRun(top, kH / 4, kH / 4).length(), 5);
}

TEST_F(SceneTest, TrajectoryIsColouredByErrorWhereItProjects) {
  test::TempDir tmp("scene_err");
  test::RunSpec spec;
  spec.points = false;
  // Ground truth dips 0.5 m below the estimate over the middle fifth; SE(3) alignment (symmetric
  // problem) shifts the estimate down a little, so the error is small outside and large inside.
  spec.gt = [](int i) { return Eigen::Vector3d(0.05 * i, 0, (i >= 80 && i < 120) ? -0.5 : 0.0); };
  const auto run = test::makeRun(tmp.path, spec);
  const io::Snapshot snap = io::readSnapshot(run.string());
  ASSERT_TRUE(snap.errors.has_value()) << (snap.notes.empty() ? "" : snap.notes.back());
  DisplayGuard guard;
  ASSERT_TRUE(guard.ok()) << guard.message();
  SceneOptions o;
  o.width = kW;
  o.height = kH;
  o.views = {View::kTop};
  o.show_ground_truth = false;  // the ground truth would hide the estimate where they coincide
  o.show_frusta = false;
  const auto files = renderScenes(snap, o, (tmp.path / "fig").string());
  const cv::Mat top = cv::imread(files.at(0));
  ASSERT_EQ(top.cols, kW);
  ASSERT_EQ(top.rows, kH);
  const PixelRun r = longestRun(top, kH / 2 - 3, kH / 2 + 3);
  ASSERT_GT(r.length(), kW * 0.6);
  const cv::Vec3b mid = top.at<cv::Vec3b>(r.row, r.x0 + r.length() / 2);
  const cv::Vec3b end = top.at<cv::Vec3b>(r.row, r.x0 + r.length() / 10);
  // Middle: the top of the turbo map (dark red). End: its lower part (blue/cyan).
  const Rgb hot = errorMap(1.0);
  EXPECT_NEAR(mid[2], hot.r, 40);
  EXPECT_NEAR(mid[1], hot.g, 40);
  EXPECT_NEAR(mid[0], hot.b, 40);
  EXPECT_GT(end[0], end[2]) << "low error should be blue-ish";
}

TEST_F(SceneTest, FailedRunStillRendersItsError) {
  test::TempDir tmp("scene_failed");
  const auto run = test::makeFailedRun(tmp.path, "numerical instability at frame 12");
  const io::Snapshot snap = io::readSnapshot(run.string());
  EXPECT_TRUE(snap.failed());
  DisplayGuard guard;
  ASSERT_TRUE(guard.ok()) << guard.message();
  SceneOptions o;
  o.width = kW;
  o.height = kH;
  o.views = {View::kTop};
  const auto files = renderScenes(snap, o, (tmp.path / "fig").string());
  const cv::Mat img = cv::imread(files.at(0));
  ASSERT_EQ(img.cols, kW);
  ASSERT_EQ(img.rows, kH);
  // The message is drawn in red around the middle of the image.
  int red = 0;
  for (int r = kH / 3; r < 2 * kH / 3; ++r) {
    for (int c = 0; c < kW; ++c) {
      const cv::Vec3b p = img.at<cv::Vec3b>(r, c);
      if (p[2] > 150 && p[1] < 120 && p[0] < 120) ++red;
    }
  }
  EXPECT_GT(red, 30);
}

}  // namespace
}  // namespace rsvio::viz
