// source.euroc: datasets in the EuRoC/ASL layout - EuRoC, TUM-VI, the TUM rolling-shutter VIO dataset
// and rsvio's simulator - one camera chosen by name. Interface contract: rsvio/interfaces/data_source.h.
//
// Layout read (dir = the sequence folder holding mav0/, or mav0/ itself):
//   mav0/<camera>/data.csv + data/<file>   image index and images (8-/16-bit PNG or JPEG, rsvio/io/image_file.h;
//                                          colour converted to grey; read on demand)
//   mav0/imu0/data.csv                     IMU samples (optional: without it has_imu = false)
//   calibration, first found unless params.calibration_file names one:
//     Kalibr camchain: dso/camchain.yaml, camchain*.yaml, dso/*camchain*.yaml
//     EuRoC:           mav0/<camera>/sensor.yaml
//   IMU noise: mav0/imu0/sensor.yaml, dso/imu_config.yaml, imu_config.yaml / imu.yaml beside the camchain
//   photometric (DSO style, optional): dso/<camera>/ or mav0/<camera>/ {pcalib.txt, vignette.png, times.txt}
// Ground truth (state_groundtruth_estimate0, mocap0, dso/gt_imu.csv) is never read here.
//
// Time: frameTime(i) is the capture time of raw row y0 = (h-1)/2. A dataset stamping the first (last)
// row read out is converted with t_mid = t_stamp + y0 * line_delay (t_stamp - y0 * line_delay), whatever
// the readout direction. The line delay is params.line_delay_us when > 0, else the calibration's.
// Resizing (image_scale) keeps frame times: the line delay per working-image row becomes
// line_delay / scale_y, and intrinsics follow pixel centres at integer coordinates.
#pragma once
#include <string>
#include <vector>

#include "rsvio/interfaces/data_source.h"

namespace rsvio::euroc {

struct EurocSourceOptions {
  std::string camera = "cam0";
  std::string timestamp_row = "middle";  // middle | first | last (in readout order)
  double line_delay_us = 0.0;            // 0: from the calibration
  std::string calibration = "auto";      // auto | euroc | kalibr
  std::string calibration_file;          // relative to the dataset folder, or absolute
  std::string imu_calibration_file;
  double max_imu_gap_ms = 50.0;
  double image_scale = 1.0;
  std::string photometric = "auto";      // auto | none

  static EurocSourceOptions fromParams(const Params& p);
};

// The parameter table of source.euroc (drives validation, `rsvio plugins` and the README).
ParamTable eurocSourceParams();

class EurocSource : public DataSource {
 public:
  explicit EurocSource(EurocSourceOptions options) : opt_(std::move(options)) {}

  void open(const std::string& dir) override;
  const SensorSetup& sensors() const override { return sensors_; }
  size_t numFrames() const override { return frames_.size(); }
  int64_t frameTime(size_t i) const override;
  Frame readFrame(size_t i) const override;
  const std::vector<ImuSample>& imu() const override;      // read on first call (diagnose, tests)
  std::unique_ptr<ImuReader> imuReader() const override;  // streamed from data.csv (runs)
  std::vector<std::string> warnings() const override { return warnings_; }

 private:
  struct FrameEntry {
    int64_t t_ns = 0;      // middle-row time
    int64_t stamp_ns = 0;  // as in data.csv
    std::string path;      // image file
    long line = 0;         // line in data.csv
    double exposure_ms = std::numeric_limits<double>::quiet_NaN();
  };

  void resolveFolders(const std::string& dir);
  void readCalibration();
  void readFrames();
  void convertTimestamps();
  void readImu();
  void readPhotometric();
  void applyScale();
  cv::Mat loadRaw(size_t i) const;  // decoded, checked against the raw calibration size
  std::string frameLabel(size_t i) const;

  EurocSourceOptions opt_;
  SensorSetup sensors_;
  std::vector<FrameEntry> frames_;
  std::string imu_csv_;                       // imu0/data.csv when has_imu (checked whole by open())
  size_t imu_count_ = 0;                      // samples kept by open()'s pass
  mutable std::vector<ImuSample> imu_;        // imu()'s copy, read on its first call
  mutable bool imu_loaded_ = false;
  std::vector<std::string> warnings_;

  std::string dir_, mav0_, cam_dir_, index_path_;
  std::string calib_path_, calib_format_;  // what the geometry came from
  bool rate_known_ = false;
  int raw_width_ = 0, raw_height_ = 0;     // the calibration's (raw image) size
  double raw_line_delay_s_ = 0.0;          // line delay used for conversion, per raw row
};

}  // namespace rsvio::euroc
