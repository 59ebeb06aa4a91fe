// The monocular start of rsvio::Odometry: the two-view initialiser (backend/mono_initializer.h) and
// the frames since its reference, kept until the start succeeds so they can then be tracked.
// odometry.cpp hands a successful start over to the window (reference frame -> keyframe 0, the
// current frame -> keyframe 1 through the ordinary keyframe path, the frames in between tracked).
//
// Owns
// - the initialiser (corner tracks, essential matrix, its reference frame);
// - the frames since the initialiser's reference, oldest first: the reference keeps its pyramid (it
//   becomes keyframe 0), the frames in between their working image (to be tracked), the frame whose
//   addFrame() succeeded its pyramid.
//
// Invariants
// - frames().front() is the initialiser's reference whenever frames() is not empty; a new reference
//   drops the older frames (they cannot be placed any more).
// - Images are held only until clear(), which the hand-over calls.
#pragma once
#include <cmath>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "rsvio/backend/backend_options.h"
#include "rsvio/backend/mono_initializer.h"
#include "rsvio/core/types.h"
#include "rsvio/interfaces/camera.h"
#include "rsvio/photometric/image_pyramid.h"

namespace rsvio {

class MonoStart {
 public:
  struct StartFrame {
    int64_t index = 0, t_ns = 0;
    double exposure_ms = std::nan("");
    std::shared_ptr<const ImagePyramid> pyramid;  // the reference and the succeeding frame only
    cv::Mat working;                              // the frames in between only
  };

  MonoStart(const BackendOptions& options, const CameraModel& camera, const RowTiming& timing);

  // Returns true once a two-view pose is found with this frame (then reference(), T_cur_ref()).
  bool addFrame(const Frame& frame, std::shared_ptr<const ImagePyramid> pyr, const cv::Mat& working);
  const std::vector<StartFrame>& frames() const { return frames_; }
  const StartFrame& reference() const { return frames_.front(); }
  const SE3d& T_cur_ref() const { return initializer_.T_cur_ref(); }
  const Vec6& xi() const { return initializer_.xi(); }  // both frames' twist (rolling shutter), else 0
  // Each frame's own twist (rolling shutter with backend.init_rotation_rates; else both xi()).
  bool ratesUsed() const { return initializer_.ratesUsed(); }
  const Vec6& xiRef() const { return initializer_.xiRef(); }
  const Vec6& xiCur() const { return initializer_.xiCur(); }
  const std::string& status() const { return initializer_.status(); }
  const MonoInitializer& initializer() const { return initializer_; }
  void setRateSource(MonoInitializer::RateSource source) { initializer_.setRateSource(std::move(source)); }
  void setTrackGuessSource(MonoInitializer::RotationSource source) {
    initializer_.setTrackGuessSource(std::move(source));
  }
  void clear() { frames_.clear(); }

 private:
  MonoInitializer initializer_;
  std::vector<StartFrame> frames_;
};

}  // namespace rsvio
