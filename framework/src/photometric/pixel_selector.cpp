#include "rsvio/photometric/pixel_selector.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "rsvio/core/error.h"

namespace rsvio {

namespace {

// 16 unit directions in the right half plane (gradient sign does not matter, only its orientation).
std::array<Eigen::Vector2f, 16> makeDirections() {
  std::array<Eigen::Vector2f, 16> d;
  for (int i = 0; i < 16; ++i) {
    const float a = static_cast<float>(-M_PI / 2 + M_PI * i / 16.0);
    d[i] = Eigen::Vector2f(std::cos(a), std::sin(a));
  }
  return d;
}

// Cells of a d x d grid, each visited in a fixed order; a qualifying pixel's score is its gradient
// projected on the cell's random direction.
struct Best {
  int idx = -1;
  float score = 0.f;
  int level = 0;
};

}  // namespace

std::vector<float> PixelSelector::blockThresholds(const ImageLevel& L, int* blocks_x, int* blocks_y) const {
  const int B = std::max(4, options_.block_px);
  const int bx = std::max(1, L.width() / B);
  const int by = std::max(1, L.height() / B);
  *blocks_x = bx;
  *blocks_y = by;
  constexpr int kBins = 50;  // gradient norms 0..48 (clamped), as DSO's histogram
  std::vector<float> ths(static_cast<size_t>(bx) * by);
  std::array<int, kBins> hist;
  for (int j = 0; j < by; ++j)
    for (int i = 0; i < bx; ++i) {
      hist.fill(0);
      int total = 0;
      const int x1 = (i == bx - 1) ? L.width() : (i + 1) * B;
      const int y1 = (j == by - 1) ? L.height() : (j + 1) * B;
      for (int y = std::max(1, j * B); y < std::min(y1, L.height() - 1); ++y)
        for (int x = std::max(1, i * B); x < std::min(x1, L.width() - 1); ++x) {
          const int g = std::min(48, static_cast<int>(std::sqrt(L.gradSquared(x, y))));
          ++hist[g];
          ++total;
        }
      int k = 0;
      int need = static_cast<int>(total * options_.grad_quantile + 0.5);
      for (; k < 48; ++k) {
        need -= hist[k];
        if (need < 0) break;
      }
      ths[j * bx + i] = static_cast<float>(k + options_.grad_threshold_add);
    }
  // Smooth over the 3x3 block neighbourhood, then square (compared against |g|^2).
  std::vector<float> out(ths.size());
  for (int j = 0; j < by; ++j)
    for (int i = 0; i < bx; ++i) {
      float s = 0.f;
      int n = 0;
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          const int ii = i + di, jj = j + dj;
          if (ii < 0 || jj < 0 || ii >= bx || jj >= by) continue;
          s += ths[jj * bx + ii];
          ++n;
        }
      const float m = s / n;
      out[j * bx + i] = m * m;
    }
  return out;
}

std::vector<SelectedPixel> PixelSelector::selectWithPotential(const ImagePyramid& pyr, const std::vector<float>& ths,
                                                              int bx, int pot, const cv::Mat& mask,
                                                              uint64_t seed) const {
  static const std::array<Eigen::Vector2f, 16> kDirs = makeDirections();
  const ImageLevel& L0 = pyr.level(0);
  const ImageLevel* L1 = pyr.numLevels() > 1 ? &pyr.level(1) : nullptr;
  const ImageLevel* L2 = pyr.numLevels() > 2 ? &pyr.level(2) : nullptr;
  const int w = L0.width(), h = L0.height();
  const int B = std::max(4, options_.block_px);
  const int by = static_cast<int>(ths.size()) / bx;
  const int border = std::max(2, options_.border_px);
  const float dw1 = static_cast<float>(options_.level_downweight);
  const float dw2 = dw1 * dw1;
  std::mt19937_64 rng(seed);
  std::vector<SelectedPixel> out;

  auto consider = [&](int x, int y, const Eigen::Vector2f& dir, float th, float g2, int level, Best& best) {
    if (g2 <= th) return;
    const float* p = L0.pixel(x, y);
    const float score = std::abs(p[1] * dir.x() + p[2] * dir.y());
    if (score > best.score || best.idx < 0) best = Best{y * w + x, score, level};
  };

  for (int y4 = 0; y4 < h; y4 += 4 * pot)
    for (int x4 = 0; x4 < w; x4 += 4 * pot) {
      Best best4;
      bool have_finer4 = false;
      const Eigen::Vector2f dir4 = kDirs[rng() & 15];
      for (int y3 = y4; y3 < std::min(h, y4 + 4 * pot); y3 += 2 * pot)
        for (int x3 = x4; x3 < std::min(w, x4 + 4 * pot); x3 += 2 * pot) {
          Best best3;
          bool have_finer3 = false;
          const Eigen::Vector2f dir3 = kDirs[rng() & 15];
          for (int y2 = y3; y2 < std::min(h, y3 + 2 * pot); y2 += pot)
            for (int x2 = x3; x2 < std::min(w, x3 + 2 * pot); x2 += pot) {
              Best best2;
              const Eigen::Vector2f dir2 = kDirs[rng() & 15];
              for (int y = y2; y < std::min(h, y2 + pot); ++y) {
                if (y < border || y >= h - border) continue;
                const int tb_y = std::min(by - 1, y / B);
                const uint8_t* mrow = mask.empty() ? nullptr : mask.ptr<uint8_t>(y);
                for (int x = x2; x < std::min(w, x2 + pot); ++x) {
                  if (x < border || x >= w - border) continue;
                  if (mrow && !mrow[x]) continue;
                  const float th0 = ths[tb_y * bx + std::min(bx - 1, x / B)];
                  consider(x, y, dir2, th0, L0.gradSquared(x, y), 0, best2);
                  if (best2.idx >= 0) continue;  // a level-0 pixel in this cell: no fallback needed
                  if (!have_finer3 && L1) {
                    const int x1 = std::min(L1->width() - 1, x / 2), y1 = std::min(L1->height() - 1, y / 2);
                    consider(x, y, dir3, th0 * dw1, L1->gradSquared(x1, y1), 1, best3);
                  }
                  if (!have_finer4 && L2) {
                    const int x2l = std::min(L2->width() - 1, x / 4), y2l = std::min(L2->height() - 1, y / 4);
                    consider(x, y, dir4, th0 * dw2, L2->gradSquared(x2l, y2l), 2, best4);
                  }
                }
              }
              if (best2.idx >= 0) {
                out.push_back({best2.idx % w, best2.idx / w, 0, L0.gradSquared(best2.idx % w, best2.idx / w)});
                have_finer3 = have_finer4 = true;
              }
            }
          if (!have_finer3 && best3.idx >= 0) {
            out.push_back({best3.idx % w, best3.idx / w, 1, L0.gradSquared(best3.idx % w, best3.idx / w)});
            have_finer4 = true;
          }
        }
      if (!have_finer4 && best4.idx >= 0)
        out.push_back({best4.idx % w, best4.idx / w, 2, L0.gradSquared(best4.idx % w, best4.idx / w)});
    }
  return out;
}

std::vector<SelectedPixel> PixelSelector::select(const ImagePyramid& pyramid, const cv::Mat& mask) const {
  return select(pyramid, options_.num_points, mask);
}

std::vector<SelectedPixel> PixelSelector::select(const ImagePyramid& pyramid, int num_points,
                                                 const cv::Mat& mask) const {
  if (pyramid.numLevels() == 0 || num_points <= 0) return {};
  if (!mask.empty() && (mask.type() != CV_8UC1 || mask.cols != pyramid.width() || mask.rows != pyramid.height()))
    throw Error("PixelSelector: mask must be CV_8UC1 of the level-0 image size");
  int bx = 0, by = 0;
  const std::vector<float> ths = blockThresholds(pyramid.level(0), &bx, &by);

  // The count behaves like K / (pot + 1)^2 for a scene constant K (DSO); start from the pot that would
  // put one point per cell, re-select until within [num_points, 1.6 num_points] or pot can't move.
  const double area = static_cast<double>(pyramid.width()) * pyramid.height();
  int pot = std::max(1, static_cast<int>(std::sqrt(area / num_points)) - 1);
  std::vector<SelectedPixel> pts;
  for (int attempt = 0; attempt < 6; ++attempt) {
    pts = selectWithPotential(pyramid, ths, bx, pot, mask, options_.seed * 0x9E3779B97F4A7C15ull + 1);
    const double have = static_cast<double>(pts.size());
    if (have >= num_points && have <= 1.6 * num_points) break;
    if (have < 1.0) break;
    const double K = have * (pot + 1) * (pot + 1);
    int ideal = static_cast<int>(std::sqrt(K / num_points)) - 1;
    if (have < num_points) {
      if (pot <= 1) break;
      ideal = std::min(ideal, pot - 1);
    } else {
      ideal = std::max(ideal, pot + 1);
    }
    pot = std::max(1, ideal);
  }
  if (static_cast<int>(pts.size()) > num_points) {
    // Random thinning to exactly num_points (partial Fisher-Yates), then back to raster order.
    std::mt19937_64 rng(options_.seed * 0xD1B54A32D192ED03ull + 7);
    for (int i = 0; i < num_points; ++i) {
      const uint64_t j = i + rng() % (pts.size() - i);
      std::swap(pts[i], pts[j]);
    }
    pts.resize(num_points);
    std::sort(pts.begin(), pts.end(),
              [](const SelectedPixel& a, const SelectedPixel& b) { return a.v != b.v ? a.v < b.v : a.u < b.u; });
  } else {
    std::sort(pts.begin(), pts.end(),
              [](const SelectedPixel& a, const SelectedPixel& b) { return a.v != b.v ? a.v < b.v : a.u < b.u; });
  }
  return pts;
}

ParamTable PixelSelectorOptions::paramTable() {
  const PixelSelectorOptions d;
  return {
      paramInt("points", d.num_points, 10, 100000, "", "number of points selected per keyframe (DSO: 2000)"),
      paramInt("select_block_px", d.block_px, 8, 256, "px", "block side of the region-adaptive gradient threshold"),
      paramDouble("select_grad_quantile", d.grad_quantile, 0.05, 0.95, "",
                  "quantile of a block's gradient-norm histogram taken as its threshold (0.5: median)"),
      paramDouble("select_grad_add", d.grad_threshold_add, 0.0, 100.0, "intensity",
                  "added to the block quantile to form the gradient threshold"),
      paramDouble("select_level_downweight", d.level_downweight, 0.1, 1.0, "",
                  "threshold factor per pyramid level where weak regions fall back to coarser cells"),
      paramInt("select_border_px", d.border_px, 2, 64, "px", "no point closer than this to the image edge"),
  };
}

PixelSelectorOptions PixelSelectorOptions::fromParams(const Params& p) {
  PixelSelectorOptions o;
  o.num_points = static_cast<int>(p.getInt("points"));
  o.block_px = static_cast<int>(p.getInt("select_block_px"));
  o.grad_quantile = p.getDouble("select_grad_quantile");
  o.grad_threshold_add = p.getDouble("select_grad_add");
  o.level_downweight = p.getDouble("select_level_downweight");
  o.border_px = static_cast<int>(p.getInt("select_border_px"));
  return o;
}

}  // namespace rsvio
