// Image pyramid: level sizes, coordinate mapping, gradients and bilinear sampling; working-image
// preparation from raw frames.
#include <gtest/gtest.h>

#include <cmath>

#include "rsvio/core/error.h"
#include "rsvio/interfaces/photometric.h"
#include "rsvio/photometric/image_pyramid.h"

namespace rsvio {
namespace {

// A smooth image f(x, y) = 100 + 40 sin(x / 9) + 30 cos(y / 7) sampled at pixel centres.
cv::Mat smoothImage(int w, int h) {
  cv::Mat m(h, w, CV_32F);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) m.at<float>(y, x) = 100.f + 40.f * std::sin(x / 9.f) + 30.f * std::cos(y / 7.f);
  return m;
}

TEST(ImagePyramid, LevelSizesAndScales) {
  const ImagePyramid pyr(smoothImage(320, 256), 6, 16);
  ASSERT_EQ(pyr.numLevels(), 5);  // 320x256 -> 20x16 at level 4; level 5 would be 10x8
  for (int l = 0; l < pyr.numLevels(); ++l) {
    EXPECT_EQ(pyr.level(l).width(), 320 >> l);
    EXPECT_EQ(pyr.level(l).height(), 256 >> l);
    EXPECT_FLOAT_EQ(pyr.level(l).scale(), static_cast<float>(1 << l));
  }
  EXPECT_EQ(pyramidLevelsFor(640, 512, 5, 16), 5);
  EXPECT_EQ(pyramidLevelsFor(641, 33, 5, 16), 2);
}

TEST(ImagePyramid, CoordinateMappingKeepsPixelCentres) {
  const ImagePyramid pyr(smoothImage(64, 64), 3);
  const ImageLevel& L2 = pyr.level(2);
  // The 4x4 block of level-0 pixels 0..3 has its centre at 1.5, which is level-2 pixel 0.
  EXPECT_FLOAT_EQ(L2.toLevel(1.5f), 0.f);
  EXPECT_FLOAT_EQ(L2.fromLevel(0.f), 1.5f);
  EXPECT_FLOAT_EQ(L2.fromLevel(L2.toLevel(37.25f)), 37.25f);
}

TEST(ImagePyramid, DownsamplingAveragesBlocks) {
  cv::Mat img(8, 8, CV_32F);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) img.at<float>(y, x) = static_cast<float>(x + 10 * y);
  const ImagePyramid pyr(img, 2, 2);
  // Level-1 pixel (1, 2) averages level-0 pixels x in {2,3}, y in {4,5}: 2.5 + 45.
  EXPECT_FLOAT_EQ(pyr.level(1).intensity(1, 2), 47.5f);
}

TEST(ImagePyramid, GradientsAreCentralDifferencesAndZeroOnTheBorder) {
  const cv::Mat img = smoothImage(64, 48);
  const ImagePyramid pyr(img, 1);
  const ImageLevel& L = pyr.level(0);
  const int x = 20, y = 30;
  const float gx = 0.5f * (img.at<float>(y, x + 1) - img.at<float>(y, x - 1));
  const float gy = 0.5f * (img.at<float>(y + 1, x) - img.at<float>(y - 1, x));
  EXPECT_FLOAT_EQ(L.pixel(x, y)[1], gx);
  EXPECT_FLOAT_EQ(L.pixel(x, y)[2], gy);
  EXPECT_FLOAT_EQ(L.gradSquared(x, y), gx * gx + gy * gy);
  EXPECT_EQ(L.pixel(0, 10)[1], 0.f);
  EXPECT_EQ(L.pixel(63, 10)[2], 0.f);
  EXPECT_EQ(L.pixel(10, 47)[3], 0.f);
}

TEST(ImagePyramid, BilinearSamplingMatchesTheSmoothFunction) {
  const ImagePyramid pyr(smoothImage(96, 96), 1);
  const ImageLevel& L = pyr.level(0);
  float s[4];
  for (float u : {10.25f, 33.5f, 60.9f})
    for (float v : {12.75f, 47.1f, 80.5f}) {
      L.sample(u, v, s);
      const float f = 100.f + 40.f * std::sin(u / 9.f) + 30.f * std::cos(v / 7.f);
      const float fx = 40.f / 9.f * std::cos(u / 9.f);
      const float fy = -30.f / 7.f * std::sin(v / 7.f);
      EXPECT_NEAR(s[0], f, 0.3f);  // bilinear error ~ h^2 f'' / 8
      EXPECT_NEAR(s[1], fx, 0.15f);
      EXPECT_NEAR(s[2], fy, 0.15f);
      EXPECT_FLOAT_EQ(L.sampleIntensity(u, v), s[0]);
    }
  // At integer coordinates sampling returns the stored pixel exactly.
  L.sample(17.f, 23.f, s);
  EXPECT_EQ(s[0], L.intensity(17, 23));
}

TEST(ImagePyramid, RejectsWrongImageType) {
  EXPECT_THROW(ImagePyramid(cv::Mat(), 3), Error);
  EXPECT_THROW(ImagePyramid(cv::Mat(10, 10, CV_8U), 3), Error);
}

class AddTen : public PhotometricModel {
 public:
  void correct(cv::Mat& image, const Frame&) const override { image += 10.0; }
};
class Halve : public PhotometricModel {
 public:
  void correct(cv::Mat& image, const Frame&) const override { image *= 0.5; }
};

TEST(PrepareWorkingImage, ScalesBitDepthAndAppliesModelsInSlotOrder) {
  Frame f;
  f.index = 3;
  f.t_ns = 42;
  f.image = cv::Mat(4, 4, CV_16U, cv::Scalar(65535));
  AddTen add;
  Halve half;
  const cv::Mat a = prepareWorkingImage(f, {&add, &half});
  EXPECT_FLOAT_EQ(a.at<float>(1, 1), (255.f + 10.f) * 0.5f);
  const cv::Mat b = prepareWorkingImage(f, {&half, &add});
  EXPECT_FLOAT_EQ(b.at<float>(1, 1), 255.f * 0.5f + 10.f);
  f.image = cv::Mat(4, 4, CV_8U, cv::Scalar(200));
  EXPECT_FLOAT_EQ(prepareWorkingImage(f, {}).at<float>(0, 0), 200.f);
}

TEST(PrepareWorkingImage, NamesTheFrameOnBadInput) {
  Frame f;
  f.index = 7;
  f.t_ns = 123;
  f.path = "data/123.png";
  try {
    prepareWorkingImage(f, {});
    FAIL() << "expected DataError";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("frame 7"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("data/123.png"), std::string::npos);
  }
  f.image = cv::Mat(4, 4, CV_8UC3);
  EXPECT_THROW(prepareWorkingImage(f, {}), DataError);
}

}  // namespace
}  // namespace rsvio
