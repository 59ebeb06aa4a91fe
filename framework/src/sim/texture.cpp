// TextureMap sampling and value noise (rsvio/sim/texture.h).
#include "rsvio/sim/texture.h"

#include <algorithm>
#include <cmath>


namespace rsvio::sim {

TextureMap::TextureMap(int width, int height, double texel_m) : texel_m_(texel_m) {
  w_.push_back(std::max(1, width));
  h_.push_back(std::max(1, height));
  levels_.emplace_back(static_cast<size_t>(w_[0]) * h_[0], 0.0f);
}

TextureMap TextureMap::constant(float value) {
  TextureMap t(1, 1, 1e3);
  t.at(0, 0) = value;
  t.buildMips();
  return t;
}

void TextureMap::buildMips() {
  levels_.resize(1);
  w_.resize(1);
  h_.resize(1);
  // 2x2 box filter; an odd last column/row folds into the previous one.
  while (w_.back() > 1 || h_.back() > 1) {
    const int pw = w_.back(), ph = h_.back();
    const int nw = std::max(1, pw / 2), nh = std::max(1, ph / 2);
    std::vector<float> next(static_cast<size_t>(nw) * nh);
    const std::vector<float>& prev = levels_.back();
    for (int y = 0; y < nh; ++y) {
      const int y0 = std::min(2 * y, ph - 1), y1 = std::min(2 * y + 1, ph - 1);
      for (int x = 0; x < nw; ++x) {
        const int x0 = std::min(2 * x, pw - 1), x1 = std::min(2 * x + 1, pw - 1);
        next[static_cast<size_t>(y) * nw + x] =
            0.25f * (prev[static_cast<size_t>(y0) * pw + x0] + prev[static_cast<size_t>(y0) * pw + x1] +
                     prev[static_cast<size_t>(y1) * pw + x0] + prev[static_cast<size_t>(y1) * pw + x1]);
      }
    }
    levels_.push_back(std::move(next));
    w_.push_back(nw);
    h_.push_back(nh);
  }
}

size_t TextureMap::bytes() const {
  size_t n = 0;
  for (const auto& l : levels_) n += l.size() * sizeof(float);
  return n;
}

float TextureMap::bilinear(int level, double x, double y) const {
  // x, y in texel units of this level, texel centres at i + 0.5.
  const int w = w_[level], h = h_[level];
  const std::vector<float>& img = levels_[level];
  x -= 0.5;
  y -= 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const float ax = static_cast<float>(x - fx), ay = static_cast<float>(y - fy);
  const int x0 = std::clamp(static_cast<int>(fx), 0, w - 1), x1 = std::clamp(static_cast<int>(fx) + 1, 0, w - 1);
  const int y0 = std::clamp(static_cast<int>(fy), 0, h - 1), y1 = std::clamp(static_cast<int>(fy) + 1, 0, h - 1);
  const float* r0 = img.data() + static_cast<size_t>(y0) * w;
  const float* r1 = img.data() + static_cast<size_t>(y1) * w;
  const float top = r0[x0] + ax * (r0[x1] - r0[x0]);
  const float bot = r1[x0] + ax * (r1[x1] - r1[x0]);
  return top + ay * (bot - top);
}

namespace {
// log2 for x >= 1, exact at powers of two and linear in between: the mip level only needs to be
// continuous and monotone, and libm's log2 was a visible share of the render time.
double fastLog2(double x) {
  int e;
  const double m = std::frexp(x, &e);  // x = m 2^e, m in [0.5, 1)
  return (e - 1) + (2.0 * m - 1.0);
}
}  // namespace

float TextureMap::sample(double s_m, double t_m, double footprint_m) const {
  if (levels_.size() == 1 && w_[0] == 1 && h_[0] == 1) return levels_[0][0];
  const double ratio = footprint_m / texel_m_;
  const double lod = ratio > 1.0 ? fastLog2(ratio) : 0.0;
  const int last = static_cast<int>(levels_.size()) - 1;
  const int l0 = std::min(static_cast<int>(lod), last);
  const int l1 = std::min(l0 + 1, last);
  const float frac = static_cast<float>(std::min(lod - l0, 1.0));
  // Level l spans the same rectangle with w_[l] x h_[l] texels.
  const double x = s_m / texel_m_, y = t_m / texel_m_;
  const float v0 = bilinear(l0, x * w_[l0] / w_[0], y * h_[l0] / h_[0]);
  if (frac <= 0.0f || l1 == l0) return v0;
  const float v1 = bilinear(l1, x * w_[l1] / w_[0], y * h_[l1] / h_[0]);
  return v0 + frac * (v1 - v0);
}

double hash01(int64_t a, int64_t b, uint64_t seed) {
  // Two multiply-xorshift rounds: enough mixing for lattice noise, and the hot spot of texture painting.
  uint64_t h = seed ^ (static_cast<uint64_t>(a) * 0x9E3779B97F4A7C15ull) ^ (static_cast<uint64_t>(b) * 0xC2B2AE3D27D4EB4Full);
  h ^= h >> 32;
  h *= 0xD6E8FEB86659FD93ull;
  h ^= h >> 32;
  h *= 0xD6E8FEB86659FD93ull;
  h ^= h >> 32;
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

double valueNoise(double x, double y, uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
  double ux = x - fx, uy = y - fy;
  ux = ux * ux * (3.0 - 2.0 * ux);  // smoothstep: C1 continuous
  uy = uy * uy * (3.0 - 2.0 * uy);
  const double a = hash01(ix, iy, seed), b = hash01(ix + 1, iy, seed);
  const double c = hash01(ix, iy + 1, seed), d = hash01(ix + 1, iy + 1, seed);
  return a + (b - a) * ux + (c - a) * uy + (a - b - c + d) * ux * uy;
}

double fbm(double x, double y, uint64_t seed, int octaves, double gain) {
  double sum = 0.0, norm = 0.0, amp = 1.0, f = 1.0;
  for (int o = 0; o < octaves; ++o) {
    // Each octave rotated and offset, so lattice lines of the octaves do not line up.
    const double rx = 0.8 * x - 0.6 * y, ry = 0.6 * x + 0.8 * y;
    sum += amp * valueNoise(rx * f + 17.3 * o, ry * f - 9.1 * o, seed + o);
    norm += amp;
    amp *= gain;
    f *= 2.0;
    std::swap(x, y);
  }
  return sum / norm;
}

}  // namespace rsvio::sim
