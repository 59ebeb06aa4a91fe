// Ideal IMU samples and ground truth from the trajectory (rsvio/sim/imu_synth.h).
#include "rsvio/sim/imu_synth.h"

#include <cmath>

namespace rsvio::sim {

std::vector<int64_t> streamStamps(int64_t start_ns, double duration_s, double rate_hz) {
  std::vector<int64_t> stamps;
  const int64_t n = static_cast<int64_t>(std::floor(duration_s * rate_hz + 1e-9));
  stamps.reserve(n + 1);
  for (int64_t k = 0; k <= n; ++k) stamps.push_back(start_ns + std::llround(static_cast<double>(k) * 1e9 / rate_hz));
  return stamps;
}

ImuSample idealImuAt(const SimTrajectory& trajectory, double t_s) {
  const BodyState s = trajectory.state(t_s);
  ImuSample m;
  m.gyro_rad_s = s.omega_B;
  m.accel_m_s2 = s.q_W_B.conjugate() * (s.a_W - Vec3(0.0, 0.0, -kGravity));
  return m;
}

std::vector<ImuSample> idealImu(const SimTrajectory& trajectory, const std::vector<int64_t>& stamps,
                                int64_t start_ns) {
  std::vector<ImuSample> out;
  out.reserve(stamps.size());
  for (int64_t t_ns : stamps) {
    ImuSample m = idealImuAt(trajectory, static_cast<double>(t_ns - start_ns) * 1e-9);
    m.t_ns = t_ns;
    out.push_back(m);
  }
  return out;
}

std::vector<GroundTruthState> groundTruth(const SimTrajectory& trajectory, const std::vector<int64_t>& stamps,
                                          int64_t start_ns) {
  std::vector<GroundTruthState> out;
  out.reserve(stamps.size());
  for (int64_t t_ns : stamps) {
    const BodyState s = trajectory.state(static_cast<double>(t_ns - start_ns) * 1e-9);
    GroundTruthState g;
    g.t_ns = t_ns;
    g.p_W_B = s.p_W_B;
    g.q_W_B = s.q_W_B;
    g.v_W = s.v_W;
    out.push_back(g);
  }
  return out;
}

}  // namespace rsvio::sim
