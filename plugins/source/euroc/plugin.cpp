// Registration of source.euroc and its parameter table.
#include <memory>

#include "euroc_source.h"
#include "rsvio/plugin/plugin_api.h"

namespace rsvio::euroc {

ParamTable eurocSourceParams() {
  return {
      paramString("camera", "cam0", "camera folder under mav0/ (TUM RS-VIO: cam0 global shutter, cam1 rolling shutter)"),
      paramEnum("timestamp_row", "middle", {"middle", "first", "last"},
                "raw row the dataset's image stamps refer to, in readout order; converted to the middle row"),
      paramDouble("line_delay_us", 0.0, 0.0, 1000.0, "us",
                  "line delay for the timestamp conversion; 0 = the calibration's"),
      paramEnum("calibration", "auto", {"auto", "euroc", "kalibr"},
                "geometric calibration: Kalibr camchain if found, else mav0/<camera>/sensor.yaml"),
      paramString("calibration_file", "", "calibration file (relative to the dataset folder or absolute); \"\" = search"),
      paramString("imu_calibration_file", "", "IMU noise yaml (EuRoC or Kalibr); \"\" = search"),
      paramDouble("max_imu_gap_ms", 50.0, 0.1, 10000.0, "ms",
                  "larger gaps between IMU samples inside the camera's time span are fatal"),
      paramDouble("image_scale", 1.0, 0.1, 1.0, "",
                  "resize images by this factor (intrinsics and line delay follow)"),
      paramEnum("photometric", "auto", {"auto", "none"},
                "read DSO photometric calibration (pcalib.txt, vignette.png, times.txt) when present"),
  };
}

EurocSourceOptions EurocSourceOptions::fromParams(const Params& p) {
  EurocSourceOptions o;
  o.camera = p.getString("camera");
  o.timestamp_row = p.getString("timestamp_row");
  o.line_delay_us = p.getDouble("line_delay_us");
  o.calibration = p.getString("calibration");
  o.calibration_file = p.getString("calibration_file");
  o.imu_calibration_file = p.getString("imu_calibration_file");
  o.max_imu_gap_ms = p.getDouble("max_imu_gap_ms");
  o.image_scale = p.getDouble("image_scale");
  o.photometric = p.getString("photometric");
  return o;
}

}  // namespace rsvio::euroc

namespace {

void registerAll(rsvio::PluginRegistrar& r) {
  r.add<rsvio::DataSource>(
      {"source.euroc", rsvio::PluginKind::Source, "1.0.0",
       "EuRoC/ASL layout reader: EuRoC, TUM-VI, TUM RS-VIO, rsvio simulator; EuRoC/Kalibr/DSO calibration",
       rsvio::euroc::eurocSourceParams()},
      [](const rsvio::Params& p) {
        return std::make_unique<rsvio::euroc::EurocSource>(rsvio::euroc::EurocSourceOptions::fromParams(p));
      });
}

}  // namespace

RSVIO_PLUGIN_ENTRY(registerAll)
