// A time-ordered store of IMU samples with linear interpolation at arbitrary times.
//
// Contract
// - Samples are on the IMU clock (int64 ns), strictly increasing; add() throws DataError on a sample
//   that goes back in time or repeats a stamp, naming both stamps.
// - interpolate(t) is linear between the two samples around t (exact at a sample). Outside the
//   covered range it throws DataError unless the time lies within `max_extrapolation_ns` of an end,
//   where the end sample is held (zero-order): a camera stamp a few microseconds past the last IMU
//   sample is normal, a gap of several samples is not.
// - window(t0, t1) returns the integration knots of [t0, t1]: the interpolated sample at t0, every
//   stored sample strictly inside, and the interpolated sample at t1 (preintegration.h integrates
//   between consecutive knots). Camera times are converted by the caller: t_imu = t_cam + offset.
#pragma once
#include <cstdint>
#include <deque>
#include <vector>

#include "rsvio/core/types.h"

namespace rsvio {

class ImuBuffer {
 public:
  explicit ImuBuffer(int64_t max_extrapolation_ns = 2'000'000) : max_extrapolation_ns_(max_extrapolation_ns) {}

  void add(const ImuSample& s);
  bool empty() const { return samples_.empty(); }
  size_t size() const { return samples_.size(); }
  int64_t firstTime() const;
  int64_t lastTime() const;
  // True when [t0, t1] lies inside the covered range (with the extrapolation allowance).
  bool covers(int64_t t0_ns, int64_t t1_ns) const;

  ImuSample interpolate(int64_t t_ns) const;
  std::vector<ImuSample> window(int64_t t0_ns, int64_t t1_ns) const;

  // Forgets samples older than t_ns, keeping the last one at or before it (needed to interpolate there).
  void dropBefore(int64_t t_ns);

  const std::deque<ImuSample>& samples() const { return samples_; }

 private:
  size_t upperIndex(int64_t t_ns) const;  // first sample with time > t_ns
  std::deque<ImuSample> samples_;
  int64_t max_extrapolation_ns_;
};

}  // namespace rsvio
