// The renderer: a known surface point under a rolling shutter appears where an independent solve of the
// rolling-shutter constraint puts it; rendering is deterministic; the lens model round-trips.
#include <gtest/gtest.h>

#include <cmath>

#include "rsvio/sim/lens.h"
#include "rsvio/sim/renderer.h"
#include "rsvio/sim/rng.h"
#include "sim_test_util.h"

namespace rsvio::sim {
namespace {

struct BlobWorld {
  Scene scene;
  Vec3 centre;  // centre of the bright square's front face
};

// A dark room with one small bright square on the wall where `ray` from `origin` hits it.
BlobWorld makeBlobWorld(const Vec3& origin, const Vec3& ray, double half_size) {
  BlobWorld w;
  const int dark = w.scene.addTexture(TextureMap::constant(0.1f));
  const int bright = w.scene.addTexture(TextureMap::constant(0.9f));
  const Vec3 rmin(-4.5, -3.5, 0.0), rmax(4.5, 3.5, 3.0);
  w.scene.addSolid(rmin, rmax, {dark, dark, dark, dark, dark, dark}, true);
  Scene::Hit hit;
  EXPECT_TRUE(w.scene.intersect(origin, ray, hit));
  const int axis = hit.face / 2, side = hit.face % 2;
  const double plane = side ? rmax[axis] : rmin[axis], depth = 0.002;
  Vec3 mn = hit.p - Vec3::Constant(half_size), mx = hit.p + Vec3::Constant(half_size);
  mn[axis] = side ? plane - depth : plane;
  mx[axis] = side ? plane : plane + depth;
  w.scene.addSolid(mn, mx, {bright, bright, bright, bright, bright, bright}, false);
  w.centre = hit.p;
  w.centre[axis] = side ? plane - depth : plane + depth;
  return w;
}

// Intensity-weighted centroid of the bright blob in a window.
Vec2 blobCentroid(const cv::Mat& img, const Vec2& guess, int radius) {
  double sw = 0, su = 0, sv = 0;
  for (int y = std::max(0, int(guess.y()) - radius); y <= std::min(img.rows - 1, int(guess.y()) + radius); ++y)
    for (int x = std::max(0, int(guess.x()) - radius); x <= std::min(img.cols - 1, int(guess.x()) + radius); ++x) {
      const double w = std::max(0.0, img.at<float>(y, x) - 0.1);
      sw += w;
      su += w * x;
      sv += w * y;
    }
  return Vec2(su / sw, sv / sw);
}

// The rolling-shutter constraint solved by fixed-point iteration on the row, with the plain pinhole
// projection: independent of the renderer's ray tables, texture lookup and culling.
Vec2 rowSolve(const SimTrajectory& tr, const SimSensorModel& s, const Vec3& X_w, double t_capture) {
  const auto& K = s.camera.intrinsics;
  Vec2 uv(K[2], s.rowZero());
  for (int it = 0; it < 50; ++it) {
    const double t = t_capture + s.rowTime(uv.y());
    const Eigen::Isometry3d T_W_C = tr.pose(t) * s.camera.T_B_C;
    const Vec3 p = T_W_C.inverse() * X_w;
    uv = Vec2(K[0] * p.x() / p.z() + K[2], K[1] * p.y() / p.z() + K[3]);
  }
  return uv;
}

class RollingShutterRender : public ::testing::TestWithParam<const char*> {};

TEST_P(RollingShutterRender, KnownPointLandsWhereTheRowSolvePutsIt) {
  const SimSettings settings = simSettings(test::tinyConfig("tiny_rs", {"motion.mean_rot_speed_deg_s=137",
                                                                         "motion.mean_rot_accel_deg_s2=539"}));
  SimSensorModel sensor = settings.sensor;
  sensor.line_delay_s = 117.88e-6;
  sensor.readout = GetParam();
  std::mt19937_64 rng = makeStream(settings.seed, "trajectory");
  const SimTrajectory tr = SimTrajectory::generate(settings.motion, rng);

  // The fastest-turning moment, and a square seen near the top of the image (far from row y0).
  double t_star = 0.5, best = 0;
  for (double t = 0.5; t < 2.5; t += 0.01)
    if (tr.state(t).omega_B.norm() > best) best = tr.state(t).omega_B.norm(), t_star = t;
  const Lens lens(sensor.camera);
  Vec3 ray_c;
  ASSERT_TRUE(lens.unproject(Vec2(sensor.camera.intrinsics[2] + 20, 40.0), ray_c));
  // Placed with the pose at the image time: under the rolling shutter it shows up rows away from 40.
  const Eigen::Isometry3d T = tr.pose(t_star) * sensor.camera.T_B_C;
  BlobWorld world = makeBlobWorld(T.translation(), T.linear() * ray_c, 0.04);

  const Renderer renderer(world.scene, tr, sensor, 4);
  const cv::Mat img = renderer.render(t_star);
  const Vec2 solved = rowSolve(tr, sensor, world.centre, t_star);
  const Vec2 seen = blobCentroid(img, solved, 12);
  EXPECT_NEAR((seen - solved).norm(), 0.0, 0.1) << "seen " << seen.transpose() << " solved " << solved.transpose();

  // The shutter matters here: a global-shutter projection at the image time is pixels away.
  SimSensorModel global = sensor;
  global.line_delay_s = 0;
  const Vec2 gs = rowSolve(tr, global, world.centre, t_star);
  EXPECT_GT((gs - solved).norm(), 2.0) << "gs " << gs.transpose() << " rs " << solved.transpose();
}

INSTANTIATE_TEST_SUITE_P(Readout, RollingShutterRender, ::testing::Values("top_down", "bottom_up"));

TEST(SimRender, DeterministicAndRowSplitInvariant) {
  Simulator sim(test::tinyConfig("tiny_rs"), test::host());
  sim.prepareRendering();
  const double t = sim.captureTime(10);
  const cv::Mat a = sim.renderer().render(t), b = sim.renderer().render(t);
  cv::Mat c(a.size(), CV_32F, cv::Scalar(0));
  sim.renderer().renderRows(t, 100, a.rows, c);
  sim.renderer().renderRows(t, 0, 100, c);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a, c, cv::NORM_INF), 0.0);
  // An indoor scene with texture everywhere, not a flat image.
  cv::Scalar mean, stddev;
  cv::meanStdDev(a, mean, stddev);
  EXPECT_GT(mean[0], 0.15);
  EXPECT_LT(mean[0], 0.85);
  EXPECT_GT(stddev[0], 0.05);
}

TEST(SimLens, ProjectUnprojectRoundTrip) {
  for (const auto& [model, coeffs] : std::vector<std::pair<std::string, std::vector<double>>>{
           {"none", {0, 0, 0, 0}}, {"radtan", {-0.28, 0.07, 2e-4, -1e-4}}, {"equidistant", {-0.02, 0.004, -0.002, 5e-4}}}) {
    CameraCalibration c;
    c.width = 320;
    c.height = 256;
    c.intrinsics << 208, 209, 159.5, 127.5;
    c.distortion = model;
    c.distortion_coeffs = Eigen::Map<const Eigen::VectorXd>(coeffs.data(), 4);
    const Lens lens(c);
    for (const Vec2 uv : {Vec2(0, 0), Vec2(319, 255), Vec2(100.25, 30.5), Vec2(159.5, 127.5)}) {
      Vec3 ray;
      ASSERT_TRUE(lens.unproject(uv, ray)) << model;
      Vec2 back;
      ASSERT_TRUE(lens.project(2.5 * ray, back));
      EXPECT_NEAR((back - uv).norm(), 0.0, 1e-8) << model << " at " << uv.transpose();
    }
  }
}

}  // namespace
}  // namespace rsvio::sim
