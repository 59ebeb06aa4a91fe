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
// - IMU samples (increasing t_ns, IMU clock) are streamed too: imuReader() gives a reader from the first
//   sample on that holds only what it is reading, so a run's memory does not grow with the sequence
//   (issue 16: a 10-minute recording at 200 Hz is 120 000 samples). open() has checked the whole stream
//   already (its errors and warnings are open()'s); a file changed since then may still throw DataError
//   from next(). imu() is the whole stream in memory, read on its first call, for consumers that need
//   all of it at once (diagnose's probes, tests); a source may override either.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

// Reads IMU samples in time order, one at a time.
class ImuReader {
 public:
  virtual ~ImuReader() = default;
  virtual bool next(ImuSample& sample) = 0;  // false at the end of the stream
};

class DataSource : public PluginBase {
 public:
  static constexpr PluginKind kKind = PluginKind::Source;

  virtual void open(const std::string& dir) = 0;
  virtual const SensorSetup& sensors() const = 0;
  virtual size_t numFrames() const = 0;
  virtual int64_t frameTime(size_t i) const = 0;
  virtual Frame readFrame(size_t i) const = 0;
  virtual const std::vector<ImuSample>& imu() const = 0;
  virtual std::unique_ptr<ImuReader> imuReader() const {
    // Default: over imu() (for a source that holds its samples anyway).
    struct Over : ImuReader {
      const std::vector<ImuSample>& v;
      size_t i = 0;
      explicit Over(const std::vector<ImuSample>& s) : v(s) {}
      bool next(ImuSample& s) override {
        if (i >= v.size()) return false;
        s = v[i++];
        return true;
      }
    };
    return std::make_unique<Over>(imu());
  }
  virtual std::vector<std::string> warnings() const { return {}; }
};

}  // namespace rsvio
