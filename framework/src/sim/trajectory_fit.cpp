// Drawing and fitting the simulated trajectory (rsvio/sim/trajectory.h).
//
// Both bands of a signal group (translation, rotation) are fixed in shape by the random draw; the fit
// only chooses one scale per band. Mean speed and mean acceleration are homogeneous of degree one in
// the two scales (s_slow, s_fast), so their ratio depends only on rho = s_fast / s_slow: a 1-D
// bisection on rho matches the target acceleration/speed ratio, then a common factor matches the speed.
// Rotation is nearly linear in the angle rates; the fit uses the angle rates as a proxy and corrects
// the proxy targets with the exact body-rate statistics a few times.
// When the room is too small for the slow band at the requested speed, the slow frequencies are raised
// (a tighter path, not a faster one) until the path fits; when pitch or roll leave their limits, they
// take a smaller share of the rotation and yaw the rest.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "rsvio/core/error.h"
#include "rsvio/sim/rng.h"
#include "rsvio/sim/trajectory.h"

namespace rsvio::sim {

namespace {
constexpr double kTwoPi = 6.283185307179586;
constexpr double kDeg = M_PI / 180.0;

// Per-sample band vectors at unit scale: rate (velocity or angle rates) and its derivative.
struct BandSamples {
  std::vector<Vec3> rate_slow, rate_fast, acc_slow, acc_fast;
};

double meanNorm(const std::vector<Vec3>& a, const std::vector<Vec3>& b, double s_a, double s_b) {
  double m = 0.0;
  for (size_t k = 0; k < a.size(); ++k) m += (s_a * a[k] + s_b * b[k]).norm();
  return a.empty() ? 0.0 : m / a.size();
}

// Scales (s_slow, s_fast) giving mean |rate| = speed and mean |acc| = accel.
void solveScales(const BandSamples& b, double speed, double accel, double& s_slow, double& s_fast) {
  auto ratio = [&](double rho) {
    const double v = meanNorm(b.rate_slow, b.rate_fast, 1.0, rho);
    return v > 0 ? meanNorm(b.acc_slow, b.acc_fast, 1.0, rho) / v : 0.0;
  };
  const double target = accel / std::max(speed, 1e-12);
  double lo = -12.0, hi = 12.0;  // log(rho)
  double rho;
  if (target <= ratio(std::exp(lo))) {
    rho = 0.0;
  } else if (target >= ratio(std::exp(hi))) {
    rho = -1.0;  // fast band only
  } else {
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      (ratio(std::exp(mid)) < target ? lo : hi) = mid;
    }
    rho = std::exp(0.5 * (lo + hi));
  }
  if (rho < 0) {
    s_slow = 0.0;
    const double v = meanNorm(b.rate_fast, b.rate_fast, 1.0, 0.0);
    s_fast = v > 0 ? speed / v : 0.0;
  } else {
    const double v = meanNorm(b.rate_slow, b.rate_fast, 1.0, rho);
    s_slow = v > 0 ? speed / v : 0.0;
    s_fast = rho * s_slow;
  }
}

std::vector<Wave> drawWaves(std::mt19937_64& rng, int n, double w_lo, double w_hi, double weight) {
  std::vector<Wave> waves(n);
  for (Wave& w : waves) {
    w.w = uniform(rng, w_lo, w_hi);
    w.amp = weight * uniform(rng, 0.5, 1.0);
    w.phase = uniform(rng, 0.0, kTwoPi);
  }
  return waves;
}

void waveDerivs(const std::vector<Wave>& waves, double t, double& df, double& ddf) {
  df = ddf = 0.0;
  for (const Wave& w : waves) {
    const double arg = w.w * t + w.phase;
    df += w.amp * w.w * std::cos(arg);
    ddf -= w.amp * w.w * w.w * std::sin(arg);
  }
}

}  // namespace

class TrajectoryFitter {
 public:
  TrajectoryFitter(SimTrajectory& tr, const MotionSpec& spec) : tr_(tr), spec_(spec) {
    const int n = std::max(8, static_cast<int>(spec.duration_s * 100.0));
    for (int k = 0; k < n; ++k) times_.push_back((k + 0.5) * spec.duration_s / n);
  }

  BandSamples samples(int first_signal) const {
    BandSamples b;
    for (double t : times_) {
      Vec3 rs, rf, as, af;
      for (int j = 0; j < 3; ++j) {
        waveDerivs(tr_.slow_[first_signal + j], t, rs[j], as[j]);
        waveDerivs(tr_.fast_[first_signal + j], t, rf[j], af[j]);
      }
      b.rate_slow.push_back(rs);
      b.rate_fast.push_back(rf);
      b.acc_slow.push_back(as);
      b.acc_fast.push_back(af);
    }
    return b;
  }

  void fitTranslation() {
    solveScales(samples(0), spec_.mean_speed_m_s, spec_.mean_accel_m_s2, tr_.scale_[0], tr_.scale_[1]);
  }

  void fitRotation() {
    const BandSamples b = samples(3);
    double w_target = spec_.mean_rot_speed_deg_s * kDeg, a_target = spec_.mean_rot_accel_deg_s2 * kDeg;
    for (int it = 0; it < 5; ++it) {
      solveScales(b, w_target, a_target, tr_.scale_[2], tr_.scale_[3]);
      double w = 0, a = 0;
      for (double t : times_) {
        const BodyState s = tr_.state(t);
        w += s.omega_B.norm();
        a += s.alpha_B.norm();
      }
      w /= times_.size();
      a /= times_.size();
      if (w <= 0 || a <= 0) break;
      w_target *= spec_.mean_rot_speed_deg_s * kDeg / w;
      a_target *= spec_.mean_rot_accel_deg_s2 * kDeg / a;
    }
  }

  // Sampled at 20 Hz (and the end points): where the path leaves the box, or pitch/roll their limits.
  bool positionInside() const {
    for (double t = 0.0; t <= spec_.duration_s + 1e-9; t += 0.05) {
      const Vec3 p = tr_.state(t).p_W_B;
      if ((p - spec_.box_min).minCoeff() < 0 || (spec_.box_max - p).minCoeff() < 0) return false;
    }
    return true;
  }
  bool attitudeInside() const {
    for (double t = 0.0; t <= spec_.duration_s + 1e-9; t += 0.05) {
      double f, df, ddf;
      tr_.signal(4, t, f, df, ddf);
      if (std::abs(f) > spec_.max_pitch_deg * kDeg) return false;
      tr_.signal(5, t, f, df, ddf);
      if (std::abs(f) > spec_.max_roll_deg * kDeg) return false;
    }
    return true;
  }

  void raiseSlowFrequencies(int first_signal, double factor) {
    for (int j = first_signal; j < first_signal + 3; ++j)
      for (Wave& w : tr_.slow_[j]) w.w *= factor;
  }

  // Pitch and roll take a smaller share of the rotation; yaw (unbounded) makes up the rest.
  void shrinkTilt(double factor) {
    for (int j = 4; j < 6; ++j) {
      for (Wave& w : tr_.slow_[j]) w.amp *= factor;
      for (Wave& w : tr_.fast_[j]) w.amp *= factor;
    }
  }

 private:
  SimTrajectory& tr_;
  const MotionSpec& spec_;
  std::vector<double> times_;
};

SimTrajectory SimTrajectory::generate(const MotionSpec& spec, std::mt19937_64& rng) {
  if (!(spec.duration_s > 0)) throw ConfigError("motion.duration_s: must be positive");
  if ((spec.box_max - spec.box_min).minCoeff() <= 0)
    throw ConfigError("scene.room_size_m: the room leaves no space for the camera path (see motion.wall_clearance_m)");
  SimTrajectory tr;
  tr.duration_s_ = spec.duration_s;
  const Vec3 centre = 0.5 * (spec.box_min + spec.box_max);
  const Vec3 half = 0.5 * (spec.box_max - spec.box_min);
  for (int j = 0; j < 3; ++j) tr.base_[j] = centre[j];
  // Every draw happens in a fixed order whatever the spec, so the stream's use never shifts.
  tr.base_[3] = uniform(rng, 0.0, kTwoPi);
  tr.base_[4] = -std::min(6.0, spec.max_pitch_deg / 3.0) * kDeg;  // look slightly down
  tr.base_[5] = 0.0;
  const double pos_w[3] = {half.x(), half.y(), half.z()};
  const double fast_pos_w[3] = {1.0, 1.0, 0.7};
  for (int j = 0; j < 3; ++j) {
    tr.slow_[j] = drawWaves(rng, 3, 0.25, 0.6, pos_w[j]);
    tr.fast_[j] = drawWaves(rng, 4, 3.5, 9.0, fast_pos_w[j]);
  }
  const double rot_slow_w[3] = {1.0, 0.3, 0.12};
  const double rot_fast_w[3] = {1.0, 0.8, 0.5};
  for (int j = 0; j < 3; ++j) {
    tr.slow_[3 + j] = drawWaves(rng, 3, 0.25, 0.6, rot_slow_w[j]);
    tr.fast_[3 + j] = drawWaves(rng, 4, 4.0, 10.0, rot_fast_w[j]);
  }

  TrajectoryFitter fit(tr, spec);
  bool ok = false;
  for (int it = 0; it < 40 && !ok; ++it) {
    fit.fitTranslation();
    ok = fit.positionInside();
    if (!ok) fit.raiseSlowFrequencies(0, 1.1);
  }
  if (!ok) {
    std::ostringstream msg;
    msg << "motion.mean_speed_m_s: " << spec.mean_speed_m_s
        << " m/s cannot be reached inside the room; lower it or enlarge scene.room_size_m";
    throw ConfigError(msg.str());
  }
  ok = false;
  for (int it = 0; it < 40 && !ok; ++it) {
    fit.fitRotation();
    ok = fit.attitudeInside();
    if (!ok) fit.shrinkTilt(0.85);
  }
  if (!ok) {
    std::ostringstream msg;
    msg << "motion.mean_rot_speed_deg_s: " << spec.mean_rot_speed_deg_s
        << " deg/s cannot be reached within motion.max_pitch_deg / max_roll_deg; lower it or raise the limits";
    throw ConfigError(msg.str());
  }
  // The bands can only mix two frequency ranges: a target outside what they reach (or a room too small
  // for it) leaves a statistic off. Say which, instead of writing a sequence that is not what was asked.
  const MotionStats st = tr.stats(100.0);
  const struct {
    const char* key;
    double asked, got;
  } checks[] = {{"mean_speed_m_s", spec.mean_speed_m_s, st.mean_speed_m_s},
                {"mean_accel_m_s2", spec.mean_accel_m_s2, st.mean_accel_m_s2},
                {"mean_rot_speed_deg_s", spec.mean_rot_speed_deg_s, st.mean_rot_speed_deg_s},
                {"mean_rot_accel_deg_s2", spec.mean_rot_accel_deg_s2, st.mean_rot_accel_deg_s2}};
  for (const auto& c : checks) {
    if (std::abs(c.got - c.asked) > 0.1 * c.asked) {
      std::ostringstream msg;
      msg << "motion." << c.key << ": asked " << c.asked << ", the closest path that fits the room and the other "
          << "targets reaches " << c.got << "; make the speed and acceleration targets more compatible "
          << "(acceleration / speed between about 0.3 and 6 per second)";
      throw ConfigError(msg.str());
    }
  }
  return tr;
}

}  // namespace rsvio::sim
