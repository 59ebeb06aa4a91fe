// Candidate points: the epipolar search converges to the true inverse depth within the stated
// interval, intervals shrink with the baseline, rolling shutter handled, statuses and activation.
#include <gtest/gtest.h>

#include <algorithm>

#include "rsvio/frontend/candidate_points.h"
#include "rsvio/photometric/pixel_selector.h"
#include "test_camera.h"

namespace rsvio {
namespace {

Vec6 twist(double tx, double ty, double tz, double rx, double ry, double rz) {
  Vec6 v;
  v << tx, ty, tz, rx, ry, rz;
  return v;
}

struct CandidateScene {
  test::PinholeK K;
  test::SyntheticScene scene{11};
  test::TestPinholeCamera camera{K};
  SE3d T_host;
  cv::Mat depth;
  ImagePyramid host_pyr;
  std::vector<Vec2> pixels;
  std::vector<double> true_idepth;

  CandidateScene() {
    T_host = SE3d::exp(twist(0.0, 0.0, 0.0, 0.0, 0.02, 0.0));
    host_pyr = ImagePyramid(scene.render(K, test::toPoseCW(T_host), &depth), 3);
    PixelSelectorOptions so;
    so.num_points = 600;
    for (const SelectedPixel& p : PixelSelector(so).select(host_pyr)) {
      const double z = depth.at<float>(p.v, p.u);
      if (!(z > 0)) continue;
      pixels.emplace_back(p.u, p.v);
      true_idepth.push_back(1.0 / (z * Vec3((p.u - K.cx) / K.fx, (p.v - K.cy) / K.fy, 1).norm()));
    }
  }
  // Target poses: sideways motion with growing baseline and small rotations.
  SE3d target(int i) const {
    const double b = 0.03 * (i + 1);
    return SE3d::exp(twist(-b, 0.2 * b, 0.3 * b, 0.01 * i, -0.3 * b, 0.005)) * T_host;
  }
};

const CandidateScene& candidateScene() {
  static const CandidateScene s;
  return s;
}

// Fraction of good candidates whose interval (widened by `slack` of its width) contains the truth.
double coverage(const std::vector<CandidatePoint>& c, const std::vector<double>& truth, const std::vector<int>& idx,
                double* median_rel_width, int* num_good) {
  int inside = 0, good = 0;
  std::vector<double> widths;
  for (size_t i = 0; i < c.size(); ++i) {
    if (c[i].status != CandidateStatus::Good) continue;
    ++good;
    const double t = truth[static_cast<size_t>(idx[i])];
    if (t >= c[i].idepth_min && t <= c[i].idepth_max) ++inside;
    widths.push_back((c[i].idepth_max - c[i].idepth_min) / t);
  }
  std::sort(widths.begin(), widths.end());
  *median_rel_width = widths.empty() ? 1e9 : widths[widths.size() / 2];
  *num_good = good;
  return good > 0 ? static_cast<double>(inside) / good : 0.0;
}

TEST(CandidatePoints, DepthsConvergeToTheTruthWithinTheirInterval) {
  const CandidateScene& s = candidateScene();
  const RowTiming gs = RowTiming::global(s.K.height * 0.5 - 0.5);
  CandidateTracer tracer(CandidateOptions(), ResidualOptions(), s.camera, gs);
  std::vector<CandidatePoint> cands = tracer.create(s.host_pyr.level(0), s.pixels);
  ASSERT_GT(cands.size(), 400u);
  // create() keeps the order; map back to the pixels (patterns near the border are dropped).
  std::vector<int> idx;
  for (size_t i = 0, j = 0; i < cands.size(); ++i) {
    while (s.pixels[j] != cands[i].uv) ++j;
    idx.push_back(static_cast<int>(j));
  }
  CandidateFrame host{RsFrame{s.T_host, Vec6::Zero()}, {}, std::nan("")};
  double prev_width = 1e9;
  for (int i = 0; i < 4; ++i) {
    const ImagePyramid tgt(s.scene.render(s.K, test::toPoseCW(s.target(i))), 1);
    const TraceStats st = tracer.trace(cands, host, CandidateFrame{RsFrame{s.target(i), Vec6::Zero()}, {}, std::nan("")},
                                       tgt.level(0));
    double width = 0;
    int good = 0;
    const double cov = coverage(cands, s.true_idepth, idx, &width, &good);
    SCOPED_TRACE("target " + std::to_string(i));
    EXPECT_GT(st.good, 0.5 * cands.size());
    // Few outliers or lost points (some leave the view or get occluded by the box as the camera moves).
    EXPECT_GT(st.good + st.skipped + st.bad_condition, 0.85 * cands.size());
    EXPECT_GT(cov, 0.9) << "good " << good << " median relative width " << width;
    if (getenv("FE_VERBOSE")) printf("target %d: good %d of %zu, coverage %.3f, median rel width %.3f\n", i, good, cands.size(), cov, width);
    EXPECT_LT(width, prev_width * 1.05);  // intervals shrink (or stay) with the baseline
    prev_width = width;
  }
  EXPECT_LT(prev_width, 0.3);  // 0.12 m baseline at 2.5-4 m: ~9 px disparity, +-0.5 px
  int ready = 0;
  for (const CandidatePoint& c : cands) {
    if (!c.readyForActivation(tracer.options())) continue;
    ++ready;
    EXPECT_TRUE(c.hasDepth());
  }
  EXPECT_GT(ready, 0.5 * cands.size());
}

TEST(CandidatePoints, RollingShutterTargetsWithTheTwistKnown) {
  const CandidateScene& s = candidateScene();
  const RowTiming rs = RowTiming::rolling(s.K.height * 0.5 - 0.5, 30e-3 / s.K.height, true);
  const Vec6 xi = twist(1.5, 0.2, 0.4, 0.3, -1.0, 0.2);
  CandidateTracer tracer(CandidateOptions(), ResidualOptions(), s.camera, rs);
  std::vector<CandidatePoint> cands = tracer.create(s.host_pyr.level(0), s.pixels);
  std::vector<int> idx;
  for (size_t i = 0, j = 0; i < cands.size(); ++i) {
    while (s.pixels[j] != cands[i].uv) ++j;
    idx.push_back(static_cast<int>(j));
  }
  CandidateFrame host{RsFrame{s.T_host, Vec6::Zero()}, {}, std::nan("")};  // host rendered without motion
  for (int i = 1; i < 4; i += 2) {
    const SE3d T0 = s.target(i);
    const ImagePyramid tgt(
        s.scene.render(s.K, [&](double v) { return test::toPoseCW(SE3d::exp(xi * rs.rowTime(v)) * T0); }), 1);
    tracer.trace(cands, host, CandidateFrame{RsFrame{T0, xi}, {}, std::nan("")}, tgt.level(0));
  }
  double width = 0;
  int good = 0;
  EXPECT_GT(coverage(cands, s.true_idepth, idx, &width, &good), 0.9) << "good " << good;
  EXPECT_GT(good, 0.6 * cands.size());
  EXPECT_LT(width, 0.2);
}

TEST(CandidatePoints, StatusesForDegenerateCases) {
  const CandidateScene& s = candidateScene();
  CandidateTracer tracer(CandidateOptions(), ResidualOptions(), s.camera, RowTiming::global(127.5));
  std::vector<CandidatePoint> cands = tracer.create(s.host_pyr.level(0), s.pixels);
  const size_t n = cands.size();
  // No translation: nothing to triangulate, the interval stays [0, inf).
  const ImagePyramid same(s.scene.render(s.K, test::toPoseCW(s.T_host)), 1);
  CandidateFrame host{RsFrame{s.T_host, Vec6::Zero()}, {}, std::nan("")};
  TraceStats st = tracer.trace(cands, host, host, same.level(0));
  EXPECT_EQ(st.bad_condition, static_cast<int>(n));
  for (const CandidatePoint& c : cands) EXPECT_FALSE(c.hasDepth());
  // A wrong brightness: the pattern matches nowhere -> outliers, then out of bounds the second time.
  const ImagePyramid tgt(s.scene.render(s.K, test::toPoseCW(s.target(1))), 1);
  CandidateFrame target{RsFrame{s.target(1), Vec6::Zero()}, AffineBrightness{0.0, 120.0}, std::nan("")};
  st = tracer.trace(cands, host, target, tgt.level(0));
  EXPECT_GT(st.outlier, 0.9 * n);
  st = tracer.trace(cands, host, target, tgt.level(0));
  EXPECT_GT(st.out_of_bounds, 0.9 * n);
  st = tracer.trace(cands, host, target, tgt.level(0));
  EXPECT_GT(st.already_out, 0.9 * n);
  EXPECT_STREQ(candidateStatusName(CandidateStatus::OutOfBounds), "out_of_bounds");
}

}  // namespace
}  // namespace rsvio
