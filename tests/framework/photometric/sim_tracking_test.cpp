// The front end on simulator images (configs/sim/tiny_gs.json and tiny_rs.json: 320x256, the paper's
// mean motion, image noise, 8-bit), with the real camera.pinhole plugin through the host:
// - the tracker converges from perturbed poses within the stated basin and reports failure outside it;
// - motion.constant_velocity's guesses track the next frames;
// - candidate depths converge to the truth within their intervals.
//
// Stated basin here (f = 208 px, room of 9 x 7 x 3 m): a guess off by 0.1 m and 0.05 rad (2.9 deg)
// converges to within 1.5 cm and 0.005 rad of the truth; a guess off by 0.6 rad is reported lost (or,
// if the recovery is genuine, accurate) - never accepted at a wrong pose.
#include <gtest/gtest.h>

#include <map>
#include <random>

#include "plugins/motion/constant_velocity/constant_velocity.h"
#include "rsvio/config/validate.h"
#include "rsvio/frontend/candidate_points.h"
#include "rsvio/frontend/frame_tracker.h"
#include "rsvio/interfaces/camera.h"
#include "rsvio/photometric/pixel_selector.h"
#include "rsvio/plugin/host.h"
#include "rsvio/sim/simulator.h"
#include "framework/src/system/tracking.h"

namespace rsvio {
namespace {

struct SimSequence {
  PluginHost host{{RSVIO_PLUGIN_DIR}};
  std::unique_ptr<sim::Simulator> sim;
  std::unique_ptr<CameraModel> camera;
  RowTiming timing;

  explicit SimSequence(const std::string& config) {
    const nlohmann::json cfg =
        sim::loadSimConfig(std::string(RSVIO_SOURCE_DIR) + "/configs/sim/" + config, {}, std::nullopt, host);
    sim = std::make_unique<sim::Simulator>(cfg, host);
    sim->prepareRendering();
    std::vector<ConfigProblem> problems;
    const nlohmann::json p = validateParams(nlohmann::json::object(), host.info("camera.pinhole").params,
                                            "camera.params", problems);
    camera = host.create<CameraModel>("camera.pinhole", Params(p, "camera"));
    camera->setCalibration(sim->sensor().camera);
    const SimSensorModel& s = sim->sensor();
    timing = s.line_delay_s > 0 ? RowTiming::rolling(s.rowZero(), s.line_delay_s, s.readout == "top_down")
                                : RowTiming::global(s.rowZero());
  }

  // True central pose camera-from-world of frame i, and the true twist (per second, left).
  SE3d pose(size_t i, double dt = 0.0) const {
    const Eigen::Isometry3d T_W_C = sim->renderer().T_W_C(sim->captureTime(i) + dt);
    return SE3d(Eigen::Matrix3d(T_W_C.rotation()), Vec3(T_W_C.translation())).inverse();
  }
  Vec6 twist(size_t i) const {
    const double h = 1e-4;
    return (pose(i, h) * pose(i, -h).inverse()).log() / (2 * h);
  }
  std::shared_ptr<ImagePyramid> pyramid(size_t i) const {
    cv::Mat f;
    sim->renderImage(i).convertTo(f, CV_32F, sim->sensor().bit_depth == 8 ? 1.0 : 255.0 / 65535.0);
    return std::make_shared<ImagePyramid>(f, 5);
  }
  // Selected pixels of frame i with their true inverse depth (1 / distance along the bearing).
  void points(const ImagePyramid& pyr, size_t i, int n, std::vector<Vec2>* uv, std::vector<double>* idepth) const {
    PixelSelectorOptions so;
    so.num_points = n;
    const SE3d T = pose(i);
    for (const SelectedPixel& p : PixelSelector(so).select(pyr)) {
      sim::Scene::Hit hit;
      if (!sim->renderer().castPixel(Vec2(p.u, p.v), sim->captureTime(i), hit)) continue;
      // The pixel's own row time: the point in the camera at that time (rolling shutter).
      const Eigen::Isometry3d T_W_C = sim->renderer().T_W_C(sim->captureTime(i) + timing.rowTime(p.v));
      const Vec3 p_c = T_W_C.inverse() * hit.p;
      uv->emplace_back(p.u, p.v);
      idepth->push_back(1.0 / p_c.norm());
    }
    (void)T;
  }
};

// Building a simulator's scene takes a while: one per config for the whole file.
const SimSequence& sequence(const std::string& config) {
  static std::map<std::string, std::unique_ptr<SimSequence>> cache;
  auto& slot = cache[config];
  if (!slot) slot = std::make_unique<SimSequence>(config);
  return *slot;
}

double rotErr(const SE3d& a, const SE3d& b) { return (a * b.inverse()).log().tail<3>().norm(); }
double transErr(const SE3d& a, const SE3d& b) { return (a.inverse().translation() - b.inverse().translation()).norm(); }

TrackingReference reference(const SimSequence& s, size_t k) {
  TrackingReference ref;
  ref.frame_id = static_cast<int64_t>(k);
  ref.T_c_w = s.pose(k);
  ref.twist = s.timing.line_delay_s > 0 ? s.twist(k) : Vec6::Zero();
  ref.pyramid = s.pyramid(k);
  std::vector<Vec2> uv;
  std::vector<double> id;
  s.points(*ref.pyramid, k, 1500, &uv, &id);
  for (size_t i = 0; i < uv.size(); ++i) ref.points.push_back({uv[i], id[i], 1.0});
  return ref;
}

// Issue 7: on the textured walls (since e09466e) a guess 0.76 rad off converged to a wrong pose (1.57 m,
// 0.76 rad) whose RMSE and inlier ratio were in range; the explained-ratio test (frame_tracker.h)
// reports it lost.
TEST(SimTracking, BasinAndLostOnGlobalShutterImages) {
  const SimSequence& s = sequence("tiny_gs.json");
  const size_t k = 12;
  FrameTracker tracker(TrackerOptions(), *s.camera, s.timing);
  tracker.setReference(reference(s, k));
  ASSERT_GT(tracker.numReferencePoints(0), 1000);
  const auto target = s.pyramid(k + 2);
  const SE3d truth = s.pose(k + 2);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 4; ++trial) {
    Vec6 d;
    d << Vec3(u(rng), u(rng), u(rng)).normalized() * 0.1, Vec3(u(rng), u(rng), u(rng)).normalized() * 0.05;
    const TrackResult r = tracker.track(*target, TrackingFrame(), {SE3d::exp(d) * truth});
    if (getenv("FE_VERBOSE"))
      printf("basin trial %d: terr %.4f rerr %.4f rmse %.2f inl %.2f expl %.2f\n", trial, transErr(r.T_c_w, truth),
             rotErr(r.T_c_w, truth), r.rmse, r.inlier_ratio, r.explained_ratio);
    ASSERT_TRUE(r.ok()) << "trial " << trial << ": " << r.reason;
    EXPECT_LT(transErr(r.T_c_w, truth), 0.015) << "trial " << trial;
    EXPECT_LT(rotErr(r.T_c_w, truth), 0.005) << "trial " << trial;
  }
  int lost = 0;
  for (int trial = 0; trial < 4; ++trial) {
    Vec6 d;
    d << Vec3(u(rng), u(rng), u(rng)).normalized() * 0.3, Vec3(u(rng), u(rng), u(rng)).normalized() * 0.6;
    const TrackResult r = tracker.track(*target, TrackingFrame(), {SE3d::exp(d) * truth});
    if (getenv("FE_VERBOSE"))
      printf("lost test trial %d: %s terr %.3f rerr %.3f rmse %.2f inl %.2f expl %.2f (%s)\n", trial,
             r.ok() ? "ok" : "lost", transErr(r.T_c_w, truth), rotErr(r.T_c_w, truth), r.rmse, r.inlier_ratio,
             r.explained_ratio, r.reason.c_str());
    if (r.ok()) {
      EXPECT_LT(transErr(r.T_c_w, truth), 0.02) << "wrong pose reported as tracked, trial " << trial;
      EXPECT_LT(rotErr(r.T_c_w, truth), 0.01) << "wrong pose reported as tracked, trial " << trial;
    } else {
      ++lost;
      EXPECT_FALSE(r.reason.empty());
    }
  }
  EXPECT_GE(lost, 2);
}

TEST(SimTracking, ConstantVelocityGuessesTrackASequence) {
  const SimSequence& s = sequence("tiny_gs.json");
  const size_t k = 20;
  FrameTracker tracker(TrackerOptions(), *s.camera, s.timing);
  tracker.setReference(reference(s, k));
  const ConstantVelocityPrior prior;
  std::vector<MotionState> history;
  for (size_t i : {k - 1, k}) {
    MotionState m;
    m.t_ns = s.sim->frameStamps()[i];
    m.T_c_w = s.pose(i);  // the tracker's own estimates would be used in a run
    m.is_keyframe = i == k;
    history.push_back(m);
  }
  for (size_t i = k + 1; i <= k + 4; ++i) {
    const TrackResult r =
        tracker.track(*s.pyramid(i), TrackingFrame(), prior.predict(history, s.sim->frameStamps()[i]));
    ASSERT_TRUE(r.ok()) << "frame " << i << ": " << r.reason;
    tracker.accept(r);
    EXPECT_LT(transErr(r.T_c_w, s.pose(i)), 0.02) << "frame " << i;
    EXPECT_LT(rotErr(r.T_c_w, s.pose(i)), 0.005) << "frame " << i;
    MotionState m;
    m.t_ns = s.sim->frameStamps()[i];
    m.T_c_w = r.T_c_w;
    history.push_back(m);
  }
}

TEST(SimTracking, RollingShutterImagesWithTheTwistGiven) {
  const SimSequence& s = sequence("tiny_rs.json");
  ASSERT_GT(s.timing.line_delay_s, 0.0);
  const size_t k = 12;
  FrameTracker tracker(TrackerOptions(), *s.camera, s.timing);
  tracker.setReference(reference(s, k));
  TrackingFrame info;
  info.twist = s.twist(k + 1);
  const SE3d truth = s.pose(k + 1);
  Vec6 d;
  d << 0.03, -0.02, 0.02, 0.01, 0.02, -0.01;
  const TrackResult r = tracker.track(*s.pyramid(k + 1), info, {SE3d::exp(d) * truth});
  ASSERT_TRUE(r.ok()) << r.reason;
  EXPECT_LT(transErr(r.T_c_w, truth), 0.01);
  EXPECT_LT(rotErr(r.T_c_w, truth), 0.004);
}

// The twist's rotation of a rolling-shutter frame (Tracking::track): frames after a keyframe of
// tiny_rs tracked as a run tracks them, each from the last pose with the last frame interval's rate as
// the predicted rotation (the translation given true here, to look at the rotation alone), and each
// frame's pose goes into the history the next prediction is made from. Four trackers: plain (the
// predicted rate held), one refinement (TrackerOptions::twist_refinements: tracked again with the rate
// through the pose found), the in-pass refresh (twist_refresh_levels 1: the rate through the pose of
// level 1 for level 0), and the rate estimated with the pose (rotation_rate_sigma 0.3 rad/s about the
// prediction, the default). Measured (frames 13-18): mean error 31.9 mm and 0.36 deg plain, 8.5 mm and
// 0.10 deg refined, 8.1 mm and 0.09 deg refreshed, 3.7 mm and 0.05 deg estimated. Shown failing once: a
// refinement with the rate extrapolated from the history alone (without the pose just found) gave
// 54.8 mm; with the refreshed rate dropped the refresh is the plain figure; with the rate's Jacobian
// zeroed (frame_tracker.cpp, projectBlock) the estimate is the plain figure too (at half its value the
// damped steps still get there: 3.3 mm; its value is checked in FrameTracker.OwnProjection...).
TEST(SimTracking, RollingShutterRotationRateFromThePoseOrTheImagesLowersThePoseErrorOfALaggingRate) {
  const SimSequence& s = sequence("tiny_rs.json");
  ASSERT_GT(s.timing.line_delay_s, 0.0);
  const size_t k = 12;
  const std::vector<int64_t>& stamps = s.sim->frameStamps();
  auto run = [&](int refinements, int refresh_levels, double rate_sigma, double* trans, double* rot) {
    TrackerOptions o;
    o.twist_refinements = refinements;
    o.twist_refresh_levels = refresh_levels;
    o.rotation_rate_sigma = rate_sigma;
    Tracking tracking(o, *s.camera, s.timing, {});
    tracking.setReference(reference(s, k));
    tracking.pushHistory(stamps[k - 1], s.pose(k - 1), false);
    tracking.pushHistory(stamps[k], s.pose(k), true);
    *trans = *rot = 0.0;
    for (size_t i = k + 1; i <= k + 6; ++i) {
      TrackingFrame info;
      info.t_ns = stamps[i];
      info.twist << s.twist(i).head<3>(), tracking.velocityEstimate().tail<3>();
      bool ok = false;
      const TrackResult r = tracking.track(*s.pyramid(i), info, &ok);
      ASSERT_TRUE(ok) << "frame " << i << ": " << r.reason;
      EXPECT_EQ(r.rate_estimated, rate_sigma > 0.0);
      *trans += transErr(r.T_c_w, s.pose(i)) / 6.0;
      *rot += rotErr(r.T_c_w, s.pose(i)) / 6.0;
      tracking.pushHistory(stamps[i], r.T_c_w, false);
    }
  };
  double t0 = 0, r0 = 0, t1 = 0, r1 = 0, t2 = 0, r2 = 0, t3 = 0, r3 = 0;
  run(0, 0, 0.0, &t0, &r0);
  run(1, 0, 0.0, &t1, &r1);
  run(0, 1, 0.0, &t2, &r2);
  run(0, 0, TrackerOptions().rotation_rate_sigma, &t3, &r3);
  if (getenv("FE_VERBOSE"))
    printf("mean pose error: plain %.2f mm %.4f deg, refined %.2f mm %.4f deg, refreshed %.2f mm %.4f deg, "
           "estimated %.2f mm %.4f deg\n",
           1e3 * t0, r0 * 180 / M_PI, 1e3 * t1, r1 * 180 / M_PI, 1e3 * t2, r2 * 180 / M_PI, 1e3 * t3, r3 * 180 / M_PI);
  EXPECT_LT(t1, 0.7 * t0);
  EXPECT_LT(t2, 0.7 * t0);
  EXPECT_LT(t3, 0.7 * t1);
  EXPECT_LT(r3, 0.7 * r1);
}

TEST(SimTracking, CandidateDepthsConvergeWithinTheirIntervals) {
  const SimSequence& s = sequence("tiny_gs.json");
  const size_t k = 8;
  const auto host_pyr = s.pyramid(k);
  std::vector<Vec2> uv;
  std::vector<double> truth;
  s.points(*host_pyr, k, 800, &uv, &truth);
  CandidateTracer tracer(CandidateOptions(), ResidualOptions(), *s.camera, s.timing);
  std::vector<CandidatePoint> c = tracer.create(host_pyr->level(0), uv);
  const CandidateFrame host{RsFrame{s.pose(k), Vec6::Zero()}, {}, std::nan("")};
  for (size_t i = k + 1; i <= k + 3; ++i)
    tracer.trace(c, host, CandidateFrame{RsFrame{s.pose(i), Vec6::Zero()}, {}, std::nan("")}, s.pyramid(i)->level(0));
  int good = 0, inside = 0;
  for (const CandidatePoint& p : c) {
    if (p.status != CandidateStatus::Good) continue;
    ++good;
    size_t j = 0;
    while (uv[j] != p.uv) ++j;
    if (truth[j] >= p.idepth_min && truth[j] <= p.idepth_max) ++inside;
  }
  EXPECT_GT(good, 0.3 * c.size());
  EXPECT_GT(inside, 0.85 * good) << inside << " of " << good;
}

}  // namespace
}  // namespace rsvio
