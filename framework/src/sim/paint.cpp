// Materials and decals of the simulated room (paint.h).
#include "paint.h"

#include <algorithm>
#include <cmath>

#include "rsvio/sim/texture.h"

namespace rsvio::sim::paint {

namespace {
constexpr double kTwoPi = 6.283185307179586;

double clamp01(double v) { return std::clamp(v, 0.02, 0.97); }

// Signed distance to the border of the rectangle [0,w] x [0,h] (negative inside).
double rectDist(double x, double y, double w, double h) {
  return std::max(std::max(-x, x - w), std::max(-y, y - h));
}

double wood(double u, double v, uint64_t seed, double tone) {
  // u along the grain.
  const double warp = 0.6 * fbm(u * 0.8, v * 6.0, seed + 1, 3);
  const double rings = 0.5 + 0.5 * std::sin(kTwoPi * (v * 28.0 + 3.0 * warp));
  const double grain = fbm(u * 3.0, v * 90.0, seed + 2, 4);
  return clamp01(tone * (0.78 + 0.22 * rings) + 0.16 * (grain - 0.5));
}

double plaster(double s, double t, uint64_t seed, double tone) {
  // Blotches at half a metre, a trowel texture at centimetres and grain at millimetres: enough gradient
  // for a direct method on an otherwise plain wall.
  return clamp01(tone + 0.16 * (fbm(s * 2.0, t * 2.0, seed, 3) - 0.5) + 0.10 * (fbm(s * 12.0, t * 12.0, seed + 7, 3) - 0.5) +
                 0.06 * (valueNoise(s * 150.0, t * 150.0, seed + 11) - 0.5));
}

double wallpaper(double s, double t, uint64_t seed, double tone) {
  // Vertical stripes with a repeating motif (small diamonds) between them, on plaster.
  const double period = 0.12 + 0.1 * hash01(1, 2, seed);
  const double fs = s / period - std::floor(s / period), ft = t / period - std::floor(t / period);
  double v = plaster(s, t, seed, tone);
  if (fs < 0.12) v *= 0.75;
  if (std::abs(fs - 0.56) + std::abs(ft - 0.5) < 0.14) v *= 0.7;
  return clamp01(v);
}

double planks(double s, double t, uint64_t seed, double tone) {
  const double w = 0.17, len = 1.3;
  const double row = std::floor(t / w);
  const double off = hash01(static_cast<int64_t>(row), 11, seed) * len;
  const double col = std::floor((s + off) / len);
  const double plank_tone = tone * (0.7 + 0.6 * hash01(static_cast<int64_t>(row), static_cast<int64_t>(col), seed));
  double v = wood(s + off + 13.0 * col, t + 0.37 * row, seed + static_cast<uint64_t>(row), plank_tone);
  const double dt = std::min(t - row * w, (row + 1) * w - t), ds = std::min(s + off - col * len, (col + 1) * len - s - off);
  if (dt < 0.003 || ds < 0.003) v *= 0.35;  // gaps between planks
  return v;
}

double ceilingTiles(double s, double t, uint64_t seed, double tone) {
  const double cell = 0.6;
  const double fs = s / cell - std::floor(s / cell), ft = t / cell - std::floor(t / cell);
  const double d = std::min({fs, 1.0 - fs, ft, 1.0 - ft}) * cell;
  if (d < 0.012) return 0.45;  // metal grid
  return clamp01(tone + 0.12 * (valueNoise(s * 160.0, t * 160.0, seed) - 0.5) +
                 0.05 * (fbm(s * 3.0, t * 3.0, seed + 3, 3) - 0.5));
}

double books(double s, double t, uint64_t seed, double tone) {
  const double shelf_h = 0.36, board = 0.025;
  const double level = std::floor(t / shelf_h), tt = t - level * shelf_h;
  if (tt < board) return clamp01(0.8 * tone + 0.05 * (fbm(s * 40, t * 200, seed, 2) - 0.5));
  // Books of varying width along s; walk cells of 4 cm and merge by hash for varied widths.
  const double cell = 0.035;
  const int64_t c = static_cast<int64_t>(std::floor(s / cell));
  const int64_t lv = static_cast<int64_t>(level);
  const double h = hash01(c, lv, seed);
  if (h < 0.08) return 0.06;  // a gap: the dark back of the shelf
  const double top = board + (0.55 + 0.4 * hash01(c, lv + 100, seed)) * (shelf_h - board);
  if (tt > top) return 0.06;
  const double book_tone = 0.1 + 0.8 * hash01(c, lv + 200, seed);
  double v = book_tone;
  const double label_lo = board + 0.55 * (top - board), label_hi = label_lo + 0.03;
  if (tt > label_lo && tt < label_hi) v = 1.0 - 0.8 * book_tone;
  const double edge = s / cell - std::floor(s / cell);
  if (edge < 0.06 || edge > 0.94) v *= 0.5;
  return clamp01(v + 0.04 * (valueNoise(s * 300.0, t * 60.0, seed + 5) - 0.5));
}

double fabric(double s, double t, uint64_t seed, double tone) {
  const double plaid = 0.5 + 0.5 * std::sin(kTwoPi * s * 9.0) * std::sin(kTwoPi * t * 9.0);
  return clamp01(tone * (0.85 + 0.25 * plaid) + 0.10 * (fbm(s * 60.0, t * 60.0, seed, 2) - 0.5));
}

double leaves(double s, double t, uint64_t seed, double tone) {
  const double n = fbm(s * 14.0, t * 14.0, seed, 4);
  return clamp01(tone * (0.4 + 1.2 * n) + 0.1 * (valueNoise(s * 120, t * 120, seed + 1) - 0.5));
}

double material(const FacePaint& fp, double s, double t) {
  const double u = fp.along_t ? t : s, v = fp.along_t ? s : t;
  switch (fp.material) {
    case Material::Plaster: return plaster(s, t, fp.seed, fp.tone);
    case Material::Wallpaper: return wallpaper(s, t, fp.seed, fp.tone);
    case Material::FloorPlanks: return planks(u, v, fp.seed, fp.tone);
    case Material::CeilingTiles: return ceilingTiles(s, t, fp.seed, fp.tone);
    case Material::Wood: return wood(u, v, fp.seed, fp.tone);
    case Material::DarkWood: return wood(u, v, fp.seed, 0.55 * fp.tone);
    case Material::Fabric: return fabric(s, t, fp.seed, fp.tone);
    case Material::Cardboard:
      return clamp01(fp.tone + 0.10 * (fbm(s * 8, t * 8, fp.seed, 4) - 0.5) + 0.05 * (valueNoise(s * 250, t * 250, fp.seed) - 0.5));
    case Material::Books: return books(s, t, fp.seed, fp.tone);
    case Material::Leaves: return leaves(s, t, fp.seed, fp.tone);
    case Material::Plain: return clamp01(fp.tone + 0.08 * (fbm(s * 4, t * 4, fp.seed, 4) - 0.5));
  }
  return fp.tone;
}

// Poster content in [0,1]^2 coordinates (x right, y up), by variant.
double posterContent(double x, double y, double w, double h, const Decal& d) {
  const uint64_t sd = d.seed;
  switch (d.variant % 6) {
    case 0: {  // bold stripes at an angle
      const double ang = kTwoPi * hash01(1, 0, sd), f = 4.0 + 10.0 * hash01(2, 0, sd);
      const double p = std::sin(kTwoPi * f * (std::cos(ang) * x * w + std::sin(ang) * y * h));
      return 0.5 + 0.4 * std::tanh(3.0 * p);
    }
    case 1: {  // discs
      double v = 0.85;
      for (int i = 0; i < 9; ++i) {
        const double cx = hash01(i, 1, sd) * w, cy = hash01(i, 2, sd) * h, r = (0.04 + 0.16 * hash01(i, 3, sd)) * std::min(w, h) * 1.5;
        if (std::hypot(x * w - cx, y * h - cy) < r) v = 0.1 + 0.7 * hash01(i, 4, sd);
      }
      return v;
    }
    case 2: {  // rotated checkerboard
      const double cell = 0.03 + 0.06 * hash01(3, 0, sd), ang = 0.6 * (hash01(4, 0, sd) - 0.5);
      const double a = (std::cos(ang) * x * w - std::sin(ang) * y * h) / cell, b = (std::sin(ang) * x * w + std::cos(ang) * y * h) / cell;
      return ((static_cast<int64_t>(std::floor(a)) + static_cast<int64_t>(std::floor(b))) & 1) ? 0.15 : 0.85;
    }
    case 3: {  // a page of text: title block and lines of words
      const double yy = (1.0 - y) * h, xx = x * w;
      if (yy < 0.12 * h) return (hash01(static_cast<int64_t>(xx / 0.04), 7, sd) < 0.8 && yy > 0.03 * h) ? 0.15 : 0.9;
      const double line = 0.022;
      const int64_t li = static_cast<int64_t>(yy / line);
      if (yy - li * line < 0.35 * line) return 0.9;
      const int64_t word = static_cast<int64_t>(xx / 0.018);
      return hash01(word, li, sd) < 0.72 ? 0.2 : 0.9;
    }
    case 4: {  // landscape: sky, hills, ground
      const double ridge = 0.45 + 0.25 * fbm(x * 3.0, 0.5, sd, 4);
      if (y > ridge) return 0.75 + 0.2 * y + 0.1 * (fbm(x * 6, y * 3, sd + 2, 3) - 0.5);
      return 0.15 + 0.5 * fbm(x * 12.0, y * 12.0, sd + 1, 5);
    }
    default: {  // concentric rings
      const double r = std::hypot(x - 0.5, (y - 0.5) * h / w);
      return 0.5 + 0.4 * std::tanh(4.0 * std::sin(kTwoPi * r * (6.0 + 10.0 * hash01(5, 0, sd))));
    }
  }
}

// Shade of a decal at local coordinates (x, y) in metres from its lower-left corner; false = not covered.
bool decalShade(const Decal& d, double x, double y, Shade& out) {
  const double w = d.s1 - d.s0, h = d.t1 - d.t0;
  const double border = rectDist(x, y, w, h);
  if (border > 0) return false;
  const double in = -border;  // distance to the edge, inside
  switch (d.kind) {
    case DecalKind::Poster:
      if (in < 0.004) { out.albedo = 0.1; return true; }
      if (in < 0.02) { out.albedo = 0.92; return true; }
      out.albedo = clamp01(posterContent(x / w, y / h, w, h, d));
      return true;
    case DecalKind::Frame:
      if (in < 0.04) { out.albedo = wood(x + y, in * 3.0, d.seed, 0.3); return true; }
      if (in < 0.07) { out.albedo = 0.9; return true; }
      out.albedo = clamp01(0.1 + 0.85 * fbm(x * 4.0, y * 4.0, d.seed, 6, 0.6));
      return true;
    case DecalKind::Door: {
      if (in < 0.05) { out.albedo = 0.8; return true; }  // frame
      const double hx = w - 0.12, hy = 1.0;
      if (std::hypot(x - hx, y - hy) < 0.03) { out.albedo = 0.1; return true; }
      const double px = x - 0.15, py = y - 0.2, pw = w - 0.3, ph = 0.75;  // two inset panels
      const bool edge1 = std::abs(rectDist(px, py, pw, ph)) < 0.008, edge2 = std::abs(rectDist(px, py - 0.95, pw, ph)) < 0.008;
      out.albedo = wood(y, x, d.seed, d.tone) * (edge1 || edge2 ? 0.55 : 1.0);
      return true;
    }
    case DecalKind::Window: {
      if (in < 0.05 || std::abs(x - 0.5 * w) < 0.025 || std::abs(y - 0.55 * h) < 0.025) { out.albedo = 0.85; return true; }
      out.albedo = 0.0;  // the sky and a skyline: light from outside, not lit by the room
      const double sky = fbm(x * 2.5, y * 2.5, d.seed, 4);
      const double roof = 0.25 * h + 0.2 * h * hash01(static_cast<int64_t>(x / 0.12), 3, d.seed);
      out.emission = y < roof ? 0.25 + 0.1 * hash01(static_cast<int64_t>(x / 0.05), static_cast<int64_t>(y / 0.06), d.seed)
                              : 0.75 + 0.25 * sky;
      return true;
    }
    case DecalKind::Whiteboard: {
      if (in < 0.02) { out.albedo = 0.55; return true; }
      double v = 0.9;
      for (int i = 0; i < 7; ++i) {  // marker strokes: wavy lines
        const double y0 = h * (0.15 + 0.7 * hash01(i, 1, d.seed)), amp = 0.03 + 0.08 * hash01(i, 2, d.seed);
        const double f = 3.0 + 12.0 * hash01(i, 3, d.seed), xs = w * 0.6 * hash01(i, 4, d.seed), xe = xs + w * (0.2 + 0.4 * hash01(i, 5, d.seed));
        if (x > xs && x < xe && std::abs(y - y0 - amp * std::sin(kTwoPi * f * x + i)) < 0.004) v = 0.15 + 0.3 * hash01(i, 6, d.seed);
      }
      out.albedo = v;
      return true;
    }
    case DecalKind::Baseboard:
      out.albedo = (y > h - 0.008) ? 0.12 : clamp01(d.tone + 0.05 * (valueNoise(x * 80, y * 80, d.seed) - 0.5));
      return true;
    case DecalKind::Switch:
      out.albedo = (std::abs(x - 0.5 * w) < 0.012 && std::abs(y - 0.5 * h) < 0.02) ? 0.35 : (in < 0.003 ? 0.5 : 0.92);
      return true;
    case DecalKind::Lamp: {
      const bool louvre = std::fmod(x + 10.0, 0.15) < 0.012 || in < 0.03;
      out.albedo = 0.7;
      out.emission = louvre ? 0.1 : 0.55;
      return true;
    }
    case DecalKind::Rug: {
      if (in < 0.06) { out.albedo = 0.15 + 0.1 * std::sin(kTwoPi * (x + y) * 15.0); return true; }
      const double cx = x - 0.5 * w, cy = y - 0.5 * h;
      const double diamond = std::fmod(std::abs(cx) + std::abs(cy), 0.3) / 0.3;
      out.albedo = clamp01(d.tone * (0.6 + 0.6 * (diamond > 0.5)) + 0.1 * (fbm(x * 80, y * 80, d.seed, 2) - 0.5));
      return true;
    }
    case DecalKind::CabinetDoors: {
      const int n = 1 + d.variant % 3;
      const double dw = w / n, fx = x - std::floor(x / dw) * dw;
      if (fx < 0.004 || fx > dw - 0.004 || in < 0.01) { out.albedo = 0.1; return true; }
      if (std::abs(fx - (std::fmod(std::floor(x / dw), 2.0) ? 0.05 : dw - 0.05)) < 0.008 && std::abs(y - 0.75 * h) < 0.06) {
        out.albedo = 0.85;  // handle
        return true;
      }
      return false;  // the material shows through
    }
    case DecalKind::Drawers: {
      const int n = 2 + d.variant % 3;
      const double dh = h / n, fy = y - std::floor(y / dh) * dh;
      if (fy < 0.004 || in < 0.008) { out.albedo = 0.1; return true; }
      if (std::abs(fy - 0.7 * dh) < 0.01 && std::abs(x - 0.5 * w) < 0.08) { out.albedo = 0.85; return true; }
      return false;
    }
    case DecalKind::Clock: {
      const double cx = x - 0.5 * w, cy = y - 0.5 * h, r = std::hypot(cx, cy), R = 0.5 * std::min(w, h);
      if (r > R) return false;
      if (r > R - 0.015) { out.albedo = 0.1; return true; }
      const double ang = std::atan2(cy, cx);
      const double tick = std::fmod(ang / kTwoPi * 12.0 + 12.5, 1.0);
      if (r > R - 0.05 && std::abs(tick - 0.5) < 0.06) { out.albedo = 0.1; return true; }
      const double hand_a = kTwoPi * hash01(1, 1, d.seed);
      const double along = cx * std::cos(hand_a) + cy * std::sin(hand_a), across = -cx * std::sin(hand_a) + cy * std::cos(hand_a);
      out.albedo = (along > 0 && along < 0.7 * R && std::abs(across) < 0.006) ? 0.1 : 0.92;
      return true;
    }
    case DecalKind::Tape:
      out.albedo = clamp01(d.tone + 0.05 * (valueNoise(x * 200, y * 40, d.seed) - 0.5));
      return true;
  }
  return false;
}

}  // namespace

Shade shade(const FacePaint& fp, double s, double t) {
  for (auto it = fp.decals.rbegin(); it != fp.decals.rend(); ++it) {
    Shade out;
    if (s >= it->s0 && s <= it->s1 && t >= it->t0 && t <= it->t1 && decalShade(*it, s - it->s0, t - it->t0, out)) return out;
  }
  Shade out;
  out.albedo = material(fp, s, t);
  return out;
}

}  // namespace rsvio::sim::paint
