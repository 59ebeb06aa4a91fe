// Time in rsvio (../shared/guides/conventions.md, "Time"):
// - Timestamps are int64_t nanoseconds everywhere inside (`t_ns`); seconds only at file edges
//   (TUM trajectories, 9 decimals) and as durations in double (`dt_s`).
// - An image's timestamp is the capture time of its middle row y0 = (h - 1) / 2 of the raw image.
// - Camera-IMU time offset follows Kalibr: t_imu = t_cam + time_offset.
#pragma once
#include <cmath>
#include <cstdint>

namespace rsvio {

using Timestamp = int64_t;  // nanoseconds

constexpr double kNsToS = 1e-9;
constexpr double kSToNs = 1e9;

inline double nsToS(int64_t t_ns) { return static_cast<double>(t_ns) * kNsToS; }
inline int64_t sToNs(double t_s) { return static_cast<int64_t>(std::llround(t_s * kSToNs)); }

}  // namespace rsvio
