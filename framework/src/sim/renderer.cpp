// Ray casting with per-row poses (rsvio/sim/renderer.h).
#include "rsvio/sim/renderer.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "rsvio/core/error.h"

namespace rsvio::sim {

Renderer::Renderer(const Scene& scene, const SimTrajectory& trajectory, const SimSensorModel& sensor,
                   int supersampling)
    : scene_(scene), trajectory_(trajectory), sensor_(sensor), lens_(sensor.camera), ss_(std::max(1, supersampling)) {
  const int w = sensor.camera.width, h = sensor.camera.height, n = ss_ * ss_;
  const int blur = sensor.exposure_s > 0 ? std::max(1, sensor.blur_samples) : 1;
  rays_per_pixel_ = ((std::max(n, blur) + n - 1) / n) * n;  // a multiple of the spatial pattern
  ray_angle_ = 1.0 / (sensor.camera.intrinsics[0] * ss_);
  rays_.resize(static_cast<size_t>(w) * h * n);
  xn_.resize(rays_.size());
  row_yn_lo_.assign(h, 1e300);
  row_yn_hi_.assign(h, -1e300);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int j = 0; j < ss_; ++j) {
        for (int i = 0; i < ss_; ++i) {
          const Vec2 uv(x + (i + 0.5) / ss_ - 0.5, y + (j + 0.5) / ss_ - 0.5);
          Vec3 ray;
          if (!lens_.unproject(uv, ray)) {
            std::ostringstream msg;
            msg << "camera distortion '" << sensor.camera.distortion << "': pixel (" << uv.x() << ", " << uv.y()
                << ") cannot be unprojected (the model folds over inside the image); use smaller coefficients";
            throw ConfigError(msg.str());
          }
          const size_t idx = (static_cast<size_t>(y) * w + x) * n + j * ss_ + i;
          rays_[idx] = ray.normalized().cast<float>();
          xn_[idx] = static_cast<float>(ray.x());
          row_yn_lo_[y] = std::min(row_yn_lo_[y], ray.y());
          row_yn_hi_[y] = std::max(row_yn_hi_[y], ray.y());
        }
      }
    }
  }
}

Eigen::Isometry3d Renderer::T_W_C(double t_s) const { return trajectory_.pose(t_s) * sensor_.camera.T_B_C; }

bool Renderer::castPixel(const Vec2& uv, double t_capture_s, Scene::Hit& hit) const {
  Vec3 ray;
  if (!lens_.unproject(uv, ray)) return false;
  // The row of a pixel is its integer raw row, as in render().
  const double row = std::round(uv.y());
  const Eigen::Isometry3d T = T_W_C(t_capture_s + sensor_.rowTime(row));
  return scene_.intersect(T.translation(), T.linear() * ray.normalized(), hit);
}

cv::Mat Renderer::render(double t_capture_s) const {
  cv::Mat out(sensor_.camera.height, sensor_.camera.width, CV_32F, cv::Scalar(0));
  renderRows(t_capture_s, 0, sensor_.camera.height, out);
  return out;
}

void Renderer::cullRow(const Mat3& R_W_C, const Vec3& o, int row, std::vector<Candidate>& out) const {
  // A box's image is the convex hull of its corners' images when all corners are in front of the
  // camera, so the corners' x/z and y/z ranges bound it; a box straddling the camera plane is kept.
  out.clear();
  const double margin = 1e-6;
  for (int i = 1; i < scene_.numSolids(); ++i) {
    const Vec3 mn = scene_.solidMin(i), mx = scene_.solidMax(i);
    double x_lo = 1e300, x_hi = -1e300, y_lo = 1e300, y_hi = -1e300;
    bool behind = false;
    for (int c = 0; c < 8 && !behind; ++c) {
      const Vec3 corner((c & 1) ? mx.x() : mn.x(), (c & 2) ? mx.y() : mn.y(), (c & 4) ? mx.z() : mn.z());
      const Vec3 p = R_W_C.transpose() * (corner - o);
      if (p.z() < 1e-3) {
        behind = true;
        break;
      }
      const double xn = p.x() / p.z(), yn = p.y() / p.z();
      x_lo = std::min(x_lo, xn), x_hi = std::max(x_hi, xn), y_lo = std::min(y_lo, yn), y_hi = std::max(y_hi, yn);
    }
    if (behind) {
      // Entirely behind is impossible to tell from corners alone here; keep it with an open x range.
      out.push_back({i, -1e30f, 1e30f});
      continue;
    }
    if (y_hi < row_yn_lo_[row] - margin || y_lo > row_yn_hi_[row] + margin) continue;
    out.push_back({i, static_cast<float>(x_lo - margin), static_cast<float>(x_hi + margin)});
  }
}

void Renderer::renderRows(double t_capture_s, int row_begin, int row_end, cv::Mat& out) const {
  const int w = sensor_.camera.width, n = ss_ * ss_;
  const int m = rays_per_pixel_;
  const bool blur = sensor_.exposure_s > 0 && m > 1;
  const int poses = blur ? m : 1;
  std::vector<Mat3> R(poses);
  std::vector<Vec3> o(poses);
  std::vector<std::vector<Candidate>> cand(poses);
  std::vector<int> list(scene_.numSolids());
  for (int y = row_begin; y < row_end; ++y) {
    const double t_row = t_capture_s + sensor_.rowTime(y);
    // Ray k of a pixel: spatial subsample k % n at time sample k (spread over the exposure).
    for (int k = 0; k < poses; ++k) {
      const double t = blur ? t_row + ((k + 0.5) / m - 0.5) * sensor_.exposure_s : t_row;
      const Eigen::Isometry3d T = T_W_C(t);
      R[k] = T.linear();
      o[k] = T.translation();
      cullRow(R[k], o[k], y, cand[k]);
    }
    float* row = out.ptr<float>(y);
    const size_t row_base = static_cast<size_t>(y) * w * n;
    for (int x = 0; x < w; ++x) {
      double sum = 0.0;
      for (int k = 0; k < m; ++k) {
        const int pk = blur ? k : 0;
        const size_t idx = row_base + static_cast<size_t>(x) * n + (k % n);
        const float xn = xn_[idx];
        int n_list = 0;
        for (const Candidate& c : cand[pk])
          if (xn >= c.xn_lo && xn <= c.xn_hi) list[n_list++] = c.solid;
        const Vec3 d = R[pk] * rays_[idx].cast<double>();
        Scene::Hit hit;
        if (!scene_.intersect(o[pk], d, hit, list.data(), n_list)) continue;
        const double cos_in = std::abs(d[hit.face / 2]);  // faces are axis-aligned, d is a unit vector
        sum += scene_.radiance(hit, hit.t * ray_angle_ / std::max(cos_in, 0.25));
      }
      row[x] = static_cast<float>(sum / m);
    }
  }
}

}  // namespace rsvio::sim
