// Output of a trajectory evaluation: JSON (eval.json, `rsvio eval --json`), the terminal table and
// error_over_time.csv. The JSON's top-level "ate_rmse_m" and "align" are the fields report.json's
// "eval" object carries (user-contract.md), so a run can embed this object as is.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "rsvio/eval/trajectory_metrics.h"

namespace rsvio::eval {

// Where the compared trajectories came from and how their frames were reconciled (for the record).
struct EvalContext {
  std::string gt_path;
  std::string est_path;
  std::string est_frame = "unknown";  // from the estimate's header
  std::string frame_mapping = "none";  // e.g. "ground truth body poses mapped to camera through T_BS of <file>"
  std::string align_reason;            // why this alignment, e.g. "default for '# frame: camera'"
};

nlohmann::json evalToJson(const EvalResult& r, const EvalContext& ctx);
std::string formatEvalTable(const EvalResult& r, const EvalContext& ctx);
// Columns: t_s, dt_s, trans_err_m, rot_err_deg, est_x, est_y, est_z (aligned), gt_x, gt_y, gt_z.
void writeErrorOverTimeCsv(const std::string& path, const EvalResult& r);

// The alignment used when none is asked for: Sim(3) for camera poses (monocular VO has no metric scale),
// SE(3) otherwise (metric VIO body poses, as the paper's eq. 35).
AlignMode defaultAlignFor(io::PoseFrame est_frame);

}  // namespace rsvio::eval
