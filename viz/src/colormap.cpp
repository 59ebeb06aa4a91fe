// Colour maps (rsvio/viz/colormap.h).
#include "rsvio/viz/colormap.h"

#include <algorithm>
#include <cmath>

namespace rsvio::viz {
namespace {

uint8_t toByte(double c) { return static_cast<uint8_t>(std::lround(255.0 * std::clamp(c, 0.0, 1.0))); }

}  // namespace

Rgb turbo(double t) {
  if (std::isnan(t)) return kNoData;
  const double x = std::clamp(t, 0.0, 1.0);
  // Anton Mikhailov's polynomial approximation (Google AI blog, 2019).
  const double r = 0.13572138 + x * (4.61539260 + x * (-42.66032258 + x * (132.13108234 + x * (-152.94239396 + x * 59.28637943))));
  const double g = 0.09140261 + x * (2.19418839 + x * (4.84296658 + x * (-14.18503333 + x * (4.27729857 + x * 2.82956604))));
  const double b = 0.10667330 + x * (12.64194608 + x * (-60.58204836 + x * (110.36276771 + x * (-89.90310912 + x * 27.34824973))));
  return {toByte(r), toByte(g), toByte(b)};
}

Rgb errorMap(double t) {
  if (std::isnan(t)) return kNoData;
  return turbo(0.1 + 0.85 * std::clamp(t, 0.0, 1.0));
}

Rgb viridis(double t) {
  if (std::isnan(t)) return kNoData;
  static constexpr std::array<std::array<uint8_t, 3>, 11> kStops = {{{0x44, 0x01, 0x54}, {0x48, 0x24, 0x75},
                                                                     {0x41, 0x44, 0x87}, {0x35, 0x5f, 0x8d},
                                                                     {0x2a, 0x78, 0x8e}, {0x21, 0x91, 0x8c},
                                                                     {0x22, 0xa8, 0x84}, {0x44, 0xbf, 0x70},
                                                                     {0x7a, 0xd1, 0x51}, {0xbd, 0xdf, 0x26},
                                                                     {0xfd, 0xe7, 0x25}}};
  const double x = std::clamp(t, 0.0, 1.0) * 10.0;
  const int i = std::min(9, static_cast<int>(x));
  const double f = x - i;
  auto mix = [&](int c) { return static_cast<uint8_t>(std::lround(kStops[i][c] * (1 - f) + kStops[i + 1][c] * f)); };
  return {mix(0), mix(1), mix(2)};
}

Rgb grey(double t, uint8_t lo, uint8_t hi) {
  if (std::isnan(t)) return kNoData;
  const auto v = static_cast<uint8_t>(std::lround(lo + (hi - lo) * std::clamp(t, 0.0, 1.0)));
  return {v, v, v};
}

double normalise(double v, double lo, double hi, bool log_scale) {
  if (std::isnan(v)) return v;
  if (log_scale && lo > 0 && hi > lo) {
    if (v <= 0) return 0.0;
    return std::clamp((std::log(v) - std::log(lo)) / (std::log(hi) - std::log(lo)), 0.0, 1.0);
  }
  if (!(hi > lo)) return 0.0;
  return std::clamp((v - lo) / (hi - lo), 0.0, 1.0);
}

}  // namespace rsvio::viz
