// Monocular initialisation: corner tracks, 8-point essential matrix in RANSAC, pose and scale
// (contract in rsvio/backend/mono_initializer.h).
#include "rsvio/backend/mono_initializer.h"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>
#include <utility>

#include "rsvio/core/median.h"
#include "rsvio/core/time.h"
#include "rsvio/interfaces/camera.h"

namespace rsvio {
namespace {

// Mean intensity of the 3x3 pixels around p (level 0, bilinear); false near the border.
bool boxMean(const ImageLevel& level, const Vec2& p, float* mean) {
  const float u = static_cast<float>(p.x()), v = static_cast<float>(p.y());
  if (!level.inside(u, v, 2.f)) return false;
  float sum = 0.f;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) sum += level.sampleIntensity(u + static_cast<float>(dx), v + static_cast<float>(dy));
  *mean = sum / 9.f;
  return std::isfinite(*mean);
}

constexpr int kHalfWin = 4;       // 9x9 Lucas-Kanade window
constexpr int kLkIterations = 12;
constexpr int kRansacIterations = 400;

// Pyramidal Lucas-Kanade of one point from `a` to `b` (zero-mean SSD over a 9x9 window, inverse
// compositional per level). Returns false when the point leaves an image or the window is flat.
bool trackPoint(const ImagePyramid& a, const ImagePyramid& b, const Vec2& p0, const Vec2& guess0, Vec2* out) {
  int levels = std::min({a.numLevels(), b.numLevels(), 5});
  while (levels > 1 && std::min(a.level(levels - 1).width(), a.level(levels - 1).height()) < 6 * kHalfWin) --levels;
  constexpr int n = (2 * kHalfWin + 1) * (2 * kHalfWin + 1);
  float T[n], GX[n], GY[n];
  Vec2 d = (guess0 - p0) / std::pow(2.0, levels - 1);
  for (int l = levels - 1; l >= 0; --l) {
    const ImageLevel& la = a.level(l);
    const ImageLevel& lb = b.level(l);
    const float pu = la.toLevel(static_cast<float>(p0.x())), pv = la.toLevel(static_cast<float>(p0.y()));
    // A window that does not fit a coarse level (near the border): that level is skipped.
    const bool fits = la.inside(pu, pv, kHalfWin + 1.f) &&
                      lb.inside(pu + static_cast<float>(d.x()), pv + static_cast<float>(d.y()), kHalfWin + 1.f);
    if (!fits) {
      if (l == 0) return false;
      d *= 2.0;
      continue;
    }
    double h00 = 0, h01 = 0, h11 = 0, mean_t = 0;
    float s[4];
    int k = 0;
    for (int dy = -kHalfWin; dy <= kHalfWin; ++dy)
      for (int dx = -kHalfWin; dx <= kHalfWin; ++dx, ++k) {
        la.sample(pu + dx, pv + dy, s);
        T[k] = s[0];
        GX[k] = s[1];
        GY[k] = s[2];
        mean_t += s[0];
      }
    mean_t /= n;
    double mgx = 0, mgy = 0;
    for (k = 0; k < n; ++k) {
      mgx += GX[k];
      mgy += GY[k];
    }
    mgx /= n;
    mgy /= n;
    for (k = 0; k < n; ++k) {  // zero-mean residual: the mean gradient drops out of the Hessian too
      GX[k] -= static_cast<float>(mgx);
      GY[k] -= static_cast<float>(mgy);
      h00 += GX[k] * GX[k];
      h01 += GX[k] * GY[k];
      h11 += GY[k] * GY[k];
    }
    const double det = h00 * h11 - h01 * h01;
    if (!(det > 1e-6 * (h00 + h11) * (h00 + h11)) || !(h00 + h11 > 1e-3)) return false;
    for (int it = 0; it < kLkIterations; ++it) {
      const float qu = pu + static_cast<float>(d.x()), qv = pv + static_cast<float>(d.y());
      if (!lb.inside(qu, qv, kHalfWin + 1.f)) return false;
      float I[n];
      double mean_i = 0;
      k = 0;
      for (int dy = -kHalfWin; dy <= kHalfWin; ++dy)
        for (int dx = -kHalfWin; dx <= kHalfWin; ++dx, ++k) {
          I[k] = lb.sampleIntensity(qu + dx, qv + dy);
          mean_i += I[k];
        }
      mean_i /= n;
      double b0 = 0, b1 = 0;
      for (k = 0; k < n; ++k) {
        const double e = (I[k] - mean_i) - (T[k] - mean_t);
        b0 += GX[k] * e;
        b1 += GY[k] * e;
      }
      const Vec2 step((h11 * b0 - h01 * b1) / det, (h00 * b1 - h01 * b0) / det);
      d -= step;
      if (step.squaredNorm() < 1e-4) break;
    }
    if (l > 0) d *= 2.0;
  }
  *out = p0 + d;
  return std::isfinite(out->x()) && std::isfinite(out->y());
}

using Mat3d = Eigen::Matrix3d;

// Hartley normalisation of 2D points: T maps them to zero mean and mean distance sqrt(2).
Mat3d normaliser(const std::vector<Eigen::Vector2d>& x, const std::vector<int>& idx) {
  Eigen::Vector2d m = Eigen::Vector2d::Zero();
  for (int i : idx) m += x[static_cast<size_t>(i)];
  m /= static_cast<double>(idx.size());
  double s = 0;
  for (int i : idx) s += (x[static_cast<size_t>(i)] - m).norm();
  s = std::sqrt(2.0) * static_cast<double>(idx.size()) / std::max(s, 1e-12);
  Mat3d T;
  T << s, 0, -s * m.x(), 0, s, -s * m.y(), 0, 0, 1;
  return T;
}

// Linear 8-point (or more) essential matrix, x2^T E x1 = 0, projected onto the essential manifold.
Mat3d eightPoint(const std::vector<Eigen::Vector2d>& x1, const std::vector<Eigen::Vector2d>& x2,
                 const std::vector<int>& idx) {
  const Mat3d T1 = normaliser(x1, idx), T2 = normaliser(x2, idx);
  Eigen::MatrixXd A(static_cast<Eigen::Index>(idx.size()), 9);
  for (size_t r = 0; r < idx.size(); ++r) {
    const Eigen::Vector3d a = T1 * x1[static_cast<size_t>(idx[r])].homogeneous();
    const Eigen::Vector3d b = T2 * x2[static_cast<size_t>(idx[r])].homogeneous();
    A.row(static_cast<Eigen::Index>(r)) << b.x() * a.x(), b.x() * a.y(), b.x(), b.y() * a.x(), b.y() * a.y(), b.y(),
        a.x(), a.y(), 1.0;
  }
  Eigen::Matrix<double, 9, 9> AtA = A.transpose() * A;
  Eigen::JacobiSVD<Eigen::Matrix<double, 9, 9>> svd(AtA, Eigen::ComputeFullV);
  const Eigen::Matrix<double, 9, 1> e = svd.matrixV().col(8);
  Mat3d En;
  En << e[0], e[1], e[2], e[3], e[4], e[5], e[6], e[7], e[8];
  Mat3d E = T2.transpose() * En * T1;
  Eigen::JacobiSVD<Mat3d> s2(E, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const double sv = 0.5 * (s2.singularValues()[0] + s2.singularValues()[1]);
  return s2.matrixU() * Eigen::Vector3d(sv, sv, 0).asDiagonal() * s2.matrixV().transpose();
}

double sampson(const Mat3d& E, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector3d x1 = a.homogeneous(), x2 = b.homogeneous();
  const Eigen::Vector3d Ex1 = E * x1, Etx2 = E.transpose() * x2;
  const double num = x2.dot(Ex1);
  const double den = Ex1.head<2>().squaredNorm() + Etx2.head<2>().squaredNorm();
  return den > 0 ? num * num / den : 1e30;
}

// Depths of the two rays (bearings b1 in camera 1, b2 in camera 2, x2 = R x1 + t) at their closest points.
bool triangulate(const Mat3d& R, const Eigen::Vector3d& t, const Eigen::Vector3d& b1, const Eigen::Vector3d& b2,
                 double* d1, double* d2) {
  Eigen::Matrix<double, 3, 2> A;
  A.col(0) = R * b1;
  A.col(1) = -b2;
  const Eigen::Matrix2d AtA = A.transpose() * A;
  const double det = AtA.determinant();
  if (!(std::abs(det) > 1e-12)) return false;
  const Eigen::Vector2d l = AtA.inverse() * (A.transpose() * (-t));
  *d1 = l[0];
  *d2 = l[1];
  return true;
}

}  // namespace

bool fitRotationRate(const std::vector<Eigen::Vector3d>& a, const std::vector<double>& tau_a,
                     const std::vector<Eigen::Vector3d>& b, const std::vector<double>& tau_b, double dt,
                     Eigen::Vector3d* w) {
  const size_t n = std::min({a.size(), b.size(), tau_a.size(), tau_b.size()});
  std::vector<uint8_t> use(n, 1);
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  // r_k = b_k - exp([w] dt_k) a_k; d r_k / d w = [p_k]x dt_k with p_k = exp([w] dt_k) a_k (left
  // perturbation of the rotation, to first order).
  auto solve = [&](int rounds) {
    for (int it = 0; it < rounds; ++it) {
      Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
      Eigen::Vector3d g = Eigen::Vector3d::Zero();
      int used = 0;
      for (size_t k = 0; k < n; ++k) {
        if (!use[k]) continue;
        const double dk = dt + tau_b[k] - tau_a[k];
        const Eigen::Vector3d p = SO3d::exp(x * dk) * a[k];
        const Eigen::Matrix3d J = SO3d::hat(p) * dk;
        const Eigen::Vector3d r = b[k] - p;
        H += J.transpose() * J;
        g += J.transpose() * r;
        ++used;
      }
      if (used < 8) return false;
      Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
      if (ldlt.info() != Eigen::Success || !(H.trace() > 0.0)) return false;
      const Eigen::Vector3d dx = ldlt.solve(-g);
      if (!dx.allFinite()) return false;
      x += dx;
    }
    return true;
  };
  if (n < 8 || !solve(3)) return false;
  std::vector<double> res(n);
  for (size_t k = 0; k < n; ++k) res[k] = (b[k] - SO3d::exp(x * (dt + tau_b[k] - tau_a[k])) * a[k]).norm();
  const double lim = 3.0 * upperMedian(res);
  for (size_t k = 0; k < n; ++k) use[k] = res[k] <= lim ? 1 : 0;
  if (!solve(2)) return false;
  *w = x;
  return true;
}

MonoInitializer::MonoInitializer(const BackendOptions& options, const CameraModel& camera, const RowTiming& timing)
    : options_(options), camera_(camera), timing_(timing) {}

void MonoInitializer::reset(int64_t frame_index, int64_t t_ns) {
  const ImageLevel& l0 = prev_->level(0);
  cv::Mat img8(l0.height(), l0.width(), CV_8U);
  for (int y = 0; y < l0.height(); ++y)
    for (int x = 0; x < l0.width(); ++x)
      img8.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(l0.intensity(x, y));
  std::vector<cv::Point2f> corners;
  const double diag = std::hypot(l0.width(), l0.height());
  cv::Mat mask = cv::Mat::zeros(img8.size(), CV_8U);
  const int border = 12;
  mask(cv::Rect(border, border, std::max(1, img8.cols - 2 * border), std::max(1, img8.rows - 2 * border))) = 255;
  cv::goodFeaturesToTrack(img8, corners, options_.init_corners, 0.01, std::max(3.0, diag / 60.0), mask, 5);
  ref_pts_ = corners;
  cur_pts_ = corners;
  ref_intensity_.assign(corners.size(), std::numeric_limits<float>::quiet_NaN());
  for (size_t i = 0; i < corners.size(); ++i) boxMean(l0, Vec2(corners[i].x, corners[i].y), &ref_intensity_[i]);
  unexplained_flow_.assign(corners.size(), Vec2::Zero());
  hist_pts_.assign(1, corners);
  hist_t_ns_.assign(1, t_ns);
  initial_tracks_ = static_cast<int>(corners.size());
  ref_index_ = frame_index;
  ref_t_ns_ = t_ns;
  frames_since_ref_ = 0;
}

bool MonoInitializer::addFrame(std::shared_ptr<const ImagePyramid> pyramid, int64_t frame_index, int64_t t_ns) {
  cur_t_ns_ = t_ns;
  steps_.clear();
  step_from_ = -1;
  if (!prev_ || ref_index_ < 0) {
    prev_index_ = frame_index;
    prev_ = std::move(pyramid);
    reset(frame_index, t_ns);
    status_ = "reference frame set (" + std::to_string(initial_tracks_) + " corners)";
    return false;
  }
  // Where each search starts: the corner's old position, or (with a rotation source) its bearing
  // rotated by the camera's rotation since the previous frame and projected back, plus what the
  // rotation did not explain of the corner's previous step (translation's flow, constant over one frame
  // interval; 0 on a new reference). The old position where the projection fails.
  const size_t n = cur_pts_.size();
  Eigen::Matrix2Xd rotated_px(2, static_cast<Eigen::Index>(n));
  for (size_t i = 0; i < n; ++i) rotated_px.col(static_cast<Eigen::Index>(i)) = Vec2(cur_pts_[i].x, cur_pts_[i].y);
  Eigen::Matrix2Xd guess = rotated_px;
  SO3d R_cur_prev;
  const bool rotated = guess_source_ && n > 0 && guess_source_(hist_t_ns_.back(), t_ns, &R_cur_prev);
  if (rotated) {
    Eigen::Matrix3Xd bearing;
    std::vector<uint8_t> ok_u, ok_p;
    camera_.unproject(guess, bearing, ok_u);
    Eigen::Matrix2Xd uv;
    camera_.project(R_cur_prev.matrix() * bearing, uv, ok_p);
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Index c = static_cast<Eigen::Index>(i);
      if (!ok_u[i] || !ok_p[i] || !uv.col(c).allFinite()) continue;
      rotated_px.col(c) = uv.col(c);
      guess.col(c) = uv.col(c) + unexplained_flow_[i];
    }
  }
  // Frame-to-frame tracks with a forward-backward check.
  std::vector<cv::Point2f> ref_kept, cur_kept;
  std::vector<float> ref_intensity_kept;
  std::vector<size_t> kept;
  std::vector<Vec2> unexplained_kept;
  for (size_t i = 0; i < n; ++i) {
    const Vec2 p(cur_pts_[i].x, cur_pts_[i].y);
    Vec2 q, back;
    if (!trackPoint(*prev_, *pyramid, p, guess.col(static_cast<Eigen::Index>(i)), &q)) continue;
    if (!trackPoint(*pyramid, *prev_, q, p, &back) || (back - p).norm() > 1.0) continue;
    ref_kept.push_back(ref_pts_[i]);
    ref_intensity_kept.push_back(ref_intensity_[i]);
    cur_kept.emplace_back(static_cast<float>(q.x()), static_cast<float>(q.y()));
    kept.push_back(i);
    unexplained_kept.push_back(rotated ? Vec2(q - rotated_px.col(static_cast<Eigen::Index>(i))) : Vec2::Zero());
    CornerStep s;
    if (frames_since_ref_ > 0 && boxMean(prev_->level(0), p, &s.intensity_prev) &&
        boxMean(pyramid->level(0), q, &s.intensity)) {
      s.px = q;
      steps_.push_back(s);
    }
  }
  if (frames_since_ref_ > 0) step_from_ = prev_index_;
  prev_index_ = frame_index;
  unexplained_flow_.swap(unexplained_kept);
  ref_pts_.swap(ref_kept);
  ref_intensity_.swap(ref_intensity_kept);
  cur_pts_.swap(cur_kept);
  for (std::vector<cv::Point2f>& h : hist_pts_) {
    std::vector<cv::Point2f> hk;
    hk.reserve(kept.size());
    for (size_t i : kept) hk.push_back(h[i]);
    h.swap(hk);
  }
  hist_pts_.push_back(cur_pts_);
  hist_t_ns_.push_back(t_ns);
  prev_ = std::move(pyramid);
  ++frames_since_ref_;
  if (static_cast<int>(cur_pts_.size()) < std::max(30, initial_tracks_ / 3)) {
    status_ = "lost corner tracks (" + std::to_string(cur_pts_.size()) + "), new reference";
    reset(frame_index, t_ns);
    return false;
  }
  if (frames_since_ref_ < options_.init_min_frames) {
    status_ = "waiting for frames (" + std::to_string(cur_pts_.size()) + " corner tracks)";
    return false;
  }
  return tryInitialise();
}

double MonoInitializer::logGainCurRef() const {
  if (!prev_) return 0.0;
  std::vector<double> ratio;
  for (size_t i = 0; i < cur_pts_.size(); ++i) {
    float cur = 0.f;
    if (std::isfinite(ref_intensity_[i]) && ref_intensity_[i] >= 8.f &&
        boxMean(prev_->level(0), Vec2(cur_pts_[i].x, cur_pts_[i].y), &cur) && cur > 0.f)
      ratio.push_back(static_cast<double>(cur) / ref_intensity_[i]);
  }
  return ratio.size() < 20 ? 0.0 : std::log(upperMedian(std::move(ratio)));
}

bool MonoInitializer::tryInitialise() {
  const int w = camera_.width(), h = camera_.height();
  std::vector<double> flow;
  for (size_t i = 0; i < cur_pts_.size(); ++i) flow.push_back(std::hypot(cur_pts_[i].x - ref_pts_[i].x, cur_pts_[i].y - ref_pts_[i].y));
  const double med_flow = upperMedian(flow);
  if (med_flow < options_.init_min_flow_px * std::hypot(w, h)) {
    std::ostringstream os;
    os << "median corner flow " << med_flow << " px is small";
    status_ = os.str();
    return false;
  }
  std::vector<Vec2> ref_px, cur_px;
  for (size_t i = 0; i < cur_pts_.size(); ++i) {
    ref_px.emplace_back(ref_pts_[i].x, ref_pts_[i].y);
    cur_px.emplace_back(cur_pts_[i].x, cur_pts_[i].y);
  }
  TwoViewOptions tvo;
  tvo.rolling_shutter_iterations = options_.init_rolling_shutter_iterations;
  // Each image's rotation rate needs two frame pairs at each end (with 3 frames after the reference
  // the two ends share their middle pair).
  const int last = static_cast<int>(hist_pts_.size()) - 1;
  const bool rates_wanted = options_.init_rotation_rates && timing_.dtDv() != 0.0;
  bool from_source = false;
  if (rates_wanted && rate_source_)
    from_source = rate_source_(hist_t_ns_.front(), &tvo.w_ref) && rate_source_(hist_t_ns_.back(), &tvo.w_cur);
  if (from_source)
    tvo.use_rates = true;
  else if (rates_wanted && last >= 3)
    tvo.use_rates = rateAt(0, 0, &tvo.w_ref) && rateAt(last - 2, last, &tvo.w_cur);
  const TwoViewResult r = solveTwoView(ref_px, cur_px, camera_, timing_, nsToS(cur_t_ns_ - ref_t_ns_),
                                       0x5eed1234u + static_cast<uint64_t>(ref_index_), tvo);
  status_ = r.status;
  if (from_source) status_ += ", the rates from the gyroscope";
  parallax_deg_ = r.parallax_deg;
  if (!r.found) return false;
  if (r.inlier_ratio < options_.init_min_inlier_ratio || r.front < 0.9 * static_cast<double>(r.inliers) ||
      parallax_deg_ < options_.init_min_parallax_deg || r.num_depths < 10)
    return false;
  T_cur_ref_ = r.T_cur_ref;
  xi_ = r.xi;
  rates_used_ = tvo.use_rates;
  xi_ref_ = tvo.use_rates ? r.xi_ref : r.xi;
  xi_cur_ = tvo.use_rates ? r.xi_cur : r.xi;
  return true;
}

bool MonoInitializer::rateAt(int i0, int at, Eigen::Vector3d* w) const {
  auto pairRate = [&](int i, Eigen::Vector3d* out) {
    const std::vector<cv::Point2f>& pa = hist_pts_[static_cast<size_t>(i)];
    const std::vector<cv::Point2f>& pb = hist_pts_[static_cast<size_t>(i) + 1];
    const Eigen::Index n = static_cast<Eigen::Index>(pa.size());
    Eigen::Matrix2Xd ua(2, n), ub(2, n);
    for (Eigen::Index k = 0; k < n; ++k) {
      ua.col(k) << pa[static_cast<size_t>(k)].x, pa[static_cast<size_t>(k)].y;
      ub.col(k) << pb[static_cast<size_t>(k)].x, pb[static_cast<size_t>(k)].y;
    }
    Eigen::Matrix3Xd ba, bb;
    std::vector<uint8_t> va, vb;
    camera_.unproject(ua, ba, va);
    camera_.unproject(ub, bb, vb);
    std::vector<Eigen::Vector3d> a, b;
    std::vector<double> ta, tb;
    for (Eigen::Index k = 0; k < n; ++k) {
      if (!va[static_cast<size_t>(k)] || !vb[static_cast<size_t>(k)]) continue;
      a.push_back(ba.col(k).normalized());
      b.push_back(bb.col(k).normalized());
      ta.push_back(timing_.rowTime(ua(1, k)));
      tb.push_back(timing_.rowTime(ub(1, k)));
    }
    const double dt = nsToS(hist_t_ns_[static_cast<size_t>(i) + 1] - hist_t_ns_[static_cast<size_t>(i)]);
    return dt > 0.0 && fitRotationRate(a, ta, b, tb, dt, out);
  };
  Eigen::Vector3d w0, w1;
  if (!pairRate(i0, &w0) || !pairRate(i0 + 1, &w1)) return false;
  // Each pair's rate belongs to the middle of its interval; the line through both, at the image's time.
  auto mid = [&](int i) {
    return 0.5 * nsToS(hist_t_ns_[static_cast<size_t>(i)] - hist_t_ns_[0]) +
           0.5 * nsToS(hist_t_ns_[static_cast<size_t>(i) + 1] - hist_t_ns_[0]);
  };
  const double m0 = mid(i0), m1 = mid(i0 + 1), t = nsToS(hist_t_ns_[static_cast<size_t>(at)] - hist_t_ns_[0]);
  if (!(m1 > m0)) return false;
  *w = w0 + (w1 - w0) * ((t - m0) / (m1 - m0));
  return w->allFinite();
}

namespace {

// One essential-matrix fit from the inlier set `in` (refit twice, re-selecting inliers), its
// decomposition (the one of four with most points in front of both cameras), and the depths of every
// correspondence along its ray in both cameras (NaN where the rays do not meet in front).
struct EssentialFit {
  Mat3d R;
  Eigen::Vector3d t;  // unit length
  std::vector<int> in;
  int front = -1;
  std::vector<double> d1, d2;  // per correspondence
  std::vector<double> angle;   // per inlier in front
};

EssentialFit fitEssential(const std::vector<Eigen::Vector2d>& x1, const std::vector<Eigen::Vector2d>& x2,
                          const std::vector<Eigen::Vector3d>& B1, const std::vector<Eigen::Vector3d>& B2,
                          std::vector<int> in, double thr) {
  const int m = static_cast<int>(x1.size());
  EssentialFit f;
  Mat3d E = eightPoint(x1, x2, in);
  for (int rep = 0; rep < 2; ++rep) {
    std::vector<int> sel;
    for (int i = 0; i < m; ++i)
      if (sampson(E, x1[static_cast<size_t>(i)], x2[static_cast<size_t>(i)]) < thr) sel.push_back(i);
    if (sel.size() < 8) break;
    in.swap(sel);
    E = eightPoint(x1, x2, in);
  }
  f.in = in;
  Eigen::JacobiSVD<Mat3d> svd(E, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3d U = svd.matrixU(), V = svd.matrixV();
  if (U.determinant() < 0) U = -U;
  if (V.determinant() < 0) V = -V;
  Mat3d Wm;
  Wm << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const Mat3d Rs[2] = {U * Wm * V.transpose(), U * Wm.transpose() * V.transpose()};
  for (const Mat3d& R : Rs)
    for (double sgn : {1.0, -1.0}) {
      const Eigen::Vector3d t = sgn * U.col(2);
      int front = 0;
      std::vector<double> angle;
      for (int i : in) {
        double d1 = 0, d2 = 0;
        if (!triangulate(R, t, B1[static_cast<size_t>(i)], B2[static_cast<size_t>(i)], &d1, &d2)) continue;
        if (d1 > 0 && d2 > 0) {
          ++front;
          angle.push_back(std::acos(std::clamp(B1[static_cast<size_t>(i)].dot(R.transpose() * B2[static_cast<size_t>(i)]), -1.0, 1.0)));
        }
      }
      if (front > f.front) {
        f.front = front;
        f.R = R;
        f.t = t;
        f.angle = angle;
      }
    }
  const double nan = std::nan("");
  f.d1.assign(static_cast<size_t>(m), nan);
  f.d2.assign(static_cast<size_t>(m), nan);
  for (int i = 0; i < m; ++i) {
    double d1 = 0, d2 = 0;
    if (triangulate(f.R, f.t, B1[static_cast<size_t>(i)], B2[static_cast<size_t>(i)], &d1, &d2) && d1 > 0 && d2 > 0) {
      f.d1[static_cast<size_t>(i)] = d1;
      f.d2[static_cast<size_t>(i)] = d2;
    }
  }
  return f;
}

// A bearing seen at row time tau of a frame moving with twist xi, moved to the frame's central pose:
// P(tau) = exp(xi tau) P(0) (shutter.h), so P(0) = exp(-xi tau) P(tau). With the depth unknown (NaN)
// the ray's direction at infinity: the rotation alone.
Eigen::Vector3d toCentralPose(const Eigen::Vector3d& b, double depth, const Vec6& xi, double tau) {
  const SE3d M = SE3d::exp(-xi * tau);
  if (std::isfinite(depth)) return (M * (depth * b)).normalized();
  return (M.so3() * b).normalized();
}

}  // namespace

TwoViewResult solveTwoView(const std::vector<Vec2>& ref_px, const std::vector<Vec2>& cur_px, const CameraModel& camera,
                           const RowTiming& timing, double dt_s, uint64_t seed, const TwoViewOptions& options) {
  TwoViewResult r;
  // Unit-focal image-plane coordinates through the camera's own unprojection.
  const Eigen::Index n = static_cast<Eigen::Index>(std::min(ref_px.size(), cur_px.size()));
  Eigen::Matrix2Xd u1(2, n), u2(2, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    u1.col(i) = ref_px[static_cast<size_t>(i)];
    u2.col(i) = cur_px[static_cast<size_t>(i)];
  }
  Eigen::Matrix3Xd b1, b2;
  std::vector<uint8_t> v1, v2;
  camera.unproject(u1, b1, v1);
  camera.unproject(u2, b2, v2);
  std::vector<Eigen::Vector2d> x1, x2;
  std::vector<Eigen::Vector3d> R1, R2;  // raw bearings, as observed at their rows
  std::vector<double> tau1, tau2;       // row times relative to each image's timestamp
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!v1[static_cast<size_t>(i)] || !v2[static_cast<size_t>(i)] || b1(2, i) < 0.1 || b2(2, i) < 0.1) continue;
    x1.emplace_back(b1(0, i) / b1(2, i), b1(1, i) / b1(2, i));  // the unit-focal plane, as observed
    x2.emplace_back(b2(0, i) / b2(2, i), b2(1, i) / b2(2, i));
    R1.push_back(b1.col(i).normalized());
    R2.push_back(b2.col(i).normalized());
    tau1.push_back(timing.rowTime(u1(1, i)));
    tau2.push_back(timing.rowTime(u2(1, i)));
  }
  const int m = static_cast<int>(R1.size());
  r.correspondences = m;
  if (m < 20) {
    r.status = "too few corners for the essential matrix";
    return r;
  }
  std::vector<Eigen::Vector3d> B1 = R1, B2 = R2;
  auto toPlane = [&]() {
    x1.resize(static_cast<size_t>(m));
    x2.resize(static_cast<size_t>(m));
    for (size_t i = 0; i < static_cast<size_t>(m); ++i) {
      x1[i] = B1[i].head<2>() / B1[i].z();
      x2[i] = B2[i].head<2>() / B2[i].z();
    }
  };
  const bool rates = options.use_rates && timing.dtDv() != 0.0;
  if (rates) {
    // Each bearing rotated to its image's central pose with the image's own rotation rate: a bearing
    // read at row time tau is exp([w] tau) times its direction at the central pose.
    for (size_t i = 0; i < static_cast<size_t>(m); ++i) {
      B1[i] = SO3d::exp(-options.w_ref * tau1[i]) * R1[i];
      B2[i] = SO3d::exp(-options.w_cur * tau2[i]) * R2[i];
    }
    toPlane();
  }
  const double f = camera.calibration().intrinsics[0] > 0 ? camera.calibration().intrinsics[0] : 500.0;
  const double thr = (1.0 / f) * (1.0 / f);
  std::mt19937_64 rng(seed);
  std::vector<int> best_in;
  std::vector<int> sample(8);
  for (int it = 0; it < kRansacIterations; ++it) {
    for (int k = 0; k < 8; ++k) {
      int c;
      do {
        c = static_cast<int>(rng() % static_cast<uint64_t>(m));
      } while (std::find(sample.begin(), sample.begin() + k, c) != sample.begin() + k);
      sample[static_cast<size_t>(k)] = c;
    }
    const Mat3d E = eightPoint(x1, x2, sample);
    std::vector<int> in;
    for (int i = 0; i < m; ++i)
      if (sampson(E, x1[static_cast<size_t>(i)], x2[static_cast<size_t>(i)]) < thr) in.push_back(i);
    if (in.size() > best_in.size()) best_in.swap(in);
  }
  if (best_in.size() < 8) {
    r.status = "no essential matrix";
    return r;
  }
  EssentialFit fit = fitEssential(x1, x2, B1, B2, best_in, thr);
  // Rolling shutter: each corner was seen at its own row's time. With the motion of the fit taken as a
  // constant twist between the two timestamps (xi = log(T_cur_ref) / dt, per second, in the units of
  // the unit baseline), every bearing is moved to its frame's central pose through its triangulated
  // depth, and the essential matrix is fitted again from the current inliers. A global shutter (or a
  // line delay of 0) skips this: every row time is 0.
  Vec6 xi = Vec6::Zero();
  const bool rolling = timing.dtDv() != 0.0 && dt_s > 0.0;
  for (int k = 0; rolling && !rates && k < options.rolling_shutter_iterations; ++k) {
    xi = SE3d(fit.R, fit.t).log() / dt_s;
    for (size_t i = 0; i < static_cast<size_t>(m); ++i) {
      B1[i] = toCentralPose(R1[i], fit.d1[i], xi, tau1[i]);
      B2[i] = toCentralPose(R2[i], fit.d2[i], xi, tau2[i]);
    }
    toPlane();
    fit = fitEssential(x1, x2, B1, B2, fit.in, thr);
  }
  r.inliers = static_cast<int>(fit.in.size());
  r.inlier_ratio = static_cast<double>(fit.in.size()) / m;
  r.front = fit.front;
  r.parallax_deg = upperMedian(fit.angle) * 180.0 / M_PI;
  std::ostringstream os;
  os << "essential matrix: " << fit.in.size() << "/" << m << " inliers, " << fit.front << " in front, median parallax "
     << r.parallax_deg << " deg";
  if (rates)
    os << ", rolling shutter corrected with each image's rotation rate";
  else if (rolling && options.rolling_shutter_iterations > 0)
    os << ", rolling shutter corrected";
  r.status = os.str();
  std::vector<double> depth;
  for (int i : fit.in)
    if (std::isfinite(fit.d1[static_cast<size_t>(i)])) depth.push_back(fit.d1[static_cast<size_t>(i)]);
  r.num_depths = static_cast<int>(depth.size());
  const double med_depth = upperMedian(depth);
  if (depth.empty() || !(med_depth > 0)) return r;
  r.T_cur_ref = SE3d(Eigen::Quaterniond(fit.R).normalized(), fit.t / med_depth);
  if (rolling && dt_s > 0) r.xi = r.T_cur_ref.log() / dt_s;
  if (rates) {
    r.xi_ref << r.xi.head<3>(), options.w_ref;
    r.xi_cur << r.xi.head<3>(), options.w_cur;
  }
  r.found = true;
  return r;
}

}  // namespace rsvio
