// Monocular start (backend/mono_initializer.h): corner tracks until a two-view pose with parallax is
// found, then the reference frame becomes the first keyframe (the gauge), its candidates are traced into
// the current frame, the current frame becomes the second keyframe through the ordinary keyframe path
// (activation, bundle adjustment), and the frames in between are tracked against it.
#include <sstream>

#include "odometry_impl.h"
#include "rsvio/core/time.h"

namespace rsvio {

FrameStatus Odometry::Impl::initialise(const Frame& frame, std::shared_ptr<const ImagePyramid> pyr,
                                       const cv::Mat& working) {
  bool done = false;
  {
    ScopedStage st(stages, "initialise");
    const int64_t ref_before = initializer->referenceIndex();
    done = initializer->addFrame(pyr, frame.index);
    if (initializer->referenceIndex() != ref_before) init_frames.clear();  // new reference: older frames are lost
    InitFrame f;
    f.index = frame.index;
    f.t_ns = frame.t_ns;
    f.exposure_ms = frame.exposure_ms;
    if (init_frames.empty() || done) f.pyramid = pyr;  // the reference and the current frame keep theirs
    if (!done && !init_frames.empty()) f.working = working;
    init_frames.push_back(f);
  }
  FrameRecord rec;
  rec.index = frame.index;
  rec.t_ns = frame.t_ns;
  rec.exposure_ms = frame.exposure_ms;
  if (!done) {
    frames.push_back(rec);
    const int64_t first = frames.front().index;
    if (frame.index - first + 1 >= bo.init_max_frames) {
      std::ostringstream os;
      os << "monocular initialisation failed after " << (frame.index - first + 1)
         << " frames: " << initializer->status();
      fail(os.str());
      return FrameStatus{false, false, "failed: " + failure};
    }
    return FrameStatus{false, false, "initialising: " + initializer->status()};
  }

  // The reference frame becomes keyframe 0 with the identity pose.
  ScopedStage st(stages, "initialise");
  const InitFrame ref = init_frames.front();
  const SE3d T_cur_ref = initializer->T_cur_ref();
  for (FrameRecord& r : frames)
    if (r.index == ref.index) {
      r.tracked = true;
      r.T_c_w = SE3d();
    }
  FrameRecord ref_rec;
  ref_rec.index = ref.index;
  ref_rec.t_ns = ref.t_ns;
  ref_rec.tracked = true;
  pushHistory(ref_rec);
  auto kf0 = std::make_unique<Keyframe>();
  kf0->frame_index = ref.index;
  kf0->t_ns = ref.t_ns;
  kf0->kf_id = next_kf_id++;
  kf0->exposure_ms = ref.exposure_ms;
  kf0->pyramid = ref.pyramid;
  kf0->gauge = true;
  kf0->motion_term = smooth_motion != nullptr;
  first_kf_id = kf0->kf_id;
  Keyframe& k0 = *kf0;
  window.push_back(std::move(kf0));
  reindex(window);
  for (FrameRecord& r : frames)
    if (r.index == ref.index) {
      r.keyframe = true;
      r.ref_kf_id = k0.kf_id;
    }
  createCandidates(k0);
  CandidateFrame host, target;
  host.pose = RsFrame{SE3d(), Vec6::Zero()};
  host.exposure_ms = ref.exposure_ms;
  target.pose = RsFrame{T_cur_ref, Vec6::Zero()};
  target.exposure_ms = frame.exposure_ms;
  tracer->trace(k0.candidates, host, target, pyr->level(0));
  recordKeyframe(k0);

  // The current frame: a tracked frame that becomes keyframe 1.
  rec.tracked = true;
  rec.T_c_w = T_cur_ref;
  rec.ref_kf_id = k0.kf_id;
  rec.T_f_ref = T_cur_ref;
  frames.push_back(rec);
  pushHistory(rec);
  makeKeyframe(frame.index, frame.t_ns, frame.exposure_ms, pyr, T_cur_ref, AffineBrightness());
  initialized = true;
  if (failed) return FrameStatus{false, true, "failed: " + failure};

  // Frames between the two keyframes: tracked against keyframe 1 from poses interpolated in time.
  const SE3d T1 = window.back()->state.T_c_w;
  const Vec6 log_rel = T1.log();  // keyframe 0 is the identity
  const double span = nsToS(frame.t_ns - ref.t_ns);
  for (const InitFrame& f : init_frames) {
    if (f.index == ref.index || f.index == frame.index || f.working.empty()) continue;
    const ImagePyramid p(f.working, fo.pyramid_levels);
    TrackingFrame info;
    info.t_ns = f.t_ns;
    info.exposure_ms = f.exposure_ms;
    const double s = span > 0 ? nsToS(f.t_ns - ref.t_ns) / span : 0.5;
    const TrackResult r = tracker->track(p, info, {SE3d::exp(log_rel * s)});
    if (!r.ok()) continue;
    for (FrameRecord& fr : frames)
      if (fr.index == f.index) {
        fr.tracked = true;
        fr.T_c_w = r.T_c_w;
        fr.affine = r.affine;
        fr.ref_kf_id = window.back()->kf_id;
        fr.T_f_ref = r.T_c_w * T1.inverse();
      }
  }
  init_frames.clear();
  first_rmse = std::nan("");
  std::ostringstream os;
  os << "initialised (" << initializer->status() << ")";
  return FrameStatus{true, true, os.str()};
}

}  // namespace rsvio
