// Evaluating an estimated trajectory file against a ground-truth file or a dataset's ground truth: the
// whole of `rsvio eval` short of printing, shared with `rsvio compare` (which evaluates a run's
// keyframes.tum itself when its report has no eval).
//
// Frames: when the estimate's header says "# frame: camera" and the ground truth is of the body (EuRoC
// files, or TUM with "# frame: body"), the ground truth is mapped to camera poses through T_BS
// (eval/extrinsic.h) read from calib_path, or <dataset>/mav0/cam0/sensor.yaml. Without a calibration
// that is an error, not a silent comparison of different frames. Any other combination is compared as
// given and EvalContext::frame_mapping says so.
// Alignment: as asked, else defaultAlignFor(estimate frame) (Sim(3) for camera, SE(3) otherwise).
// Span: estimates stamped outside [est_from_ns, est_to_ns] (the estimate's clock) are left out before
// association, so two runs can be compared over the stamps both tracked (`rsvio diagnose --against`).
#pragma once
#include <cstdint>
#include <limits>
#include <optional>
#include <string>

#include "rsvio/eval/eval_output.h"
#include "rsvio/eval/trajectory_metrics.h"

namespace rsvio::eval {

struct FileEvalRequest {
  std::string dataset_dir;  // either this (ground truth found in the EuRoC layout) ...
  std::string gt_path;      // ... or this (EuRoC csv or TUM)
  std::string est_path;     // TUM trajectory
  std::string calib_path;   // optional sensor.yaml holding T_BS; default <dataset_dir>/mav0/cam0/sensor.yaml
  std::optional<AlignMode> align;  // nullopt: defaultAlignFor(estimate frame)
  EvalOptions options;             // options.align is overwritten by the resolved alignment
  int64_t est_from_ns = std::numeric_limits<int64_t>::min();  // estimates kept: from <= t_ns <= to
  int64_t est_to_ns = std::numeric_limits<int64_t>::max();
};

struct FileEvalOutcome {
  EvalResult result;
  EvalContext context;
  size_t estimates_in_span = 0;  // poses of the estimate file within [est_from_ns, est_to_ns]
};

// Throws DataError for unreadable files or a dataset without ground truth, Error for impossible
// evaluations (no pairs, degenerate alignment, camera estimate without calibration).
FileEvalOutcome evaluateFiles(const FileEvalRequest& request);

}  // namespace rsvio::eval
