#include "rsvio/imu/imu_buffer.h"

#include <algorithm>
#include <string>

#include "rsvio/core/error.h"

namespace rsvio {

namespace {
std::string stamp(int64_t t_ns) { return std::to_string(t_ns) + " ns"; }
}  // namespace

void ImuBuffer::add(const ImuSample& s) {
  if (!samples_.empty() && s.t_ns <= samples_.back().t_ns)
    throw DataError("IMU sample at " + stamp(s.t_ns) + " does not come after the previous one at " +
                    stamp(samples_.back().t_ns) + " (IMU samples must be strictly increasing in time)");
  if (!s.gyro_rad_s.allFinite() || !s.accel_m_s2.allFinite())
    throw DataError("IMU sample at " + stamp(s.t_ns) + " holds a non-finite value");
  samples_.push_back(s);
}

int64_t ImuBuffer::firstTime() const {
  if (samples_.empty()) throw DataError("IMU buffer is empty");
  return samples_.front().t_ns;
}

int64_t ImuBuffer::lastTime() const {
  if (samples_.empty()) throw DataError("IMU buffer is empty");
  return samples_.back().t_ns;
}

bool ImuBuffer::covers(int64_t t0_ns, int64_t t1_ns) const {
  if (samples_.empty()) return false;
  return t0_ns >= samples_.front().t_ns - max_extrapolation_ns_ && t1_ns <= samples_.back().t_ns + max_extrapolation_ns_;
}

size_t ImuBuffer::upperIndex(int64_t t_ns) const {
  const auto it = std::upper_bound(samples_.begin(), samples_.end(), t_ns,
                                   [](int64_t t, const ImuSample& s) { return t < s.t_ns; });
  return static_cast<size_t>(it - samples_.begin());
}

ImuSample ImuBuffer::interpolate(int64_t t_ns) const {
  if (samples_.empty()) throw DataError("no IMU sample to interpolate at " + stamp(t_ns));
  const size_t hi = upperIndex(t_ns);
  if (hi == 0 || hi == samples_.size()) {
    const ImuSample& end = hi == 0 ? samples_.front() : samples_.back();
    if (hi == samples_.size() && end.t_ns == t_ns) return end;
    const int64_t gap = t_ns > end.t_ns ? t_ns - end.t_ns : end.t_ns - t_ns;
    if (gap > max_extrapolation_ns_)
      throw DataError("no IMU data at " + stamp(t_ns) + ": samples cover [" + stamp(samples_.front().t_ns) + ", " +
                      stamp(samples_.back().t_ns) + "]");
    ImuSample r = end;
    r.t_ns = t_ns;
    return r;
  }
  const ImuSample& a = samples_[hi - 1];
  const ImuSample& b = samples_[hi];
  if (a.t_ns == t_ns) return a;
  const double w = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  ImuSample r;
  r.t_ns = t_ns;
  r.gyro_rad_s = (1.0 - w) * a.gyro_rad_s + w * b.gyro_rad_s;
  r.accel_m_s2 = (1.0 - w) * a.accel_m_s2 + w * b.accel_m_s2;
  return r;
}

std::vector<ImuSample> ImuBuffer::window(int64_t t0_ns, int64_t t1_ns) const {
  if (t1_ns < t0_ns)
    throw Error("IMU window [" + stamp(t0_ns) + ", " + stamp(t1_ns) + "] ends before it starts");
  std::vector<ImuSample> knots;
  knots.push_back(interpolate(t0_ns));
  for (size_t i = upperIndex(t0_ns); i < samples_.size() && samples_[i].t_ns < t1_ns; ++i) knots.push_back(samples_[i]);
  if (t1_ns > t0_ns) knots.push_back(interpolate(t1_ns));
  return knots;
}

void ImuBuffer::dropBefore(int64_t t_ns) {
  const size_t hi = upperIndex(t_ns);
  if (hi <= 1) return;
  samples_.erase(samples_.begin(), samples_.begin() + static_cast<long>(hi - 1));
}

}  // namespace rsvio
