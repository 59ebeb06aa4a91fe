// probe.time_offset: does the run miss a camera-IMU time offset?
//
// Physics: the gyroscope measures the body's angular velocity on the IMU clock; the run's trajectory
// gives the same angular velocity from vision on the camera clock (trajectory.tum: every tracked frame).
// When the IMU clock runs d ahead of what the run assumed (t_imu = t_cam + offset, Kalibr's sign,
// conventions.md), the gyro reading that belongs to a frame interval [a, b] is the one over
// [a + d, b + d]. Per pair of consecutive frames and per axis, with G(a, b) the mean gyro reading over
// [a, b] (IMU clock as the run assumed it) and w_vis = log(R_a^T R_b) / (b - a) (body frame):
//     r = w_vis - G(a, b) ~ d x - b_g,    x = dG/dd = (g(b) - g(a)) / (b - a)
// (g the interpolated gyro reading): the residual against the angular acceleration. b_g, the gyro bias,
// is one constant per axis (it random-walks by ~1e-4 rad/s over a minute on a MEMS IMU). The statistic
// is the score test of d = 0 with a cluster-robust standard error, frame pairs grouped in blocks of
// `block_s` (a pose error enters two neighbouring pairs with opposite signs): |z| = |d_hat| / se, and
// the fraction of the misfit energy the fitted shift explains (a poor visual rotation misfits the gyro
// at every shift); statistic = min(|z| / threshold, explained / min_explained), named above 1.
//
// Rotation rates do not depend on the scale, so this works on the trajectory of a run that never
// initialised (camera frame, camera clock: the calibration's offset and R_B_C are applied) as on a
// visual-inertial one (body frame, IMU clock).
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>
#include <set>
#include <sstream>

#include "../common/probe_common.h"
#include "rsvio/imu/inertial_options.h"
#include "rsvio/io/trajectory.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio {
namespace {

const char* kName = "probe.time_offset";
const char* kPlugin = "imu.estimate_time_offset";
const char* kLine = "--set imu.estimate_time_offset=true";

bool imuEnabled(const nlohmann::json& cfg) {
  return cfg.contains("imu") && cfg["imu"].is_object() && cfg["imu"].value("enabled", false);
}

// The gyro reading at t (linear interpolation) and its mean over [a, b] (trapezoids on the samples).
class GyroSignal {
 public:
  explicit GyroSignal(const std::vector<ImuSample>& s) : s_(s) {}
  bool covers(double a, double b) const {
    return !s_.empty() && a >= sec(s_.front().t_ns) && b <= sec(s_.back().t_ns);
  }
  Eigen::Vector3d at(double t) const {
    const size_t i = upper(t);
    if (i == 0) return s_.front().gyro_rad_s;
    if (i >= s_.size()) return s_.back().gyro_rad_s;
    const double t0 = sec(s_[i - 1].t_ns), t1 = sec(s_[i].t_ns);
    const double u = t1 > t0 ? (t - t0) / (t1 - t0) : 0.0;
    return (1.0 - u) * s_[i - 1].gyro_rad_s + u * s_[i].gyro_rad_s;
  }
  Eigen::Vector3d mean(double a, double b) const {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double t = a;
    Eigen::Vector3d g = at(a);
    for (size_t i = upper(a); i < s_.size() && sec(s_[i].t_ns) < b; ++i) {
      const double ti = sec(s_[i].t_ns);
      sum += 0.5 * (g + s_[i].gyro_rad_s) * (ti - t);
      t = ti;
      g = s_[i].gyro_rad_s;
    }
    const Eigen::Vector3d gb = at(b);
    sum += 0.5 * (g + gb) * (b - t);
    return sum / (b - a);
  }

 private:
  static double sec(int64_t ns) { return 1e-9 * static_cast<double>(ns); }
  size_t upper(double t) const {  // first sample after t
    const int64_t ns = static_cast<int64_t>(std::floor(t * 1e9));
    return static_cast<size_t>(std::upper_bound(s_.begin(), s_.end(), ns,
                                                [](int64_t v, const ImuSample& x) { return v < x.t_ns; }) -
                               s_.begin());
  }
  const std::vector<ImuSample>& s_;
};

struct PairRow {
  double a = 0, b = 0;      // interval on the IMU clock as the run assumed it [s]
  Eigen::Vector3d w_vis;    // visual angular velocity, body frame [rad/s]
  int block = 0;
};

class TimeOffsetProbe : public DiagnosticProbe {
 public:
  explicit TimeOffsetProbe(const Params& p)
      : threshold_(p.getDouble("threshold")), min_explained_(p.getDouble("min_explained")), block_s_(p.getDouble("block_s")),
        max_gap_(p.getDouble("max_gap_frames")), curve_ms_(p.getDouble("curve_range_ms")),
        min_blocks_(static_cast<int>(p.getInt("min_blocks"))) {}
  std::string effect() const override { return "time_offset"; }

  ProbeResult evaluate(const ProbeInput& in) const override {
    const nlohmann::json& cfg = in.config;
    if (!imuEnabled(cfg))
      return probe::notApplicable(effect(), kPlugin,
                                  "the run does not use the IMU (imu.enabled false): a camera-IMU time offset "
                                  "does not enter its model");
    if (cfg["imu"].value("estimate_time_offset", false))
      return probe::notApplicable(effect(), kPlugin, "the run estimates the time offset (imu.estimate_time_offset)");
    if (!in.trajectory || !in.imu || !in.sensors || in.imu->size() < 2 || in.trajectory->size() < 3) {
      ProbeResult r = probe::tooLittleData(effect(), kPlugin, 0, 1.0);
      r.explanation = std::string("too little data (") +
                      (!in.trajectory ? "no trajectory.tum in the run folder"
                                      : (!in.imu || in.imu->size() < 2 ? "the run's dataset or its IMU samples are not readable"
                                                                       : "fewer than 3 tracked frames")) +
                      ")";
      return r;
    }
    const io::Trajectory& tr = *in.trajectory;
    const bool camera = tr.frame != io::PoseFrame::kBody;
    // What the run assumed: the calibration's offset plus imu.time_offset_correction_ms of the run's own
    // config. A camera-frame trajectory is on the camera clock: to the IMU clock with that offset, and
    // R_W_B = R_W_C R_C_B. (A body-frame one is on the IMU clock with the run's final offset.)
    const InertialOptions own = inertialOptionsFromConfig(in.run_config ? *in.run_config : cfg);
    const double correction_ms = own.time_offset_correction_ms;
    const double assumed = own.assumedTimeOffsetS(in.sensors->camera);
    const double clock_shift = camera ? assumed : 0.0;
    const Eigen::Quaterniond q_c_b(in.sensors->camera.T_B_C.rotation().transpose());
    const GyroSignal gyro(*in.imu);

    std::vector<double> dts;
    for (size_t k = 1; k < tr.size(); ++k) dts.push_back(1e-9 * static_cast<double>(tr.poses[k].t_ns - tr.poses[k - 1].t_ns));
    std::vector<double> sorted = dts;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double dt_med = sorted[sorted.size() / 2];
    const double margin = curve_ms_ * 1e-3 + 1e-3;
    std::vector<PairRow> rows;
    const double t_first = 1e-9 * static_cast<double>(tr.poses.front().t_ns);
    for (size_t k = 1; k < tr.size(); ++k) {
      const double dt = dts[k - 1];
      if (!(dt > 0) || dt > max_gap_ * dt_med) continue;  // a gap (lost frames) is not one interval
      PairRow p;
      p.a = 1e-9 * static_cast<double>(tr.poses[k - 1].t_ns) + clock_shift;
      p.b = 1e-9 * static_cast<double>(tr.poses[k].t_ns) + clock_shift;
      if (!gyro.covers(p.a - margin, p.b + margin)) continue;
      Eigen::Quaterniond qa = tr.poses[k - 1].q_W_X, qb = tr.poses[k].q_W_X;
      if (camera) qa = qa * q_c_b, qb = qb * q_c_b;
      const Eigen::AngleAxisd aa(qa.conjugate() * qb);
      p.w_vis = aa.angle() * aa.axis() / dt;
      if (!p.w_vis.allFinite()) continue;
      p.block = static_cast<int>(std::floor((p.a - t_first) / block_s_));
      rows.push_back(p);
    }
    if (rows.size() < 20) {
      ProbeResult r = probe::tooLittleData(effect(), kPlugin, rows.size(), 1.0);
      r.explanation = "too little data (" + std::to_string(rows.size()) +
                      " frame pairs with IMU data around them; at least 20 are needed)";
      return r;
    }
    // The robust standard error below is formed from one score sum per block: with G blocks it has
    // G - 1 degrees of freedom, and on 3 blocks (1.5 s) |z| 6.9 is p ~ 0.02 (t with 2 dof), not a test.
    // Measured: gs_vio's first second on rolling-shutter images (lost at frame 29, 3 blocks) gave |z|
    // 6.9 for a 13.6 ms offset that is not there (docs/diagnose.md, "Rolling shutter from
    // configs/default.json").
    std::set<int> blocks;
    for (const PairRow& p : rows) blocks.insert(p.block);
    if (static_cast<int>(blocks.size()) < min_blocks_) {
      ProbeResult r = probe::tooLittleData(effect(), kPlugin, rows.size(), 1.0);
      std::ostringstream ex;
      ex << "too little data (" << blocks.size() << " blocks of " << block_s_ << " s with frame pairs; at least "
         << min_blocks_ << " are needed for the robust standard error)";
      r.explanation = ex.str();
      return r;
    }
    // Residual and regressor at shift d, with the per-axis constant (bias) removed.
    auto residuals = [&](double d, std::vector<Eigen::Vector3d>* r, std::vector<Eigen::Vector3d>* x) {
      r->resize(rows.size());
      if (x) x->resize(rows.size());
      Eigen::Vector3d mr = Eigen::Vector3d::Zero(), mx = Eigen::Vector3d::Zero();
      for (size_t i = 0; i < rows.size(); ++i) {
        const PairRow& p = rows[i];
        (*r)[i] = p.w_vis - gyro.mean(p.a + d, p.b + d);
        mr += (*r)[i];
        if (x) {
          (*x)[i] = (gyro.at(p.b + d) - gyro.at(p.a + d)) / (p.b - p.a);
          mx += (*x)[i];
        }
      }
      mr /= static_cast<double>(rows.size());
      mx /= static_cast<double>(rows.size());
      for (size_t i = 0; i < rows.size(); ++i) {
        (*r)[i] -= mr;
        if (x) (*x)[i] -= mx;
      }
      return mr;  // the bias estimate (negated)
    };
    std::vector<Eigen::Vector3d> r, x;
    const Eigen::Vector3d bias = -residuals(0.0, &r, &x);
    // Score test: d_hat = sum x.r / sum x.x, cluster-robust se over blocks.
    double sxx = 0, sxr = 0;
    for (size_t i = 0; i < rows.size(); ++i) sxx += x[i].squaredNorm(), sxr += x[i].dot(r[i]);
    const double d_hat = sxx > 0 ? sxr / sxx : 0.0;
    std::map<int, double> block_score;
    for (size_t i = 0; i < rows.size(); ++i) block_score[rows[i].block] += x[i].dot(r[i] - d_hat * x[i]);
    double v = 0;
    for (const auto& [b, s] : block_score) v += s * s;
    const double se = sxx > 0 ? std::sqrt(v) / sxx : 0.0;
    const double z = se > 0 ? d_hat / se : 0.0;
    // How much of the misfit a shift explains: a clock offset explains most of it, a poor visual
    // rotation (tracking that lags or jitters) misfits the gyro at every shift.
    double srr = 0;
    for (const auto& ri : r) srr += ri.squaredNorm();
    const double explained = srr > 0 ? std::clamp(d_hat * d_hat * sxx / srr, 0.0, 1.0) : 0.0;

    // The evidence curve: RMS rotation-rate residual against a shift of the IMU in time.
    std::vector<double> cx, cy;
    double best_d = 0, best_e = INFINITY;
    const int steps = 40;
    for (int s = -steps; s <= steps; ++s) {
      const double d = curve_ms_ * 1e-3 * s / steps;
      std::vector<Eigen::Vector3d> rs;
      residuals(d, &rs, nullptr);
      double e = 0;
      for (const auto& ri : rs) e += ri.squaredNorm();
      e = std::sqrt(e / (3.0 * static_cast<double>(rs.size())));
      cx.push_back(1e3 * d);
      cy.push_back(e * 180.0 / M_PI);
      if (e < best_e) best_e = e, best_d = d;
    }

    ProbeResult res;
    res.effect = effect();
    res.plugin = kPlugin;
    // Both conditions, each against its own threshold: statistic = min(|z| / z_threshold,
    // explained / min_explained), named above 1.
    res.statistic = std::min(std::abs(z) / threshold_, min_explained_ > 0 ? explained / min_explained_ : INFINITY);
    res.threshold = 1.0;
    // The correction to start from: what the run assumed beyond the calibration plus the estimate.
    std::ostringstream line;
    line << "--set imu.time_offset_correction_ms=" << std::round(10.0 * (correction_ms + 1e3 * d_hat)) / 10.0 << " "
         << kLine;
    res.config_line = line.str();
    std::ostringstream ex;
    ex.precision(3);
    ex << "gyro against the trajectory's rotation rate over " << rows.size()
       << " frame pairs: the IMU clock is off by " << 1e3 * d_hat << " ms (se " << 1e3 * se
       << " ms, |z| " << std::abs(z) << "; a shift explains " << 100.0 * explained
       << " % of the misfit, the residual is smallest at " << 1e3 * best_d << " ms)";
    res.explanation = ex.str();
    res.details = {{"offset_estimate_ms", 1e3 * d_hat},
                   {"se_ms", 1e3 * se},
                   {"z", z},
                   {"z_threshold", threshold_},
                   {"explained_fraction", explained},
                   {"min_explained", min_explained_},
                   {"rms_misfit_deg_s", std::sqrt(srr / (3.0 * static_cast<double>(r.size()))) * 180.0 / M_PI},
                   {"curve_minimum_ms", 1e3 * best_d},
                   {"assumed_offset_ms", 1e3 * assumed},
                   {"frame_pairs", rows.size()},
                   {"blocks", block_score.size()},
                   {"gyro_bias_rad_s", {bias.x(), bias.y(), bias.z()}},
                   {"trajectory_frame", io::poseFrameName(tr.frame)}};
    res.details["curve"] = {{"x", cx},
                            {"y", cy},
                            {"y_name", "RMS of vision minus gyro"},
                            {"x_label", "IMU shifted by [ms] (t_imu = t_cam + offset + shift)"},
                            {"y_label", "rotation-rate residual, RMS per axis [deg/s]"}};
    probe::finish(res);
    return res;
  }

 private:
  double threshold_, min_explained_, block_s_, max_gap_, curve_ms_;
  int min_blocks_;
};

ParamTable table() {
  return {paramDouble("threshold", 6.0, 0.0, 1e6, "", "|z| above which the effect can be named"),
          paramDouble("min_explained", 0.25, 0.0, 1.0, "",
                      "fraction of the rotation-rate misfit a shift must explain for the effect to be named"),
          paramDouble("block_s", 0.5, 0.05, 60.0, "s", "frame pairs are grouped in blocks this long for the robust standard error"),
          paramDouble("max_gap_frames", 1.5, 1.0, 100.0, "",
                      "a pair of tracked frames further apart than this many median frame periods is skipped"),
          paramDouble("curve_range_ms", 40.0, 1.0, 1000.0, "ms", "the evidence curve covers shifts of +- this much"),
          paramInt("min_blocks", 4, 2, 1000, "",
                   "fewer blocks with frame pairs: too little data (the robust standard error has blocks - 1 degrees "
                   "of freedom)")};
}

void registerAll(PluginRegistrar& r) {
  r.add<DiagnosticProbe>({kName, PluginKind::Probe, "1.0.0",
                          "Camera-IMU time offset: gyro against the trajectory's rotation rate (residual against "
                          "a shift of the IMU in time)",
                          table(), ""},
                         [](const Params& p) { return std::make_unique<TimeOffsetProbe>(p); });
}

}  // namespace
}  // namespace rsvio

RSVIO_PLUGIN_ENTRY(rsvio::registerAll)
