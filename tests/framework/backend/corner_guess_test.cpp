// The monocular start's corner tracks through a fast turn (MonoInitializer::setTrackGuessSource,
// rsvio/backend/mono_initializer.h): images of a book-shelf-like texture (vertical bars 2-6 px wide,
// the repetition that makes Lucas-Kanade slip by a bar) related by a camera rotation that moves every
// corner by about 40 px per frame (and, in the last test, a sideways flow the rotation does not
// explain). Convention: camera coordinates at the later image are R_1_0 times those at the earlier
// (left form, as the gyroscope's source gives it), so pixels map by K R_1_0 K^-1.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <opencv2/imgproc.hpp>
#include <random>

#include "rsvio/backend/mono_initializer.h"
#include "support/plugin_contracts.h"

namespace rsvio::test {
namespace {

class CornerGuessTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const CameraCalibration c = defaultContractCalibration();  // 320x256 pinhole, f 250 px, no distortion
    cam_ = makePlugin<CameraModel>("camera.pinhole");
    cam_->setCalibration(c);
    K_ << c.intrinsics[0], 0.0, c.intrinsics[2], 0.0, c.intrinsics[1], c.intrinsics[3], 0.0, 0.0, 1.0;
    R_ = SO3d::exp(Vec3(0.03, 0.16, 0.02));  // about 40 px of flow, mostly along the rows
    // A wall of shelves: books as vertical bars of random width and grey, each with its own top edge.
    canvas_ = cv::Mat(256 + 2 * kMargin, 320 + 2 * kMargin, CV_32F, cv::Scalar(90.0f));
    std::mt19937 rng(3);
    std::uniform_int_distribution<int> width(2, 6), grey(25, 230), top(0, 25);
    for (int shelf = 0; shelf + 60 <= canvas_.rows; shelf += 60)
      for (int x = 0; x < canvas_.cols;) {
        const int w = std::min(width(rng), canvas_.cols - x);
        cv::rectangle(canvas_, cv::Rect(x, shelf + 8 + top(rng), w, 60 - 8 - 25), cv::Scalar(grey(rng)), cv::FILLED);
        x += w;
      }
    cv::GaussianBlur(canvas_, canvas_, cv::Size(3, 3), 0.7);
  }

  // The image of a camera rotated by R from the first (the first image: R = identity), every pixel
  // then moved by shift_px (what a translation parallel to a wall does), its brightness times gain.
  std::shared_ptr<const ImagePyramid> image(const SO3d& R, const Vec2& shift_px = Vec2::Zero(),
                                            double gain = 1.0) const {
    // Destination pixel x1 -> source x0 = K R^-1 K^-1 (x1 - shift), then into the canvas (offset kMargin).
    Eigen::Matrix3d T = Eigen::Matrix3d::Identity(), S = Eigen::Matrix3d::Identity();
    T(0, 2) = T(1, 2) = kMargin;
    S(0, 2) = -shift_px.x();
    S(1, 2) = -shift_px.y();
    const Eigen::Matrix3d M = T * K_ * R.inverse().matrix() * K_.inverse() * S;
    cv::Mat Mcv(3, 3, CV_64F);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) Mcv.at<double>(r, c) = M(r, c);
    cv::Mat out;
    cv::warpPerspective(canvas_, out, Mcv, cv::Size(320, 256), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                        cv::BORDER_REPLICATE);
    out *= gain;
    return std::make_shared<ImagePyramid>(out, 5);
  }

  // A start that only tracks (no attempt at a pose); with_source: its guesses turn by R_ per 50 ms.
  std::unique_ptr<MonoInitializer> start(bool with_source) const {
    BackendOptions o;
    o.init_min_frames = 10;
    auto init = std::make_unique<MonoInitializer>(o, *cam_, RowTiming::global(0.0));
    if (with_source)
      init->setTrackGuessSource([this](int64_t t0, int64_t t1, SO3d* R) {
        if (t1 - t0 != 50'000'000) return false;
        *R = R_;
        return true;
      });
    return init;
  }

  // Tracks of the first image's corners that survive into the second; the initial count in *initial.
  int tracksKept(bool with_source, int* initial) const {
    const std::unique_ptr<MonoInitializer> owner = start(with_source);
    MonoInitializer& init = *owner;
    init.addFrame(image(SO3d()), 0, 0);
    *initial = init.numTracks();
    init.addFrame(image(R_), 1, 50'000'000);
    const std::string& st = init.status();  // "waiting for frames (N ...": kept; "lost corner tracks (N)": reset
    if (st.find("waiting for frames") != std::string::npos) return init.numTracks();
    const size_t at = st.find("lost corner tracks (");
    return at == std::string::npos ? -1 : std::stoi(st.substr(at + 20));
  }

  static constexpr int kMargin = 100;
  std::unique_ptr<CameraModel> cam_;
  Eigen::Matrix3d K_;
  SO3d R_;
  cv::Mat canvas_;
};

TEST_F(CornerGuessTest, TheGyroscopesRotationKeepsTheTracksThroughAFastTurn) {
  int initial = 0;
  const int kept = tracksKept(true, &initial);
  ASSERT_GE(initial, 100);
  // Corners that the turn carries out of the image are lost either way (about 15 % here).
  EXPECT_GE(kept, 0.7 * initial) << kept << " of " << initial;
}

TEST_F(CornerGuessTest, WithoutTheRotationTheSameTurnLosesMostTracks) {
  // The reason for the source: the zero-motion guess slips on the bars (the start then takes a new
  // reference, as on the paper's sequence 2 at 73 deg/s: docs/vio.md).
  int initial = 0;
  const int kept = tracksKept(false, &initial);
  EXPECT_LT(kept, 0.5 * initial) << kept << " of " << initial;
}

// Two steps of the same turn and a 12 px sideways flow each (a translation parallel to the wall) that
// the gyroscope does not see: the first step's search starts 12 px off, the second's starts where the
// first step's unexplained flow says. Measured: 140 of the 174 tracks of the first step kept in the
// second; 118 with that flow left out of the guess (the turn carries about 15 % out of the image
// either way).
TEST_F(CornerGuessTest, TheFlowTheRotationLeftUnexplainedCarriesToTheNextFrame) {
  const std::unique_ptr<MonoInitializer> owner = start(true);
  MonoInitializer& init = *owner;
  const Vec2 step(12.0, 0.0);
  init.addFrame(image(SO3d()), 0, 0);
  init.addFrame(image(R_, step), 1, 50'000'000);
  ASSERT_NE(init.status().find("waiting for frames"), std::string::npos) << init.status();
  const int n1 = init.numTracks();
  init.addFrame(image(R_ * R_, 2.0 * step), 2, 100'000'000);
  ASSERT_NE(init.status().find("waiting for frames"), std::string::npos) << init.status();
  EXPECT_GE(init.numTracks(), 0.74 * n1) << init.numTracks() << " of " << n1;
}

}  // namespace
}  // namespace rsvio::test

namespace rsvio::test {
namespace {

// Each step keeps every kept corner's brightness in both frames (MonoInitializer::lastSteps, the
// diagnostics log's track rows), except the step out of the reference. Frames 0 and 1 are equally
// bright, frame 2 is 5 % brighter, frame 3 as bright as frame 2. Lucas-Kanade assumes constant
// brightness, so a gain moves its corners a little along their gradients and the 3x3 means see part of
// the change: median 1.048 here (the gain from the reference, whose corners are the detector's,
// 1.037), against 1.0 for the step without a change.
std::vector<double> stepRatios(const MonoInitializer& init) {
  std::vector<double> ratio;
  for (const auto& s : init.lastSteps()) ratio.push_back(s.intensity / s.intensity_prev);
  std::sort(ratio.begin(), ratio.end());
  return ratio;
}

TEST_F(CornerGuessTest, EachStepKeepsTheCornersBrightnessInBothFrames) {
  const std::unique_ptr<MonoInitializer> init = start(false);
  const auto turn = [](double k) { return SO3d::exp(Vec3(0.0, 0.012 * k, 0.004 * k)); };  // about 3 px per frame
  init->addFrame(image(SO3d()), 0, 0);
  EXPECT_TRUE(init->lastSteps().empty());
  init->addFrame(image(turn(1)), 1, 50'000'000);
  EXPECT_TRUE(init->lastSteps().empty()) << "the step out of the reference is not kept";
  EXPECT_EQ(init->lastStepFrom(), -1);

  init->addFrame(image(turn(2), Vec2::Zero(), 1.05), 2, 100'000'000);
  ASSERT_GE(init->lastSteps().size(), 150u);
  EXPECT_LE(init->lastSteps().size(), static_cast<size_t>(init->numTracks()));
  EXPECT_EQ(init->lastStepFrom(), 1);
  const std::vector<double> brighter = stepRatios(*init);
  std::cout << "5 % brighter: ratio quantiles 10/50/90 %: " << brighter[brighter.size() / 10] << " "
            << brighter[brighter.size() / 2] << " " << brighter[brighter.size() * 9 / 10] << "\n";
  EXPECT_GT(brighter[brighter.size() / 2], 1.025);
  EXPECT_LT(brighter[brighter.size() / 2], 1.055);
  EXPECT_GT(brighter[brighter.size() / 10], 1.0);
  const double gain = std::exp(init->logGainCurRef());
  std::cout << "gain from the reference: " << gain << "\n";
  EXPECT_GT(gain, 1.025);
  EXPECT_LT(gain, 1.055);

  init->addFrame(image(turn(3), Vec2::Zero(), 1.05), 3, 150'000'000);
  EXPECT_EQ(init->lastStepFrom(), 2);
  const std::vector<double> same = stepRatios(*init);
  ASSERT_GE(same.size(), 150u);
  std::cout << "as bright: ratio quantiles 10/50/90 %: " << same[same.size() / 10] << " " << same[same.size() / 2]
            << " " << same[same.size() * 9 / 10] << "\n";
  EXPECT_NEAR(same[same.size() / 2], 1.0, 0.005);
}

}  // namespace
}  // namespace rsvio::test
