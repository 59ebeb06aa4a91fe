// What the figures contain, measured on their pixels (issue 18): the 3D views frame the trajectory even
// in a point cloud ten times its size, keyframe frusta do not hide it, states.png has no panel for what
// the run did not estimate, a dashed line has a dashed legend swatch, the residual map explains its
// dashed row; the run and compare pages say what their numbers are.
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "rsvio/io/snapshot.h"
#include "rsvio/viz/display_guard.h"
#include "rsvio/viz/render_run.h"
#include "rsvio/viz/scene.h"
#include "run_fixture.h"

namespace rsvio::viz {
namespace {
namespace fs = std::filesystem;

bool near(const cv::Vec3b& bgr, const Rgb& c, int tol) {
  return std::abs(bgr[2] - c.r) <= tol && std::abs(bgr[1] - c.g) <= tol && std::abs(bgr[0] - c.b) <= tol;
}

struct ColourStats {
  long pixels = 0;
  cv::Rect box;  // bounding box of the pixels
};

// Pixels of colour c inside `roi`.
ColourStats colourIn(const cv::Mat& img, const Rgb& c, const cv::Rect& roi, int tol = 12) {
  ColourStats s;
  int x0 = INT32_MAX, y0 = INT32_MAX, x1 = -1, y1 = -1;
  for (int r = roi.y; r < roi.y + roi.height; ++r) {
    for (int k = roi.x; k < roi.x + roi.width; ++k) {
      if (!near(img.at<cv::Vec3b>(r, k), c, tol)) continue;
      ++s.pixels;
      x0 = std::min(x0, k), y0 = std::min(y0, r), x1 = std::max(x1, k), y1 = std::max(y1, r);
    }
  }
  if (s.pixels > 0) s.box = cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
  return s;
}

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

constexpr Rgb kEstimate{31, 119, 180};   // the estimate without ground truth (vtk_helpers.h kPlainEstimate)
constexpr Rgb kFrustum{150, 90, 200};    // keyframe frusta (kFrustumColour)

// A 2 m loop inside a cloud spread over 24 m: the situation of the issue (a room around a short path).
test::RunSpec smallLoopInABigRoom() {
  test::RunSpec spec;
  spec.n = 200;
  spec.est = [](int i) {
    const double a = 2 * M_PI * i / 200.0;
    return Eigen::Vector3d(1.0 * std::cos(a), 0.6 * std::sin(a), 1.5);
  };
  spec.n_points = 3000;
  spec.point = [](int i) {  // a 24 x 18 m floor and walls, far from the path
    const double u = (i * 0.618034) - std::floor(i * 0.618034), v = (i * 0.414214) - std::floor(i * 0.414214);
    return Eigen::Vector3d(-12 + 24 * u, -9 + 18 * v, (i % 3) * 1.5);
  };
  return spec;
}

class FigureContent : public ::testing::Test {
 protected:
  void SetUp() override { ::unsetenv("DISPLAY"); }
};

TEST_F(FigureContent, TrajectoryViewsFrameTheTrajectoryNotTheRoom) {
  test::TempDir tmp("content_frame");
  const auto run = test::makeRun(tmp.path, smallLoopInABigRoom());
  const io::Snapshot snap = io::readSnapshot(run.string());
  DisplayGuard guard;
  ASSERT_TRUE(guard.ok()) << guard.message();
  SceneOptions o;
  o.width = 640;
  o.height = 480;
  o.views = {View::kTop, View::kPerspective, View::kOverview};
  const auto files = renderScenes(snap, o, (tmp.path / "fig").string());
  ASSERT_EQ(files.size(), 3u);
  // The scene without title (top 12%) and legend (bottom 25%): no colour bar without ground truth.
  const cv::Rect scene(0, 58, 640, 480 - 58 - 120);
  const cv::Mat top = cv::imread(files[0]);
  const ColourStats est = colourIn(top, kEstimate, scene);
  ASSERT_GT(est.pixels, 100) << "the estimate is drawn";
  // Share of the frame: the loop spans most of the width (x is its long side) or of the height.
  const double share = std::max(est.box.width / 640.0, est.box.height / 480.0);
  EXPECT_GT(share, 0.55) << "the 2 m loop fills the top view, box " << est.box;
  // Frusta sized to the path: they mark the keyframes without covering the line.
  const ColourStats fr = colourIn(top, kFrustum, scene);
  EXPECT_LT(fr.pixels, 2 * est.pixels) << "frusta " << fr.pixels << " px against the line's " << est.pixels;
  const cv::Mat persp = cv::imread(files[1]);
  const ColourStats pe = colourIn(persp, kEstimate, scene);
  EXPECT_GT(std::max(pe.box.width / 640.0, pe.box.height / 480.0), 0.45) << "perspective box " << pe.box;
  // The overview shows the whole room: the path is small there, and points fill the frame.
  const cv::Mat over = cv::imread(files[2]);
  const ColourStats oe = colourIn(over, kEstimate, scene);
  EXPECT_LT(std::max(oe.box.width / 640.0, oe.box.height / 480.0), share);
  long grey_top = 0, grey_over = 0;
  for (int r = scene.y; r < scene.y + scene.height; ++r)
    for (int k = 0; k < 640; ++k) {
      const cv::Vec3b a = top.at<cv::Vec3b>(r, k), b = over.at<cv::Vec3b>(r, k);
      grey_top += a[0] == a[1] && a[1] == a[2] && a[0] < 200;
      grey_over += b[0] == b[1] && b[1] == b[2] && b[0] < 200;
    }
  EXPECT_GT(grey_over, 0) << "the overview shows the point cloud";
  EXPECT_GT(grey_over, grey_top) << "the fitted view crops the points to the path's neighbourhood";
}

TEST_F(FigureContent, StatesShowOnlyWhatTheRunEstimated) {
  test::RunSpec spec;
  spec.vo_states = true;  // velocity, biases zero, scale 1: a visual-odometry run
  test::TempDir tmp("content_states");
  const auto run = test::makeRun(tmp.path, spec);
  const io::Snapshot snap = io::readSnapshot(run.string());
  std::vector<std::string> missing;
  const auto vo = keyframeStatePanels(snap.states, std::isfinite(snap.summary.scale), &missing);
  ASSERT_EQ(vo.size(), 1u);
  EXPECT_EQ(vo[0].title, "Keyframe twist (per second)");
  EXPECT_EQ(missing.size(), 6u) << "velocity, two biases, the time offset, the line delay and the scale are not estimated";
  // Every panel shown has data that is not a flat zero.
  test::TempDir tmp2("content_states_vio");
  const auto vio = test::makeRun(tmp2.path, test::RunSpec{});
  const io::Snapshot s2 = io::readSnapshot(vio.string());
  const auto all = keyframeStatePanels(s2.states, true);
  EXPECT_EQ(all.size(), 7u);
  for (const auto& p : all) {
    bool nonzero = false;
    for (const auto& s : p.series)
      for (double y : s.y) nonzero |= y != 0;
    EXPECT_TRUE(nonzero) << p.title;
  }
  // The rendered figure: one panel high, and the page says what is not there and why.
  RenderOptions o;
  o.scenes = false;
  o.figure = {480, 270};
  const RenderStatus st = renderRunFolder(run.string(), o);
  ASSERT_TRUE(st.ok) << st.message;
  const cv::Mat img = cv::imread((run / "figures/states.png").string());
  EXPECT_EQ(img.rows, 270) << "one panel: one figure high";
  const std::string html = slurp(run / "index.html");
  EXPECT_NE(html.find("Not estimated (no panel): Velocity (world), Gyroscope bias, Accelerometer bias, Time offset, Line delay, Scale"),
            std::string::npos);
  EXPECT_NE(html.find("mean per call [ms]"), std::string::npos);
}

TEST_F(FigureContent, DashedReferenceLineHasADashedLegendSwatch) {
  test::TempDir tmp("content_dash");
  ErrorSeries e;
  for (int i = 0; i < 100; ++i) {
    e.t_s.push_back(0.1 * i);
    e.err_m.push_back(i == 50 ? 1.0 : 0.01);  // RMSE ~0.1: the dashed line stays low, far from the legend
  }
  e.ate_rmse_m = 0.1;
  const auto path = (tmp.path / "err.png").string();
  renderErrorOverTime(e, path, {640, 360});
  const cv::Mat img = cv::imread(path);
  // The legend sits in the upper right of the plot: the row with most red pixels there is its swatch
  // (red: saturated towards red, so anti-aliased edges count too).
  const cv::Rect legend(320, 0, 320, 90);
  auto reddish = [&](int r, int k) {
    const cv::Vec3b p = img.at<cv::Vec3b>(r, k);
    return p[2] > p[1] + 60 && p[2] > p[0] + 60;
  };
  int best_row = -1, best = 0;
  for (int r = legend.y; r < legend.y + legend.height; ++r) {
    int n = 0;
    for (int k = legend.x; k < legend.x + legend.width; ++k) n += reddish(r, k);
    if (n > best) best = n, best_row = r;
  }
  ASSERT_GT(best, 3) << "a red swatch in the legend";
  int dashes = 0;
  bool on = false;
  for (int k = legend.x; k < legend.x + legend.width; ++k) {
    const bool red_here = reddish(best_row, k);
    dashes += red_here && !on;
    on = red_here;
  }
  std::string dbg;
  for (int k = legend.x; k < legend.x + legend.width; ++k) dbg += reddish(best_row, k) ? "#" : ".";
  EXPECT_GE(dashes, 3) << "the swatch of a dashed line is dashed: row " << best_row << " " << dbg;
}

TEST_F(FigureContent, ResidualRowTimeExplainsItsDashedRowInTheFigure) {
  test::TempDir tmp("content_resid");
  ResidualMapInput in;
  in.image_width = 320;
  in.image_height = 240;
  for (int f = 0; f < 20; ++f)
    for (int y = 0; y < 240; y += 4) in.obs.push_back({1'000'000'000LL + f * 50'000'000LL, 100, float(y), float(y - 119.5), 3, 1});
  const auto path = (tmp.path / "r.png").string();
  renderResidualRowTime(in, path, {960, 540});
  const cv::Mat img = cv::imread(path);
  // The note is text at the bottom right, below the plot (which ends above the x axis label).
  int dark = 0;
  for (int r = 510; r < 540; ++r)
    for (int k = 600; k < 960; ++k) {
      const cv::Vec3b p = img.at<cv::Vec3b>(r, k);
      dark += p[0] < 160 && p[1] < 160 && p[2] < 160;
    }
  EXPECT_GT(dark, 100) << "a line of text explains the dashed middle row";
}

TEST_F(FigureContent, ComparePageKeepsGridSizeAndHasOneRunColumn) {
  test::TempDir tmp("content_cmp");
  std::vector<CompareRun> runs = {{"gs_vo", "seq 1", 0, false, 0.03, "", ""}, {"rs_vo", "seq 1", 0, false, 0.02, "", ""}};
  CompareRenderOptions o;
  o.out_dir = (tmp.path / "cmp").string();
  o.figure = {320, 240};
  ASSERT_TRUE(renderCompare(runs, o).ok);
  const std::string html = slurp(tmp.path / "cmp/index.html");
  EXPECT_NE(html.find("figure.wide img{width:auto;max-width:100%}"), std::string::npos)
      << "a small grid image is not stretched to the page's width";
  const size_t runs_table = html.find("<h2>Runs</h2>");
  ASSERT_NE(runs_table, std::string::npos);
  const std::string header = html.substr(runs_table, html.find("</tr>", runs_table) - runs_table);
  size_t n = 0;
  for (size_t k = header.find("<th>run"); k != std::string::npos; k = header.find("<th>run", k + 1)) ++n;
  EXPECT_EQ(n, 1u) << header;
}

}  // namespace
}  // namespace rsvio::viz
