// Monocular initialisation for runs without an IMU: the relative pose of a later frame to a reference
// frame, with enough parallax that the depths of the reference's candidate points can be found by the
// epipolar search, and a scale (median depth 1).
//
// DSO (Engel et al. 2018, sec. 3.4 "Initialization") optimises pose and inverse depths jointly from a
// constant-depth start, coarse to fine, with an inverse-depth regulariser. rsvio takes the classic
// two-view route for that first guess, then hands it to the same photometric machinery DSO ends with
// (epipolar search of the candidates, then the windowed bundle adjustment), which is robust to the
// fast rotations of handheld motion that a constant-depth start struggles with:
// - corners (Shi-Tomasi) of the reference are tracked frame to frame with pyramidal Lucas-Kanade on
//   the frames' image pyramids (9x9 window, coarse to fine) and a forward-backward check (1 px); when
//   fewer than a third survive, the current frame becomes the new reference;
// - from init_min_frames on, once the median corner flow exceeds init_min_flow_px of the image
//   diagonal: essential matrix by the normalised 8-point algorithm in RANSAC (Sampson distance, on the
//   unit-focal image plane of the camera's own unprojection, so any camera model works), the pose of
//   the four decompositions with most points in front of both cameras, and the checks: inlier ratio
//   >= init_min_inlier_ratio, median triangulation angle >= init_min_parallax_deg, 90 % of the
//   inliers in front.
// - The result T_cur_ref (camera_cur from camera_ref) is scaled so that the median depth of the
//   triangulated inlier corners in the reference is 1 (DSO also normalises the initial scene to mean
//   inverse depth 1).
// Rolling shutter is ignored here (the bundle adjustment that follows models it).
#pragma once
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "rsvio/backend/backend_options.h"
#include "rsvio/lie/se3.h"
#include "rsvio/photometric/image_pyramid.h"

namespace rsvio {

class CameraModel;

class MonoInitializer {
 public:
  MonoInitializer(const BackendOptions& options, const CameraModel& camera);

  // pyramid: the frame's image pyramid (working image). Returns true once a pose is found; then
  // T_cur_ref(), referenceIndex() describe it. The first call (and every reset) sets the reference.
  // Deterministic (RANSAC samples from a fixed seed).
  bool addFrame(std::shared_ptr<const ImagePyramid> pyramid, int64_t frame_index);

  bool hasReference() const { return ref_index_ >= 0; }
  int64_t referenceIndex() const { return ref_index_; }
  int framesSinceReference() const { return frames_since_ref_; }
  const SE3d& T_cur_ref() const { return T_cur_ref_; }
  double medianParallaxDeg() const { return parallax_deg_; }
  const std::string& status() const { return status_; }  // one line: what the last attempt found
  int numTracks() const { return static_cast<int>(cur_pts_.size()); }

 private:
  void reset(int64_t frame_index);
  bool tryInitialise();

  BackendOptions options_;
  const CameraModel& camera_;
  int64_t ref_index_ = -1;
  int frames_since_ref_ = 0;
  int initial_tracks_ = 0;
  std::shared_ptr<const ImagePyramid> prev_;
  std::vector<cv::Point2f> ref_pts_, cur_pts_;
  SE3d T_cur_ref_;
  double parallax_deg_ = 0.0;
  std::string status_;
};

}  // namespace rsvio
