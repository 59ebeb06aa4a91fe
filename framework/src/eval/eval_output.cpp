// JSON, terminal table and CSV of an evaluation (rsvio/eval/eval_output.h).
#include "rsvio/eval/eval_output.h"

#include <cstdio>
#include <fstream>
#include <sstream>

#include "rsvio/core/error.h"
#include "rsvio/core/time.h"

namespace rsvio::eval {
namespace {

nlohmann::json statsJson(const ErrorStats& s, const std::string& unit) {
  return {{"n", s.n},          {"rmse_" + unit, s.rmse}, {"mean_" + unit, s.mean}, {"median_" + unit, s.median},
          {"max_" + unit, s.max}, {"min_" + unit, s.min},   {"std_" + unit, s.std}};
}

std::string stepLabel(const RpeStep& s) {
  char buf[64];
  if (s.kind == RpeStep::Kind::kTime) {
    std::snprintf(buf, sizeof(buf), "%g s", s.value);
  } else if (s.path_fraction > 0) {
    std::snprintf(buf, sizeof(buf), "%.3g m (%g%%)", s.value, 100.0 * s.path_fraction);
  } else {
    std::snprintf(buf, sizeof(buf), "%g m", s.value);
  }
  return buf;
}

std::string alignTitle(AlignMode m) {
  switch (m) {
    case AlignMode::kSE3: return "SE(3)";
    case AlignMode::kSim3: return "Sim(3)";
    default: return "none";
  }
}

}  // namespace

AlignMode defaultAlignFor(io::PoseFrame est_frame) {
  return est_frame == io::PoseFrame::kCamera ? AlignMode::kSim3 : AlignMode::kSE3;
}

nlohmann::json evalToJson(const EvalResult& r, const EvalContext& ctx) {
  using nlohmann::json;
  const auto& as = r.association;
  json j;
  j["ground_truth"] = ctx.gt_path;
  j["estimate"] = ctx.est_path;
  j["estimate_frame"] = ctx.est_frame;
  j["frame_mapping"] = ctx.frame_mapping;
  j["align"] = alignModeName(r.alignment.mode);
  if (!ctx.align_reason.empty()) j["align_reason"] = ctx.align_reason;
  j["ate_rmse_m"] = r.ate_m.rmse;
  j["association"] = {{"rule", "every estimate matched to the nearest ground-truth stamp within max_dt_s"},
                      {"max_dt_s", nsToS(as.max_dt_ns)},
                      {"largest_abs_dt_s", nsToS(as.largest_abs_dt_ns)},
                      {"pairs", as.pairs.size()},
                      {"estimates", as.n_est},
                      {"ground_truth_poses", as.n_gt},
                      {"unmatched_estimates", as.unmatched()}};
  const auto& R = r.alignment.R;
  j["alignment"] = {{"mode", alignModeName(r.alignment.mode)},
                    {"scale", r.alignment.scale},
                    {"rotation", {{R(0, 0), R(0, 1), R(0, 2)}, {R(1, 0), R(1, 1), R(1, 2)}, {R(2, 0), R(2, 1), R(2, 2)}}},
                    {"translation", {r.alignment.t.x(), r.alignment.t.y(), r.alignment.t.z()}}};
  j["ate"] = statsJson(r.ate_m, "m");
  j["ate_rotation"] = statsJson(r.ate_rot_deg, "deg");
  json rpe = json::array();
  for (const auto& e : r.rpe) {
    json x = {{"kind", e.step.kind == RpeStep::Kind::kTime ? "time" : "distance"},
              {"step", e.step.value},
              {"unit", e.step.kind == RpeStep::Kind::kTime ? "s" : "m"},
              {"pairs", e.pairs},
              {"translation", statsJson(e.trans_m, "m")},
              {"rotation", statsJson(e.rot_deg, "deg")}};
    if (e.step.path_fraction > 0) x["path_fraction"] = e.step.path_fraction;
    if (e.step.kind == RpeStep::Kind::kDistance) x["drift_percent_mean"] = e.drift_percent_mean;
    rpe.push_back(x);
  }
  j["rpe"] = rpe;
  j["gt_path_length_m"] = r.gt_path_length_m;
  j["duration_s"] = r.duration_s;
  return j;
}

std::string formatEvalTable(const EvalResult& r, const EvalContext& ctx) {
  std::ostringstream o;
  char buf[256];
  const auto& as = r.association;
  o << "estimate      " << ctx.est_path << " (frame: " << ctx.est_frame << ")\n";
  o << "ground truth  " << ctx.gt_path << "\n";
  o << "frames        " << ctx.frame_mapping << "\n";
  std::snprintf(buf, sizeof(buf),
                "association   %zu pairs of %zu estimates (%zu unmatched): nearest ground-truth stamp within %.4f s, "
                "largest |dt| %.4f s\n",
                as.pairs.size(), as.n_est, as.unmatched(), nsToS(as.max_dt_ns), nsToS(as.largest_abs_dt_ns));
  o << buf;
  std::snprintf(buf, sizeof(buf), "alignment     %s, scale %.6f%s%s\n", alignTitle(r.alignment.mode).c_str(),
                r.alignment.scale, ctx.align_reason.empty() ? "" : " - ", ctx.align_reason.c_str());
  o << buf;
  std::snprintf(buf, sizeof(buf), "path          %.3f m of ground truth over %.2f s\n\n", r.gt_path_length_m, r.duration_s);
  o << buf;
  o << "ATE            rmse        mean      median         max\n";
  std::snprintf(buf, sizeof(buf), "  trans (m) %9.6f   %9.6f   %9.6f   %9.6f\n", r.ate_m.rmse, r.ate_m.mean, r.ate_m.median,
                r.ate_m.max);
  o << buf;
  std::snprintf(buf, sizeof(buf), "  rot (deg) %9.4f   %9.4f   %9.4f   %9.4f\n\n", r.ate_rot_deg.rmse, r.ate_rot_deg.mean,
                r.ate_rot_deg.median, r.ate_rot_deg.max);
  o << buf;
  o << "RPE step             pairs  trans rmse (m)  trans mean (m)  drift (%)  rot rmse (deg)  rot mean (deg)\n";
  for (const auto& e : r.rpe) {
    const std::string drift =
        e.step.kind == RpeStep::Kind::kDistance && e.pairs ? std::to_string(e.drift_percent_mean).substr(0, 6) : "-";
    if (e.pairs == 0) {  // no pair this far apart: nothing measured, not an error of 0
      std::snprintf(buf, sizeof(buf), "  %-18s %5zu  %14s  %14s  %9s  %14s  %14s\n", stepLabel(e.step).c_str(), e.pairs,
                    "-", "-", "-", "-", "-");
      o << buf;
      continue;
    }
    std::snprintf(buf, sizeof(buf), "  %-18s %5zu  %14.6f  %14.6f  %9s  %14.4f  %14.4f\n", stepLabel(e.step).c_str(),
                  e.pairs, e.trans_m.rmse, e.trans_m.mean, drift.c_str(), e.rot_deg.rmse, e.rot_deg.mean);
    o << buf;
  }
  return o.str();
}

void writeErrorOverTimeCsv(const std::string& path, const EvalResult& r) {
  std::ofstream out(path);
  if (!out) throw Error(path + ": cannot open for writing");
  out << "t_s,dt_s,trans_err_m,rot_err_deg,est_x,est_y,est_z,gt_x,gt_y,gt_z\n";
  char buf[320];
  for (const auto& s : r.over_time) {
    std::snprintf(buf, sizeof(buf), "%s,%.9f,%.9f,%.6f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f\n", io::formatSeconds(s.t_ns).c_str(), nsToS(s.dt_ns),
                  s.trans_err_m, s.rot_err_deg, s.p_est_aligned.x(), s.p_est_aligned.y(), s.p_est_aligned.z(),
                  s.p_gt.x(), s.p_gt.y(), s.p_gt.z());
    out << buf;
  }
  if (!out) throw Error(path + ": write failed");
}

}  // namespace rsvio::eval
