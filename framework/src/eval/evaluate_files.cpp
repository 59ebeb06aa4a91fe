// File-level evaluation (rsvio/eval/evaluate_files.h).
#include "rsvio/eval/evaluate_files.h"

#include <algorithm>
#include <filesystem>

#include "rsvio/core/error.h"
#include "rsvio/eval/extrinsic.h"
#include "rsvio/io/trajectory.h"

namespace rsvio::eval {

FileEvalOutcome evaluateFiles(const FileEvalRequest& req) {
  namespace fs = std::filesystem;
  FileEvalOutcome out;
  auto& ctx = out.context;
  std::string gt_path = req.gt_path;
  if (!req.dataset_dir.empty()) {
    const auto found = io::findDatasetGroundTruth(req.dataset_dir);
    if (!found) {
      throw DataError::at(req.dataset_dir, 0,
                          "no ground truth (looked for mav0/state_groundtruth_estimate0/data.csv and mav0/mocap0/data.csv)");
    }
    gt_path = *found;
  }
  if (gt_path.empty()) throw Error("evaluation needs a ground-truth file or a dataset folder");
  io::Trajectory gt = io::readGroundTruth(gt_path);
  io::Trajectory est = io::readTum(req.est_path);
  est.poses.erase(std::remove_if(est.poses.begin(), est.poses.end(),
                                 [&](const io::StampedPose& p) { return p.t_ns < req.est_from_ns || p.t_ns > req.est_to_ns; }),
                  est.poses.end());
  out.estimates_in_span = est.poses.size();
  ctx.gt_path = gt_path;
  ctx.est_path = req.est_path;
  ctx.est_frame = io::poseFrameName(est.frame);

  if (est.frame == io::PoseFrame::kCamera && gt.frame == io::PoseFrame::kBody) {
    std::string calib = req.calib_path;
    if (calib.empty() && !req.dataset_dir.empty()) calib = (fs::path(req.dataset_dir) / "mav0/cam0/sensor.yaml").string();
    if (calib.empty()) {
      throw Error(req.est_path + ": the estimate holds camera poses ('# frame: camera') but " + gt_path +
                  " holds body poses: give the dataset (--data DIR) or its sensor.yaml (--calib FILE) for T_BS");
    }
    gt = mapBodyToCamera(gt, readSensorYamlTBS(calib));
    ctx.frame_mapping = "ground-truth body poses mapped to camera poses through T_BS of " + calib;
  } else if (est.frame == io::PoseFrame::kUnknown) {
    ctx.frame_mapping = "none (the estimate has no '# frame:' header: compared as given)";
  } else if (gt.frame == io::PoseFrame::kUnknown) {
    ctx.frame_mapping = "none (the ground truth's frame is not stated: compared as given)";
  } else if (gt.frame == est.frame) {
    ctx.frame_mapping = std::string("none (both are ") + io::poseFrameName(est.frame) + " poses)";
  } else {
    throw Error(req.est_path + ": the estimate holds " + io::poseFrameName(est.frame) + " poses but " + gt_path +
                " holds " + io::poseFrameName(gt.frame) + " poses; only body-to-camera mapping is supported");
  }

  EvalOptions opt = req.options;
  if (req.align) {
    opt.align = *req.align;
    ctx.align_reason = "as asked";
  } else {
    opt.align = defaultAlignFor(est.frame);
    ctx.align_reason = est.frame == io::PoseFrame::kCamera ? "default for camera poses (no metric scale)"
                                                            : "default for metric poses";
  }
  out.result = evaluateTrajectory(gt, est, opt);
  return out;
}

}  // namespace rsvio::eval
