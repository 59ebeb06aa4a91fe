// Point selection: count near the target, spread over the image, region-adaptive thresholds,
// determinism given the seed, masks and borders.
#include <gtest/gtest.h>

#include <set>

#include "rsvio/photometric/pixel_selector.h"
#include "synthetic_scene.h"

namespace rsvio {
namespace {

const test::PinholeK kK;

const ImagePyramid& scenePyramid() {
  static const ImagePyramid pyr = [] {
    test::SyntheticScene scene(3);
    test::PoseCW T;
    return ImagePyramid(scene.render(kK, T), 4);
  }();
  return pyr;
}

TEST(PixelSelector, CountIsNearTheTarget) {
  for (int target : {300, 1000, 2000}) {
    PixelSelectorOptions o;
    o.num_points = target;
    const auto pts = PixelSelector(o).select(scenePyramid());
    EXPECT_LE(static_cast<int>(pts.size()), target);
    EXPECT_GE(static_cast<int>(pts.size()), 0.8 * target) << "target " << target;
  }
}

TEST(PixelSelector, EveryRegionGetsPoints) {
  PixelSelectorOptions o;
  o.num_points = 1000;
  const auto pts = PixelSelector(o).select(scenePyramid());
  // 4 x 4 regions of 80 x 64 px: an even spread would give ~62 each; require at least a quarter.
  int count[4][4] = {};
  for (const auto& p : pts) ++count[std::min(3, p.v / 64)][std::min(3, p.u / 80)];
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) EXPECT_GE(count[j][i], 15) << "region " << i << "," << j;
}

TEST(PixelSelector, LowContrastRegionsStillGetPoints) {
  // Left half: strong texture; right half: the same texture at 1/3 of the contrast. A global threshold
  // would leave the right half empty; the block median threshold does not.
  cv::Mat img = test::SyntheticScene(5).render(kK, test::PoseCW());
  for (int y = 0; y < img.rows; ++y)
    for (int x = img.cols / 2; x < img.cols; ++x) img.at<float>(y, x) = 128.f + (img.at<float>(y, x) - 128.f) / 3.f;
  const ImagePyramid pyr(img, 4);
  PixelSelectorOptions o;
  o.num_points = 800;
  const auto pts = PixelSelector(o).select(pyr);
  int left = 0, right = 0;
  for (const auto& p : pts) (p.u < img.cols / 2 ? left : right)++;
  EXPECT_GT(right, 0.3 * left) << left << " vs " << right;
}

TEST(PixelSelector, SelectedPixelsHaveStrongGradientsAndRespectTheBorder) {
  PixelSelectorOptions o;
  o.num_points = 1500;
  o.border_px = 7;
  PixelSelector sel(o);
  const auto pts = sel.select(scenePyramid());
  int bx = 0, by = 0;
  const std::vector<float> ths = sel.blockThresholds(scenePyramid().level(0), &bx, &by);
  int level0 = 0;
  for (const auto& p : pts) {
    EXPECT_GE(p.u, 7);
    EXPECT_GE(p.v, 7);
    EXPECT_LT(p.u, kK.width - 7);
    EXPECT_LT(p.v, kK.height - 7);
    if (p.level == 0) {
      ++level0;
      const float th = ths[std::min(by - 1, p.v / 32) * bx + std::min(bx - 1, p.u / 32)];
      EXPECT_GT(p.grad2, th);
    }
  }
  EXPECT_GT(level0, static_cast<int>(pts.size()) / 2);
}

TEST(PixelSelector, DeterministicGivenTheSeedAndDifferentAcrossSeeds) {
  PixelSelectorOptions o;
  o.num_points = 700;
  o.seed = 11;
  const auto a = PixelSelector(o).select(scenePyramid());
  const auto b = PixelSelector(o).select(scenePyramid());
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].u, b[i].u);
    EXPECT_EQ(a[i].v, b[i].v);
  }
  o.seed = 12;
  const auto c = PixelSelector(o).select(scenePyramid());
  std::set<std::pair<int, int>> sa, sc;
  for (const auto& p : a) sa.insert({p.u, p.v});
  for (const auto& p : c) sc.insert({p.u, p.v});
  EXPECT_NE(sa, sc);
}

TEST(PixelSelector, MaskExcludesPixels) {
  cv::Mat mask(kK.height, kK.width, CV_8U, cv::Scalar(255));
  mask(cv::Rect(0, 0, kK.width / 2, kK.height)).setTo(0);
  PixelSelectorOptions o;
  o.num_points = 500;
  const auto pts = PixelSelector(o).select(scenePyramid(), mask);
  ASSERT_FALSE(pts.empty());
  for (const auto& p : pts) EXPECT_GE(p.u, kK.width / 2);
}

}  // namespace
}  // namespace rsvio
