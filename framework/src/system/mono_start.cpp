// The monocular start's frames (contract in mono_start.h).
#include "mono_start.h"

namespace rsvio {

MonoStart::MonoStart(const BackendOptions& options, const CameraModel& camera, const RowTiming& timing)
    : initializer_(options, camera, timing) {}

bool MonoStart::addFrame(const Frame& frame, std::shared_ptr<const ImagePyramid> pyr, const cv::Mat& working) {
  const int64_t ref_before = initializer_.referenceIndex();
  const bool done = initializer_.addFrame(pyr, frame.index, frame.t_ns);
  if (initializer_.referenceIndex() != ref_before) frames_.clear();  // new reference: older frames are lost
  StartFrame f;
  f.index = frame.index;
  f.t_ns = frame.t_ns;
  f.exposure_ms = frame.exposure_ms;
  if (frames_.empty() || done) f.pyramid = pyr;  // the reference and the current frame keep theirs
  if (!done && !frames_.empty()) f.working = working;
  frames_.push_back(f);
  return done;
}

}  // namespace rsvio
