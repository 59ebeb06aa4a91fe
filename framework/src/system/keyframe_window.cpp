// The sliding window (contract in keyframe_window.h): keyframes in and out, candidate activation,
// outlier removal, point and keyframe marginalisation with the smooth-motion terms, divergence tests.
#include "keyframe_window.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "rsvio/backend/keyframe_policy.h"
#include "rsvio/core/time.h"
#include "rsvio/io/trajectory.h"
#include "rsvio/photometric/pixel_selector.h"

namespace rsvio {
namespace {

RsFrame rsFrame(const Keyframe& kf, bool rolling) {
  return rolling ? RsFrame{kf.state.T_c_w, kf.state.twist, kf.w_dot} : RsFrame{kf.state.T_c_w, Vec6::Zero()};
}

// Projects every active point of `host` into `target` (one batch, no Jacobians); proj[i] is points[i]'s.
void projectHostPoints(const CameraModel& camera, const RowTiming& timing, const Keyframe& host, const RsFrame& target,
                       bool rolling, std::vector<RsHostProjection>* proj) {
  const Eigen::Index np = static_cast<Eigen::Index>(host.points.size());
  Eigen::Matrix3Xd b(3, np);
  Eigen::VectorXd vh(np), rho(np);
  for (Eigen::Index i = 0; i < np; ++i) {
    const ActivePoint& p = host.points[static_cast<size_t>(i)];
    b.col(i) = p.bearing;
    vh[i] = p.v;
    rho[i] = p.idepth;
  }
  RsProjectionOptions popt;
  popt.jacobians = false;
  projectRollingShutter(camera, timing, rsFrame(host, rolling), target, b, vh, rho, *proj, popt);
}

}  // namespace

Vec3 pointInWorld(const ActivePoint& p, const RowTiming& timing, bool rolling) {
  const Keyframe& host = *p.host;
  Vec3 Z = p.bearing / p.idepth;
  if (!rolling) return host.state.T_c_w.inverse() * Z;
  const double t_h = timing.rowTime(p.v);
  // The host saw the point at its row's time: X = T_h_w(t_h)^-1 (b / rho). Without w_dot in eq. 6's own
  // form (the bits of every run before w_dot existed), with it through rsPoseAt (rs_projection.h).
  if (!host.w_dot.isZero(0.0))
    return rsPoseAt(RsFrame{host.state.T_c_w, host.state.twist, host.w_dot}, t_h).inverse() * Z;
  return host.state.T_c_w.inverse() * Vec3(SE3d::exp(-host.state.twist * t_h) * Z);
}

KeyframeWindow::KeyframeWindow(const WindowSetup& setup, const CameraModel& camera, const RowTiming& timing,
                               SolverBackend& solver)
    : bo_(setup.backend),
      fo_(setup.frontend),
      seed_(setup.seed),
      rolling_(setup.ba.layout.rolling),
      camera_(camera),
      timing_(timing) {
  tracer_ = std::make_unique<CandidateTracer>(fo_.trace, fo_.residual, camera_, timing_);
  runner_ = std::make_unique<BlockRunner>(setup.ba.threads);
  ba_ = std::make_unique<BundleAdjuster>(setup.ba, camera_, timing_, solver);
  if (rolling_ && setup.smooth_motion) {
    SmoothMotionOptions so;
    so.information = setup.smooth_motion_information;
    smooth_motion_ = std::make_unique<SmoothMotionTerm>(so);
  }
  updateTerms();
  prior_ = std::make_unique<DynamicMarginalization>(setup.ba.layout, setup.dynamic_marginalization);
  globals_.state.line_delay_s = timing_.line_delay_s;
  if (setup.ba.layout.globalDim() > 0) {
    ba_->setGlobals(&globals_);
    prior_->setGlobals(&globals_);
  }
  min_act_dist_ = bo_.activation_min_dist_px;
}

std::vector<Keyframe*> KeyframeWindow::keyframesToMarginalize() const {
  if (window_.empty()) return {};
  return rsvio::keyframesToMarginalize(window_, bo_, first_kf_id_);
}

Keyframe& KeyframeWindow::insert(std::unique_ptr<Keyframe> kf) {
  kf->kf_id = next_kf_id_++;
  if (window_.empty()) {
    kf->gauge = true;
    first_kf_id_ = kf->kf_id;
  }
  linkMotionNeighbours(*kf);
  Keyframe* nk = kf.get();
  window_.push_back(std::move(kf));
  reindex(window_);
  for (auto& h : window_)
    if (h.get() != nk)
      for (ActivePoint& p : h->points) p.obs.push_back(ActiveObservation{nk});
  return *nk;
}

void KeyframeWindow::updateTerms() {
  std::vector<const WindowTerm*> terms;
  if (smooth_motion_) terms.push_back(smooth_motion_.get());
  if (inertial_ && inertial_->term()) terms.push_back(inertial_->term());
  ba_->setTerms(terms);
}

bool KeyframeWindow::initializeInertial(const std::vector<ViInitKeyframe>& keyframes) {
  if (!inertial_ || !inertial_->tryInitialize(keyframes, window_, *ba_, *prior_)) return false;
  updateTerms();
  return true;
}

void KeyframeWindow::optimize(int max_iterations) {
  last_ba_ = ba_->optimize(window_, prior_->active(), max_iterations);
  if (inertial_ && inertial_->initialised()) prior_->update(inertial_->scale(), nsToS(window_.back()->t_ns));
  if (ba_->config().layout.lineDelay() && timing_.line_delay_s != globals_.state.line_delay_s) {
    timing_.line_delay_s = globals_.state.line_delay_s;
    tracer_->setTiming(timing_);
  }
}

void KeyframeWindow::evaluate() { ba_->evaluate(window_, prior_->active()); }

void KeyframeWindow::releasePoints(WindowSink& sink) {
  for (auto& kf : window_) {
    for (const ActivePoint& p : kf->points) {
      for (const ActiveObservation& o : p.obs)
        if (o.state == ObsState::kIn) sink.observationLeaves(p, o);
      if (p.numIn() > 0) sink.pointLeaves(p);
    }
    kf->points.clear();
    kf->candidates.clear();
  }
}

int KeyframeWindow::numActivePoints() const {
  int n = 0;
  for (const auto& kf : window_) n += static_cast<int>(kf->points.size());
  return n;
}

double KeyframeWindow::medianIdepth() const {
  std::vector<double> v;
  for (const auto& kf : window_)
    for (const ActivePoint& p : kf->points) v.push_back(p.idepth);
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

void KeyframeWindow::traceCandidates(const CandidateFrame& target, const ImageLevel& target_level0) {
  // One block per host keyframe: each writes only its own candidates, so the result does not depend
  // on the thread count or on which thread ran which host.
  runner_->run(static_cast<int>(window_.size()), [&](int i) {
    Keyframe& kf = *window_[static_cast<size_t>(i)];
    if (kf.candidates.empty()) return;
    CandidateFrame host;
    host.pose = rsFrame(kf, rolling_);
    host.affine = kf.state.affine;
    host.exposure_ms = kf.exposure_ms;
    tracer_->trace(kf.candidates, host, target, target_level0);
  });
}

void KeyframeWindow::createCandidates(Keyframe& kf) {
  PixelSelectorOptions so = fo_.select;
  so.seed = seed_ * 1000003ULL + static_cast<uint64_t>(kf.kf_id);
  const std::vector<SelectedPixel> px = PixelSelector(so).select(*kf.pyramid);
  std::vector<Vec2> pixels;
  pixels.reserve(px.size());
  for (const SelectedPixel& p : px) pixels.emplace_back(p.u, p.v);
  kf.candidates = tracer_->create(kf.pyramid->level(0), pixels);
}

void KeyframeWindow::activateCandidates(Keyframe& newest) {
  // DSO's adaptive distance between active points (activatePointsMT).
  const int n = numActivePoints();
  const double N = bo_.active_points;
  if (n < N * 0.66) min_act_dist_ -= 0.8;
  if (n < N * 0.8) min_act_dist_ -= 0.5;
  else if (n < N * 0.9) min_act_dist_ -= 0.2;
  else if (n < N) min_act_dist_ -= 0.1;
  if (n > N * 1.5) min_act_dist_ += 0.8;
  if (n > N * 1.3) min_act_dist_ += 0.5;
  if (n > N * 1.15) min_act_dist_ += 0.2;
  if (n > N) min_act_dist_ += 0.1;
  min_act_dist_ = std::clamp(min_act_dist_, 0.0, 4.0);

  // Distance map on level 1 of the newest keyframe: distance to the nearest active point.
  const int lvl = newest.pyramid->numLevels() > 1 ? 1 : 0;
  const ImageLevel& L = newest.pyramid->level(lvl);
  cv::Mat free_px(L.height(), L.width(), CV_8U, cv::Scalar(255));
  RsProjectionOptions popt;
  popt.jacobians = false;
  std::vector<RsHostProjection> proj;
  const RsFrame target = rsFrame(newest, rolling_);
  auto toLevel = [&](const Vec2& uv, int* x, int* y) {
    *x = static_cast<int>(std::lround(L.toLevel(static_cast<float>(uv.x()))));
    *y = static_cast<int>(std::lround(L.toLevel(static_cast<float>(uv.y()))));
    return *x >= 0 && *y >= 0 && *x < L.width() && *y < L.height();
  };
  int occupied = 0;
  for (auto& host : window_) {
    if (host.get() == &newest || host->points.empty()) continue;
    projectHostPoints(camera_, timing_, *host, target, rolling_, &proj);
    for (const RsHostProjection& pr : proj) {
      int x, y;
      if (pr.valid && toLevel(pr.uv, &x, &y)) {
        free_px.at<uint8_t>(y, x) = 0;
        ++occupied;
      }
    }
  }
  cv::Mat dist;
  if (occupied > 0) {
    cv::distanceTransform(free_px, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  } else {
    dist = cv::Mat(L.height(), L.width(), CV_32F, cv::Scalar(1e6f));
  }
  const int R = static_cast<int>(std::ceil(min_act_dist_));
  auto stamp = [&](int x, int y) {
    for (int dy = -R; dy <= R; ++dy)
      for (int dx = -R; dx <= R; ++dx) {
        const int xx = x + dx, yy = y + dy;
        if (xx < 0 || yy < 0 || xx >= dist.cols || yy >= dist.rows) continue;
        float& d = dist.at<float>(yy, xx);
        d = std::min(d, static_cast<float>(std::sqrt(dx * dx + dy * dy)));
      }
  };

  std::vector<std::pair<Keyframe*, size_t>> new_points;  // host, index into host->points
  for (auto& host : window_) {
    if (host.get() == &newest || host->candidates.empty()) continue;
    std::vector<CandidatePoint>& C = host->candidates;
    const Eigen::Index nc = static_cast<Eigen::Index>(C.size());
    Eigen::Matrix3Xd b(3, nc);
    Eigen::VectorXd vh(nc), rho(nc);
    for (Eigen::Index i = 0; i < nc; ++i) {
      const CandidatePoint& c = C[static_cast<size_t>(i)];
      b.col(i) = c.bearing;
      vh[i] = c.uv.y();
      rho[i] = c.hasDepth() ? std::max(c.idepth(), 1e-6) : 0.0;  // 0: not traced yet, left out
    }
    projectRollingShutter(camera_, timing_, rsFrame(*host, rolling_), target, b, vh, rho, proj, popt);
    std::vector<CandidatePoint> keep;
    keep.reserve(C.size());
    for (Eigen::Index i = 0; i < nc; ++i) {
      const CandidatePoint& c = C[static_cast<size_t>(i)];
      if (c.status == CandidateStatus::OutOfBounds) continue;
      if (!c.hasDepth()) {
        keep.push_back(c);
        continue;
      }
      const RsHostProjection& pr = proj[static_cast<size_t>(i)];
      if (!pr.valid || !camera_.inImage(pr.uv, 4.0)) continue;  // left the view of the newest keyframe
      int x, y;
      if (!c.readyForActivation(fo_.trace) || !toLevel(pr.uv, &x, &y) || dist.at<float>(y, x) < min_act_dist_) {
        keep.push_back(c);
        continue;
      }
      stamp(x, y);
      ActivePoint p;
      p.host = host.get();
      p.id = next_point_id_++;
      p.u = static_cast<float>(c.uv.x());
      p.v = static_cast<float>(c.uv.y());
      p.bearing = c.bearing;
      p.d_bearing_d_uv = c.d_bearing_d_uv;
      p.idepth = std::max(c.idepth(), 1e-6);
      p.pattern = c.pattern;
      for (auto& t : window_)
        if (t.get() != host.get()) p.obs.push_back(ActiveObservation{t.get()});
      host->points.push_back(p);
      new_points.emplace_back(host.get(), host->points.size() - 1);
    }
    C.swap(keep);
  }
  if (new_points.empty()) return;
  std::vector<ActivePoint*> ptrs;
  for (const auto& [h, i] : new_points) ptrs.push_back(&h->points[i]);
  ba_->optimizeDepths(window_, ptrs, bo_.activation_iterations);
  // Keep the observations that fit; drop points that fit nowhere (DSO: at least one good residual) and
  // points whose depth the window_ hardly constrains (DSO's minimum inverse-depth information).
  for (ActivePoint* p : ptrs) {
    p->obs.erase(std::remove_if(p->obs.begin(), p->obs.end(),
                                [](const ActiveObservation& o) { return o.state != ObsState::kIn; }),
                 p->obs.end());
    if (!(p->idepth_hessian >= bo_.activation_min_idepth_hessian)) p->obs.clear();
  }
  for (auto& host : window_) {
    auto& P = host->points;
    P.erase(std::remove_if(P.begin(), P.end(), [](const ActivePoint& p) { return p.obs.empty() || !(p.idepth > 1e-5); }),
            P.end());
  }
}

TrackingReference KeyframeWindow::trackingReference(const Keyframe& newest) const {
  TrackingReference ref;
  ref.frame_id = newest.frame_index;
  ref.t_ns = newest.t_ns;
  ref.T_c_w = newest.state.T_c_w;
  ref.twist = rolling_ ? newest.state.twist : Vec6::Zero();
  ref.w_dot = rolling_ ? newest.w_dot : Vec3::Zero();
  ref.affine = newest.state.affine;
  ref.exposure_ms = newest.exposure_ms;
  ref.pyramid = newest.pyramid;
  std::vector<RsHostProjection> proj;
  const RsFrame target = rsFrame(newest, rolling_);
  for (const auto& host : window_) {
    if (host->points.empty()) continue;
    if (host.get() == &newest) {
      for (const ActivePoint& p : host->points) ref.points.push_back({Vec2(p.u, p.v), p.idepth, 1.0});
      continue;
    }
    projectHostPoints(camera_, timing_, *host, target, rolling_, &proj);
    for (size_t i = 0; i < proj.size(); ++i) {
      const RsHostProjection& pr = proj[i];
      if (!pr.valid || !camera_.inImage(pr.uv, 2.0)) continue;
      const ActivePoint& p = host->points[i];
      const Vec3 X = pointInWorld(p, timing_, rolling_);
      const Vec3 P = SE3d::exp(target.xi * pr.t_s) * (target.T_c_w0 * X);
      const double d = P.norm();
      if (!(d > 0)) continue;
      ref.points.push_back({pr.uv, 1.0 / d, 1.0});
    }
  }
  return ref;
}

void KeyframeWindow::removeOutliersAndMarginalizePoints(Keyframe& newest, WindowSink& sink) {
  std::vector<ActivePoint*> to_marg;
  std::vector<std::pair<Keyframe*, int64_t>> to_drop;
  const size_t min_good = static_cast<size_t>(bo_.min_good_residuals);
  for (auto& host : window_) {
    for (ActivePoint& p : host->points) {
      bool newest_oob = false;
      for (const ActiveObservation& o : p.obs)
        if (o.target == &newest && o.state == ObsState::kOob) newest_oob = true;
      // An outlier leaves here (the diagnostics log keeps it, with weight 0: probe.vignetting needs the
      // large residuals that the outlier threshold cuts off).
      for (const ActiveObservation& o : p.obs)
        if (o.state == ObsState::kOutlier) sink.observationLeaves(p, o);
      p.obs.erase(std::remove_if(p.obs.begin(), p.obs.end(),
                                 [](const ActiveObservation& o) { return o.state != ObsState::kIn; }),
                  p.obs.end());
      if (p.obs.empty() || !(p.idepth > 1e-5) || !std::isfinite(p.idepth)) {
        p.idepth = -1.0;  // marks the drop
        continue;
      }
      size_t vis_in_marg = 0;
      for (const ActiveObservation& o : p.obs) vis_in_marg += o.target->flagged_for_marg;
      const bool oob = newest_oob || (p.obs.size() >= min_good && p.obs.size() - vis_in_marg < min_good);
      if (!host->flagged_for_marg && !oob) continue;
      if (p.obs.size() >= min_good && p.idepth_hessian > bo_.min_idepth_hessian_marg) {
        to_marg.push_back(&p);
      } else {
        p.idepth = -1.0;
      }
    }
  }
  if (!to_marg.empty()) {
    std::vector<int> blocks;
    Eigen::MatrixXd H;
    Eigen::VectorXd b;
    ba_->pointsTerm(window_, to_marg, bo_.marg_weight_factor, &blocks, &H, &b);
    if (!blocks.empty()) {
      std::vector<Keyframe*> kfs;
      for (int k : blocks) kfs.push_back(window_[static_cast<size_t>(k)].get());
      prior_->addScaleFreeTerm(kfs, H, b, bo_.marg_project_scale, ba_->config().layout.lineDelay());
    }
    for (ActivePoint* p : to_marg) {
      for (const ActiveObservation& o : p->obs)
        if (o.state == ObsState::kIn) sink.observationLeaves(*p, o);
      sink.pointLeaves(*p);
      p->idepth = -1.0;
    }
  }
  for (auto& host : window_) {
    auto& P = host->points;
    const size_t before = P.size();
    P.erase(std::remove_if(P.begin(), P.end(), [](const ActivePoint& p) { return p.idepth < 0.0; }), P.end());
    host->points_out += static_cast<int>(before - P.size());
  }
}

void KeyframeWindow::marginalizeKeyframe(Keyframe* kf, WindowSink& sink) {
  for (auto& host : window_) {
    if (host.get() == kf) continue;
    for (ActivePoint& p : host->points) {
      auto it = std::find_if(p.obs.begin(), p.obs.end(), [&](const ActiveObservation& o) { return o.target == kf; });
      if (it == p.obs.end()) continue;
      if (it->state == ObsState::kIn) sink.observationLeaves(p, *it);
      p.obs.erase(it);
    }
  }
  kf->points_out += static_cast<int>(kf->points.size());
  kf->points.clear();
  kf->candidates.clear();
  marginalizeMotionTerms(kf);
  if (inertial_) inertial_->marginalizeTerms(*kf, window_, *prior_);
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  ba_->keyframePriorTerm(*kf, &H, &b);
  if (H.cwiseAbs().maxCoeff() > 0.0) prior_->addTerm({kf}, H, b);
  prior_->marginalizeKeyframe(kf);
  sink.keyframeLeaves(*kf);
  window_.erase(std::remove_if(window_.begin(), window_.end(),
                               [&](const std::unique_ptr<Keyframe>& k) { return k.get() == kf; }),
                window_.end());
  reindex(window_);
}

// A new keyframe (not yet in the window) gets its smooth-motion term with the newest keyframe as its
// previous neighbour; that keyframe's term gains the new one as its next (smooth_motion_term.h).
void KeyframeWindow::linkMotionNeighbours(Keyframe& kf) {
  if (!smooth_motion_) return;
  kf.motion_term = true;
  kf.motion_prev = window_.empty() ? nullptr : window_.back().get();
  kf.motion_next = nullptr;
  if (kf.motion_prev && kf.motion_prev->motion_term) kf.motion_prev->motion_next = &kf;
}

// Every active smooth-motion term that involves `leaving` goes into the marginalisation prior
// (linearised now, scale-free like the marginalised points) and is switched off.
void KeyframeWindow::marginalizeMotionTerms(const Keyframe* leaving) {
  if (!smooth_motion_) return;
  const int kd = ba_->config().layout.kfDim();
  for (auto& w : window_) {
    if (!w->motion_term || (w.get() != leaving && w->motion_prev != leaving && w->motion_next != leaving)) continue;
    std::vector<Keyframe*> kfs;
    Eigen::MatrixXd H;
    Eigen::VectorXd b;
    smooth_motion_->linearizeOne(*w, ba_->config().layout, &kfs, &H, &b);
    w->motion_term = false;
    if (kfs.empty()) continue;
    for (size_t i = 0; i < kfs.size(); ++i)
      if (kfs[i]->gauge) {  // fixed dimensions are zero in added terms (marginalization.h)
        const Eigen::Index o = static_cast<Eigen::Index>(i) * kd;
        H.middleRows(o, 6).setZero();
        H.middleCols(o, 6).setZero();
        b.segment(o, 6).setZero();
      }
    prior_->addScaleFreeTerm(kfs, H, b, bo_.marg_project_scale);
  }
}

std::string KeyframeWindow::divergence(std::string* warning) {
  const BundleAdjustmentStats& s = last_ba_;
  const Keyframe& nk = *window_.back();
  std::ostringstream where;
  where << " after the keyframe at frame " << nk.frame_index << " (t " << io::formatSeconds(nk.t_ns) << " s)";
  for (const auto& kf : window_)
    if (!kf->state.T_c_w.translation().allFinite() || !kf->state.T_c_w.unit_quaternion().coeffs().allFinite()) {
      return "non-finite keyframe state" + where.str();
    }
  if (s.solver_failed) *warning = "solver: " + s.message + where.str();
  std::ostringstream os;
  if (s.num_in > 0 && s.rmse() > bo_.fail_max_rmse) {
    os << "exploding energy: photometric RMSE " << s.rmse() << " > " << bo_.fail_max_rmse << where.str();
  } else if (s.num_obs >= 50 && s.inlierRatio() < bo_.fail_min_inlier_ratio) {
    os << "too few inliers: " << s.num_in << " of " << s.num_obs << " observations (" << s.inlierRatio() << " < "
       << bo_.fail_min_inlier_ratio << ")" << where.str();
  } else if (numActivePoints() < bo_.fail_min_points) {
    os << "too few points: " << numActivePoints() << " active points < " << bo_.fail_min_points << where.str();
  } else {
    const double med = medianIdepth();
    if (initial_median_idepth_ <= 0.0) {
      initial_median_idepth_ = med;
    } else if (med > 0.0) {
      const double ratio = med / initial_median_idepth_;
      if (ratio > bo_.fail_max_scale_change || ratio < 1.0 / bo_.fail_max_scale_change)
        os << "scale collapse: the median inverse depth changed by a factor " << ratio << " since initialisation"
           << where.str();
    }
  }
  return os.str();
}

}  // namespace rsvio
