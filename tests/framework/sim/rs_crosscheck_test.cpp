// Cross-check of the rolling-shutter model against the simulator (issue 13): scene points that the
// renderer drew at a raw pixel (its own ray cast at that row's capture time, no row solve) project,
// through the camera.pinhole and shutter.rolling plugins loaded by the host and the framework's
// rolling-shutter projection (geometry/rs_projection.h: Newton on the row), back to that pixel.
// The frame's pose and twist come from the simulated trajectory around the image time (the constant
// twist of eq. 6 approximates it over the 30 ms readout). The global-shutter projection of the same
// points misses by pixels, so the test sees the readout; the wrong readout direction fails it.
#include <gtest/gtest.h>

#include "rsvio/geometry/rs_projection.h"
#include "rsvio/interfaces/camera.h"
#include "rsvio/interfaces/shutter.h"
#include "sim_test_util.h"

namespace rsvio {
namespace {

using sim::Scene;
using sim::Simulator;
using sim::test::effect;
using sim::test::withEffects;

template <class T>
std::unique_ptr<T> plugin(const std::string& name, const nlohmann::json& params) {
  auto& host = sim::test::host();
  std::vector<ConfigProblem> problems;
  const nlohmann::json p = validateParams(params, host.info(name).params, name, problems);
  EXPECT_TRUE(problems.empty());
  return host.create<T>(name, Params(p));
}

// Largest pixel error of the rendered pixels re-projected with `readout` (and the twist when rolling);
// `near_y0` receives the largest over rows within 40 of y0 (where the constant-twist approximation's
// second-order error, (row time)^2 x acceleration, is small).
double maxReprojectionError(Simulator& sim, const std::string& readout, bool rolling, double* near_y0 = nullptr) {
  const double line_delay_us = sim.sensor().line_delay_s * 1e6;
  const CameraCalibration& cal = sim.sensor().camera;
  auto camera = plugin<CameraModel>("camera.pinhole", nlohmann::json::object());
  camera->setCalibration(cal);
  auto shutter = rolling ? plugin<ShutterModel>("shutter.rolling", {{"line_delay_us", line_delay_us}, {"readout", readout}})
                         : plugin<ShutterModel>("shutter.global", nlohmann::json::object());
  shutter->setCalibration(cal);
  const RowTiming timing = RowTiming::from(*shutter, *camera);
  sim.prepareRendering();
  double worst = 0.0, worst_near = 0.0;
  for (int frame : {5, 20, 40}) {
    const double t = sim.captureTime(frame);
    const double h = 1e-3;
    auto T_c_w = [&](double s) {
      const Eigen::Isometry3d T = sim.renderer().T_W_C(s).inverse();
      return SE3d(SO3d(Eigen::Quaterniond(T.linear())), T.translation());
    };
    const RsFrame f{T_c_w(t), rolling ? Vec6((T_c_w(t + h) * T_c_w(t - h).inverse()).log() / (2 * h)) : Vec6::Zero()};
    for (int v = 8; v < cal.height - 8; v += 40)
      for (int u = 8; u < cal.width - 8; u += 50) {
        Scene::Hit hit;
        if (!sim.renderer().castPixel(Vec2(u, v), t, hit)) continue;
        const RsProjection pr = projectRollingShutter(*camera, timing, f, Vec3(hit.p));
        EXPECT_TRUE(pr.valid && pr.converged) << "frame " << frame << " pixel " << u << "," << v;
        const double e = (pr.uv - Vec2(u, v)).norm();
        worst = std::max(worst, e);
        if (std::abs(v - timing.y0) <= 40.0) worst_near = std::max(worst_near, e);
      }
  }
  if (near_y0) *near_y0 = worst_near;
  return worst;
}

TEST(RollingShutterCrossCheck, RenderedPixelsProjectBackThroughTheShutterPlugin) {
  Simulator sim(withEffects("tiny_gs", {{"rs", effect("effect.rolling_shutter", {{"line_delay_us", 117.88}})}}),
                sim::test::host());
  ASSERT_GT(sim.sensor().line_delay_s, 0.0);
  // Measured (tiny_gs motion, 117.88 us per row): 0.000 px at y0, <= 0.018 px within 40 rows, 0.15-0.23 px at
  // the top and bottom rows, growing with the square of the row time: the trajectory accelerates
  // during the readout and the constant twist is its first-order model. A wrong line delay or twist
  // sign would grow linearly with the row.
  double near = 0.0;
  const double rs = maxReprojectionError(sim, "top_down", true, &near);
  EXPECT_LT(near, 0.04) << "rolling shutter near y0";
  EXPECT_LT(rs, 0.3) << "rolling shutter, top_down";
  const double gs = maxReprojectionError(sim, "top_down", false);
  EXPECT_GT(gs, 0.5) << "the global-shutter projection must miss: the sequence has a readout";
  const double flipped = maxReprojectionError(sim, "bottom_up", true);
  EXPECT_GT(flipped, 0.5) << "the wrong readout direction must miss";
  std::printf("max reprojection error: rolling %.4f px (%.4f px near y0), global %.2f px, bottom_up %.2f px\n", rs, near,
              gs, flipped);
}

}  // namespace
}  // namespace rsvio
