// Interface of source.* plugins: datasets in the EuRoC/ASL layout (EuRoC, TUM-VI, TUM RS-VIO, rsvio's
// simulator) and others.
//
// Contract
// - open(dir) reads and checks the index files and calibration (never ground truth: the estimator
//   must not see it; evaluation reads it separately). Bad input throws DataError "file:line: ..." for
//   fatal problems; recoverable ones (e.g. a duplicate IMU sample dropped) become warnings().
// - Timestamps are converted so that a frame's t_ns is the capture time of raw row y0 = (h-1)/2
//   (a param says which row the dataset stamps); IMU samples are on the IMU clock.
// - Images are read on demand in readFrame(i) (streaming, bounded memory), raw: no undistortion, no
//   photometric correction. A missing/unreadable image throws DataError naming frame, time and path.
#pragma once
#include <string>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

class DataSource : public PluginBase {
 public:
  static constexpr PluginKind kKind = PluginKind::Source;

  virtual void open(const std::string& dir) = 0;
  virtual const SensorSetup& sensors() const = 0;
  virtual size_t numFrames() const = 0;
  virtual int64_t frameTime(size_t i) const = 0;
  virtual Frame readFrame(size_t i) const = 0;
  virtual const std::vector<ImuSample>& imu() const = 0;
  virtual std::vector<std::string> warnings() const { return {}; }
};

}  // namespace rsvio
