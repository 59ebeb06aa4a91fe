// Textures of the simulated scene: single-channel float images laid on planar faces, sampled with a
// footprint-aware trilinear filter (mip pyramid), plus the value noise the painters build them from.
//
// Contract
// - A TextureMap covers a rectangle of a face: texel (i, j) has its centre at (s, t) = ((i + 0.5),
//   (j + 0.5)) * texel_m from the face's origin; sampling outside clamps to the edge.
// - Values are baked radiance (albedo times lighting), dimensionless, about [0, 1.2].
// - sample(s, t, footprint_m): footprint_m is the size of the ray's footprint on the surface; the mip
//   level is log2(footprint / texel). Deterministic and thread-safe after buildMips().
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace rsvio::sim {

class TextureMap {
 public:
  TextureMap() = default;
  TextureMap(int width, int height, double texel_m);
  static TextureMap constant(float value);

  int width() const { return w_.empty() ? 0 : w_[0]; }
  int height() const { return h_.empty() ? 0 : h_[0]; }
  double texelSize() const { return texel_m_; }
  float* data() { return levels_[0].data(); }
  float& at(int x, int y) { return levels_[0][static_cast<size_t>(y) * w_[0] + x]; }
  float at(int x, int y) const { return levels_[0][static_cast<size_t>(y) * w_[0] + x]; }

  void buildMips();  // after the base level is filled
  float sample(double s_m, double t_m, double footprint_m) const;
  size_t bytes() const;

 private:
  float bilinear(int level, double x, double y) const;
  double texel_m_ = 1.0;
  std::vector<std::vector<float>> levels_;
  std::vector<int> w_, h_;
};

// 2-D value noise on an integer lattice hashed with `seed`: smooth, in [0, 1), period-free.
double valueNoise(double x, double y, uint64_t seed);
// Fractal sum of value noise: `octaves` octaves, each twice the frequency and `gain` times the weight;
// normalised to [0, 1).
double fbm(double x, double y, uint64_t seed, int octaves, double gain = 0.5);
// Hash of integers to [0, 1) (for per-cell random choices inside painters).
double hash01(int64_t a, int64_t b, uint64_t seed);

}  // namespace rsvio::sim
