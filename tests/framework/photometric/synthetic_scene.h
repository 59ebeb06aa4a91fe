// A small ray-cast scene for the front-end tests: textured planes seen by a pinhole camera, rendered
// with 3x3 supersampling so that views agree photometrically, with the exact z-depth of every pixel.
// Rolling shutter: the pose is asked per row, so a moving camera shears the image as a real sensor does.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

namespace rsvio::test {

struct PinholeK {
  double fx = 250, fy = 250, cx = 159.5, cy = 127.5;
  int width = 320, height = 256;
};

// A rigid pose camera-from-world.
struct PoseCW {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Vector3d apply(const Eigen::Vector3d& p) const { return R * p + t; }
  Eigen::Vector3d centre() const { return -R.transpose() * t; }
};

struct TexturedPlane {
  Eigen::Vector3d origin;  // a point on the plane (texture (0,0))
  Eigen::Vector3d e1, e2;  // orthonormal in-plane axes
  double texel_m = 0.01;   // metres per texel
  int texture = 0;         // index into the scene's textures
};

class SyntheticScene {
 public:
  // Default: a room corner seen from the origin looking +z: back wall at z = 4, a floor at y = 1.2,
  // a left wall at x = -2.5 and a box face at z = 2.5 in front of the wall (depth discontinuities).
  explicit SyntheticScene(uint32_t seed = 1) {
    textures_.push_back(makeTexture(seed, 512));
    textures_.push_back(makeTexture(seed + 17, 512));
    const Eigen::Vector3d X(1, 0, 0), Y(0, 1, 0), Z(0, 0, 1);
    planes_.push_back({Eigen::Vector3d(-3, -3, 4.0), X, Y, 0.012, 0});   // back wall
    planes_.push_back({Eigen::Vector3d(-3, 1.2, 0.0), X, Z, 0.012, 1});  // floor
    planes_.push_back({Eigen::Vector3d(-2.5, -3, 0.0), Z, Y, 0.012, 1});  // left wall
    box_ = true;
  }

  void setPlanes(std::vector<TexturedPlane> planes, bool box) {
    planes_ = std::move(planes);
    box_ = box;
  }

  // Radiance along a world ray; depth = ray parameter along a direction with unit z in the camera.
  bool trace(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double* value, double* t_hit) const {
    double best = 1e30;
    double val = 0;
    for (const TexturedPlane& p : planes_) {
      const Eigen::Vector3d n = p.e1.cross(p.e2);
      const double den = n.dot(d);
      if (std::abs(den) < 1e-9) continue;
      const double t = n.dot(p.origin - o) / den;
      if (t <= 1e-6 || t >= best) continue;
      const Eigen::Vector3d q = o + t * d - p.origin;
      best = t;
      val = texel(p.texture, q.dot(p.e1) / p.texel_m, q.dot(p.e2) / p.texel_m);
    }
    if (box_) {
      // Box face: the square x in [-0.6, 0.4], y in [-0.7, 0.3] of the plane z = 2.5.
      if (std::abs(d.z()) > 1e-9) {
        const double t = (2.5 - o.z()) / d.z();
        const Eigen::Vector3d q = o + t * d;
        if (t > 1e-6 && t < best && q.x() > -0.6 && q.x() < 0.4 && q.y() > -0.7 && q.y() < 0.3) {
          best = t;
          val = 0.8 * texel(0, (q.x() + 7) / 0.008, (q.y() + 7) / 0.008) + 30;
        }
      }
    }
    if (best >= 1e29) return false;
    *value = val;
    *t_hit = best;
    return true;
  }

  // Renders a CV_32F image and (optionally) the z-depth of each pixel centre. pose_of_row(v) gives the
  // camera pose for raw row v (constant for a global shutter).
  cv::Mat render(const PinholeK& K, const std::function<PoseCW(double)>& pose_of_row, cv::Mat* depth = nullptr,
                 int supersample = 3) const {
    cv::Mat img(K.height, K.width, CV_32F);
    if (depth) depth->create(K.height, K.width, CV_32F);
    for (int v = 0; v < K.height; ++v) {
      const PoseCW T = pose_of_row(v);
      const Eigen::Matrix3d Rwc = T.R.transpose();
      const Eigen::Vector3d o = T.centre();
      for (int u = 0; u < K.width; ++u) {
        double sum = 0;
        for (int sy = 0; sy < supersample; ++sy)
          for (int sx = 0; sx < supersample; ++sx) {
            const double du = (sx + 0.5) / supersample - 0.5, dv = (sy + 0.5) / supersample - 0.5;
            const Eigen::Vector3d dc((u + du - K.cx) / K.fx, (v + dv - K.cy) / K.fy, 1.0);
            double val = 0, t = 0;
            if (trace(o, Rwc * dc, &val, &t)) sum += val;
          }
        img.at<float>(v, u) = static_cast<float>(sum / (supersample * supersample));
        if (depth) {
          const Eigen::Vector3d dc((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
          double val = 0, t = 0;
          depth->at<float>(v, u) = trace(o, Rwc * dc, &val, &t) ? static_cast<float>(t) : 0.f;
        }
      }
    }
    return img;
  }

  cv::Mat render(const PinholeK& K, const PoseCW& T, cv::Mat* depth = nullptr) const {
    return render(K, [&](double) { return T; }, depth);
  }

 private:
  // Band-limited noise: a sum of blurred random fields at several scales, mapped to [25, 230].
  static cv::Mat makeTexture(uint32_t seed, int n) {
    std::mt19937 rng(seed);
    cv::Mat acc = cv::Mat::zeros(n, n, CV_32F);
    const double sigmas[] = {2.0, 5.0, 12.0};
    const double weights[] = {0.8, 1.0, 1.2};
    for (int s = 0; s < 3; ++s) {
      cv::Mat f(n, n, CV_32F);
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) f.at<float>(y, x) = static_cast<float>((rng() & 0xFFFF) / 65535.0 - 0.5);
      // Periodic blur (GaussianBlur has no BORDER_WRAP): pad by wrapping, blur, crop.
      const int pad = static_cast<int>(4 * sigmas[s]) + 1;
      cv::Mat padded;
      cv::copyMakeBorder(f, padded, pad, pad, pad, pad, cv::BORDER_WRAP);
      cv::GaussianBlur(padded, padded, cv::Size(0, 0), sigmas[s], sigmas[s]);
      f = padded(cv::Rect(pad, pad, n, n)).clone();
      cv::Scalar mean, sd;
      cv::meanStdDev(f, mean, sd);
      acc += (f - mean[0]) * (weights[s] / sd[0]);
    }
    cv::Scalar mean, sd;
    cv::meanStdDev(acc, mean, sd);
    cv::Mat out = (acc - mean[0]) * (45.0 / sd[0]) + 128.0;
    cv::min(out, 230.0, out);
    cv::max(out, 25.0, out);
    return out;
  }

  double texel(int tex, double x, double y) const {
    const cv::Mat& T = textures_[tex];
    const int n = T.cols;
    const double fx = std::floor(x), fy = std::floor(y);
    const double ax = x - fx, ay = y - fy;
    auto at = [&](long i, long j) {
      i = ((i % n) + n) % n;
      j = ((j % n) + n) % n;
      return static_cast<double>(T.at<float>(static_cast<int>(j), static_cast<int>(i)));
    };
    const long ix = static_cast<long>(fx), iy = static_cast<long>(fy);
    return (1 - ay) * ((1 - ax) * at(ix, iy) + ax * at(ix + 1, iy)) + ay * ((1 - ax) * at(ix, iy + 1) + ax * at(ix + 1, iy + 1));
  }

  std::vector<cv::Mat> textures_;
  std::vector<TexturedPlane> planes_;
  bool box_ = false;
};

}  // namespace rsvio::test
