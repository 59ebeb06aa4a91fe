// Colour maps shared by every figure, so that "error" looks the same in 3D views, the error plot and
// the compare grid.
// - turbo (Google's polynomial fit of the Turbo map) via errorMap: errors; blue = small, dark red = large.
// - viridis (matplotlib's, 11 stops, linear in between): residual heat maps (perceptually uniform).
// - grey: point intensities, mapped into [lo, hi] grey levels so points never vanish on white.
// Inputs are clamped to [0, 1]; NaN gives the "no data" colour (light grey).
#pragma once
#include <array>
#include <cstdint>

namespace rsvio::viz {

struct Rgb {
  uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
};

Rgb turbo(double t);
// Errors: turbo without its near-black ends (0.1 .. 0.95), so a small error never reads as "dark = bad"
// and every colour stands out on white. Used by every error figure.
Rgb errorMap(double t);
Rgb viridis(double t);
Rgb grey(double t, uint8_t lo = 90, uint8_t hi = 215);
constexpr Rgb kNoData{220, 220, 220};

// Maps v in [lo, hi] to [0, 1]; logarithmically when log_scale (lo, hi > 0). Clamped; NaN stays NaN.
double normalise(double v, double lo, double hi, bool log_scale = false);

}  // namespace rsvio::viz
