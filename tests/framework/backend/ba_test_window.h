// A synthetic window for the back-end tests: keyframes rendered from the front-end tests' ray-cast scene
// (textured planes, exact depth) at known poses, points selected in chosen hosts with their true
// inverse depths, observed in every other keyframe. Global or rolling shutter (pose asked per row).
#pragma once
#include <memory>
#include <random>
#include <vector>

#include "framework/photometric/test_camera.h"
#include "rsvio/backend/window.h"
#include "rsvio/photometric/pixel_selector.h"

namespace rsvio::test {

inline Vec6 tw(double tx, double ty, double tz, double rx, double ry, double rz) {
  Vec6 v;
  v << tx, ty, tz, rx, ry, rz;
  return v;
}

struct TestWindow {
  PinholeK K;
  SyntheticScene scene{11};
  TestPinholeCamera camera{K};
  RowTiming timing;
  std::vector<KeyframeState> truth;
  KeyframeList window;

  // n keyframes moving sideways and forward with small rotations; twists (per second) when rolling.
  // twist_scale multiplies the per-keyframe twists (rolling shutter: a stronger readout distortion).
  // smooth_twists: every twist is the poses' own constant velocity (the keyframes lie on one
  // constant-twist motion, 0.1 s apart), as the smooth-motion term assumes.
  // rotation_scale multiplies the rotation between keyframes (a faster turn: a stronger readout effect).
  explicit TestWindow(int n, bool rolling = false, double line_delay_s = 0.0, double twist_scale = 1.0,
                      double texel_m = 0.012, bool smooth_twists = false, double rotation_scale = 1.0) {
    const Vec6 step = tw(-0.12, 0.02, -0.05, 0.01 * rotation_scale, -0.02 * rotation_scale, 0.005 * rotation_scale);
    if (texel_m != 0.012) {
      const Eigen::Vector3d X(1, 0, 0), Y(0, 1, 0), Z(0, 0, 1);
      scene.setPlanes({{Eigen::Vector3d(-3, -3, 4.0), X, Y, texel_m, 0},
                       {Eigen::Vector3d(-3, 1.2, 0.0), X, Z, texel_m, 1},
                       {Eigen::Vector3d(-2.5, -3, 0.0), Z, Y, texel_m, 1}},
                      false);
    }
    timing = rolling ? RowTiming::rolling(K.height * 0.5 - 0.5, line_delay_s, true) : RowTiming::global(K.height * 0.5 - 0.5);
    for (int i = 0; i < n; ++i) {
      KeyframeState s;
      s.T_c_w = SE3d::exp(step * i);
      if (rolling) s.twist = twist_scale * tw(0.6 - 0.1 * i, 0.2, 0.3, 0.3, -0.5 + 0.1 * i, 0.2);
      if (rolling && smooth_twists) s.twist = step / 0.1;
      truth.push_back(s);
      auto kf = std::make_unique<Keyframe>();
      kf->frame_index = 10 * i;
      kf->t_ns = static_cast<int64_t>(i) * 100000000;
      kf->kf_id = i;
      kf->state = s;
      const RowTiming tm = timing;
      const cv::Mat img = scene.render(K, [&](double v) { return toPoseCW(SE3d::exp(s.twist * tm.rowTime(v)) * s.T_c_w); });
      kf->pyramid = std::make_shared<ImagePyramid>(img, 4);
      window.push_back(std::move(kf));
    }
    reindex(window);
  }

  // Selects about `num` points in keyframe `host` with their true inverse depths (1 / distance) and
  // one observation in every other keyframe.
  void addPoints(int host, int num, uint64_t seed = 3) {
    Keyframe& h = *window[static_cast<size_t>(host)];
    PixelSelectorOptions so;
    so.num_points = num;
    so.seed = seed;
    const ResidualOptions ro;
    for (const SelectedPixel& sp : PixelSelector(so).select(*h.pyramid)) {
      ActivePoint p;
      p.host = &h;
      p.id = next_id++;
      p.u = static_cast<float>(sp.u);
      p.v = static_cast<float>(sp.v);
      Eigen::Matrix3Xd b;
      Eigen::Matrix2Xd uv(2, 1);
      uv << sp.u, sp.v;
      std::vector<uint8_t> valid;
      std::vector<Jac32> J;
      camera.unproject(uv, b, valid, &J);
      if (!valid[0]) continue;
      p.bearing = b.col(0);
      p.d_bearing_d_uv = J[0];
      // True distance along the bearing: ray-cast from the host pose at this row's time.
      const KeyframeState& s = truth[static_cast<size_t>(host)];
      const SE3d T_row = SE3d::exp(s.twist * timing.rowTime(sp.v)) * s.T_c_w;
      const SE3d T_w_c = T_row.inverse();
      double val = 0, dist = 0;
      if (!scene.trace(T_w_c.translation(), T_w_c.so3() * p.bearing, &val, &dist)) continue;
      p.idepth = 1.0 / dist;
      if (!makePatternHost(h.pyramid->level(0), p.u, p.v, ro, &p.pattern)) continue;
      for (auto& kf : window)
        if (kf.get() != &h) p.obs.push_back(ActiveObservation{kf.get()});
      h.points.push_back(p);
    }
  }

  // Every keyframe gets an active smooth-motion term with its window neighbours (smooth_motion_term.h).
  void linkMotionNeighbours() {
    for (size_t i = 0; i < window.size(); ++i) {
      Keyframe& kf = *window[i];
      kf.motion_term = true;
      kf.motion_prev = i > 0 ? window[i - 1].get() : nullptr;
      kf.motion_next = i + 1 < window.size() ? window[i + 1].get() : nullptr;
    }
  }

  int numPoints() const {
    int n = 0;
    for (const auto& kf : window) n += static_cast<int>(kf->points.size());
    return n;
  }

  int64_t next_id = 0;
};

}  // namespace rsvio::test
