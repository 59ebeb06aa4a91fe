// Ray-casting renderer of the simulated camera, with exact per-row poses (rolling shutter) and
// supersampling.
//
// Contract
// - render(t_capture_s) returns the radiance image (CV_32F, raw/distorted geometry, height x width).
//   t_capture_s is the capture time of row y0 on the IMU clock, in seconds from the start. Row r is
//   rendered with the camera pose at t_capture_s + sensor.rowTime(r) (conventions.md, "Time"):
//       T_W_C(t) = T_W_B(t) * T_B_C.
//   Every subsample of a pixel uses its row's time: a pixel's capture time comes from its raw row.
// - Antialiasing: ss x ss subsamples per pixel on a regular grid, each a ray through the raw pixel
//   position, unprojected through the distortion (precomputed once), and a footprint-aware texture
//   filter. With motion blur (sensor.exposure_s > 0) each pixel also averages `blur_samples` times
//   spread evenly over row time +- exposure_s / 2 (stratified with the spatial subsamples).
// - Deterministic: no randomness; rows are independent, so the result is identical for any thread count.
#pragma once
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <vector>

#include "rsvio/sim/lens.h"
#include "rsvio/sim/scene.h"
#include "rsvio/sim/sensor_model.h"
#include "rsvio/sim/trajectory.h"

namespace rsvio::sim {

class Renderer {
 public:
  // Throws ConfigError when a pixel of the image cannot be unprojected (distortion folds over).
  Renderer(const Scene& scene, const SimTrajectory& trajectory, const SimSensorModel& sensor, int supersampling);

  cv::Mat render(double t_capture_s) const;
  // Rows [row_begin, row_end) of the image into `out` (CV_32F, full size), for callers that split rows.
  void renderRows(double t_capture_s, int row_begin, int row_end, cv::Mat& out) const;

  Eigen::Isometry3d T_W_C(double t_s) const;
  // The world point seen at raw pixel uv of the image captured (row y0) at t_capture_s.
  bool castPixel(const Vec2& uv, double t_capture_s, Scene::Hit& hit) const;

 private:
  const Scene& scene_;
  const SimTrajectory& trajectory_;
  const SimSensorModel& sensor_;
  Lens lens_;
  int ss_ = 2;
  int rays_per_pixel_ = 4;
  double ray_angle_ = 1e-3;  // angular spacing of subsample rays, for the texture footprint
  std::vector<Eigen::Vector3f> rays_;  // unit rays in the camera frame, [y][x][sub]
  std::vector<float> xn_;              // x / z of each ray (for culling)
  std::vector<double> row_yn_lo_, row_yn_hi_;  // y / z range of each row's rays

  // A box that may be hit by a row's rays, and the x / z range of its image in the camera.
  struct Candidate {
    int solid;
    float xn_lo, xn_hi;
  };
  void cullRow(const Mat3& R_W_C, const Vec3& o, int row, std::vector<Candidate>& out) const;
};

}  // namespace rsvio::sim
