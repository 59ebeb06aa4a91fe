// 2D figures (OpenCV, no display): sizes, the compare grid's failed-run marks and colour scale, residual
// maps that put the residual where it was observed.
#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "rsvio/viz/colormap.h"
#include "rsvio/viz/figures.h"
#include "run_fixture.h"

namespace rsvio::viz {
namespace {

bool near(const cv::Vec3b& bgr, const Rgb& c, int tol) {
  return std::abs(bgr[2] - c.r) <= tol && std::abs(bgr[1] - c.g) <= tol && std::abs(bgr[0] - c.b) <= tol;
}

// Bounding boxes of the connected areas of one colour (the squares of the grid), largest first.
std::vector<cv::Rect> areasOf(const cv::Mat& img, const Rgb& c, int tol) {
  cv::Mat mask(img.size(), CV_8U, cv::Scalar(0));
  for (int r = 0; r < img.rows; ++r) {
    for (int k = 0; k < img.cols; ++k) mask.at<uchar>(r, k) = near(img.at<cv::Vec3b>(r, k), c, tol) ? 255 : 0;
  }
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids);
  std::vector<cv::Rect> out;
  for (int i = 1; i < n; ++i) {
    out.emplace_back(stats.at<int>(i, cv::CC_STAT_LEFT), stats.at<int>(i, cv::CC_STAT_TOP), stats.at<int>(i, cv::CC_STAT_WIDTH),
                     stats.at<int>(i, cv::CC_STAT_HEIGHT));
  }
  std::sort(out.begin(), out.end(), [](const cv::Rect& a, const cv::Rect& b) { return a.area() > b.area(); });
  return out;
}

TEST(CompareGrid, OneSquarePerRunFailedRunsWhiteWithACross) {
  test::TempDir tmp("grid");
  // 2 configurations x 2 sequences x 3 runs; one failure in the second row.
  std::vector<CompareRun> runs;
  for (const char* cfg : {"gs_vio", "rs_vio"}) {
    for (const char* seq : {"seq1", "seq2"}) {
      for (int k = 0; k < 3; ++k) runs.push_back({cfg, seq, k, false, 0.01, "", ""});
    }
  }
  runs[7].failed = true;  // rs_vio, seq1, run 1
  runs[7].ate_m = kNaN;
  runs[11].ate_m = 1.0;   // rs_vio, seq2, run 2: the top of the scale
  CompareGrid g = makeCompareGrid(runs);
  ASSERT_EQ(g.configs.size(), 2u);
  ASSERT_EQ(g.sequences.size(), 2u);
  ASSERT_EQ(g.runs, 3);
  const std::string path = (tmp.path / "grid.png").string();
  renderCompareGrid(g, path, {480, 240});
  const cv::Mat img = cv::imread(path);
  ASSERT_EQ(img.cols, 480);
  ASSERT_EQ(img.rows, 240);
  // The log scale spans [0.01, 1]: 10 runs at its bottom colour, one at its top colour.
  const auto low = areasOf(img, errorMap(0.0), 3);
  const auto high = areasOf(img, errorMap(1.0), 3);
  int squares_low = 0;
  for (const auto& r : low) {
    if (r.width > 8 && std::abs(r.width - r.height) <= 2) ++squares_low;
  }
  EXPECT_EQ(squares_low, 10);
  ASSERT_FALSE(high.empty());
  const cv::Rect hot = high.front();
  EXPECT_GT(hot.width, 8);
  // The failed square (rs_vio, seq1, run 1) lies between rs_vio's seq1 runs 0 and 2, in the row of
  // the hot square: white inside, a red cross through its centre.
  std::vector<cv::Rect> row;
  for (const auto& r : low) {
    if (std::abs((r.y + r.height / 2) - (hot.y + hot.height / 2)) <= 2 && r.width > 8) row.push_back(r);
  }
  ASSERT_EQ(row.size(), 4u);
  std::sort(row.begin(), row.end(), [](const cv::Rect& a, const cv::Rect& b) { return a.x < b.x; });
  const int cx = (row[0].x + row[1].x + row[1].width) / 2, cy = row[0].y + row[0].height / 2;
  const int half = row[0].width / 2;
  const cv::Vec3b centre = img.at<cv::Vec3b>(cy, cx);
  EXPECT_TRUE(centre[2] > 150 && centre[1] < 110 && centre[0] < 110) << "cross centre " << centre;
  EXPECT_TRUE(near(img.at<cv::Vec3b>(cy, cx - half + 3), Rgb{255, 255, 255}, 10)) << "left inside";
  EXPECT_TRUE(near(img.at<cv::Vec3b>(cy - half + 3, cx), Rgb{255, 255, 255}, 10)) << "top inside";
  // Diagonal pixels are the cross's.
  const cv::Vec3b diag = img.at<cv::Vec3b>(cy - half / 2, cx - half / 2);
  EXPECT_TRUE(diag[2] > 150 && diag[1] < 150) << "cross diagonal " << diag;
}

TEST(Figures, ErrorOverTimeAndAtePerConfigHaveTheAskedSize) {
  test::TempDir tmp("figs");
  ErrorSeries e;
  for (int i = 0; i < 100; ++i) {
    e.t_s.push_back(0.05 * i);
    e.err_m.push_back(0.01 + 0.001 * i);
  }
  e.ate_rmse_m = 0.05;
  renderErrorOverTime(e, (tmp.path / "err.png").string(), {400, 300});
  const cv::Mat img = cv::imread((tmp.path / "err.png").string());
  ASSERT_EQ(img.cols, 400);
  ASSERT_EQ(img.rows, 300);
  // The series is drawn in blue (31, 119, 180) somewhere.
  int blue = 0;
  for (int r = 0; r < img.rows; ++r) {
    for (int c = 0; c < img.cols; ++c) blue += near(img.at<cv::Vec3b>(r, c), Rgb{31, 119, 180}, 20);
  }
  EXPECT_GT(blue, 100);

  std::vector<CompareRun> runs = {{"a", "s", 0, false, 0.02, "", ""}, {"a", "s", 1, false, 0.03, "", ""},
                                  {"b", "s", 0, true, kNaN, "", "diverged"}, {"b", "s", 1, false, 0.5, "", ""}};
  renderAtePerConfig(makeCompareGrid(runs), (tmp.path / "ate.png").string(), {320, 240});
  const cv::Mat ate = cv::imread((tmp.path / "ate.png").string());
  EXPECT_EQ(ate.cols, 320);
  EXPECT_EQ(ate.rows, 240);
}

TEST(Figures, NoDataGivesAMessageFigureNotAnError) {
  test::TempDir tmp("nodata");
  ErrorSeries e;
  e.message = "run failed: diverged";
  renderErrorOverTime(e, (tmp.path / "err.png").string(), {320, 240});
  const cv::Mat img = cv::imread((tmp.path / "err.png").string());
  ASSERT_EQ(img.cols, 320);
  int red = 0;
  for (int r = 0; r < img.rows; ++r) {
    for (int c = 0; c < img.cols; ++c) {
      const auto p = img.at<cv::Vec3b>(r, c);
      red += p[2] > 150 && p[1] < 110 && p[0] < 110;
    }
  }
  EXPECT_GT(red, 20) << "the failure message is drawn in red";
}

TEST(ResidualMaps, LargeResidualsOnTopRowsShowAtTheTop) {
  test::TempDir tmp("resid");
  ResidualMapInput in;
  in.image_width = 64;
  in.image_height = 48;
  const double y0 = 0.5 * (48 - 1);
  for (int t = 0; t < 20; ++t) {
    for (int y = 0; y < 48; ++y) {
      for (int x = 0; x < 64; x += 4) {
        // |r| = 10 on the top quarter of the image, 1 elsewhere.
        in.obs.push_back({1'000'000'000LL + t * 50'000'000LL, float(x), float(y), float(y - y0), y < 12 ? 10.f : 1.f, 1.f});
      }
    }
  }
  renderResidualRowTime(in, (tmp.path / "rt.png").string(), {480, 320});
  renderResidualImage(in, (tmp.path / "im.png").string(), {480, 320});
  for (const char* f : {"rt.png", "im.png"}) {
    const cv::Mat img = cv::imread((tmp.path / f).string());
    ASSERT_EQ(img.cols, 480) << f;
    ASSERT_EQ(img.rows, 320) << f;
    // Count the top of viridis (yellow) in the upper and the lower half of the plot.
    int upper = 0, lower = 0;
    for (int r = 0; r < img.rows; ++r) {
      for (int c = 0; c < img.cols * 3 / 4; ++c) {  // left of the colour bar
        if (near(img.at<cv::Vec3b>(r, c), viridis(1.0), 12)) (r < img.rows / 2 ? upper : lower)++;
      }
    }
    EXPECT_GT(upper, 500) << f;
    EXPECT_EQ(lower, 0) << f;
  }
}

}  // namespace
}  // namespace rsvio::viz
