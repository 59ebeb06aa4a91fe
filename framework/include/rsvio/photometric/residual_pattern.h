// The residual pattern: which pixels around a point's host pixel form its photometric residual.
//
// DSO's 8-pixel pattern (Engel et al. 2018, Fig. 4, "residual pattern N_p"): a sparse diamond of radius
// 2 that spreads 8 samples over a 5x5 area, so one point sees an edge from several sides at the cost of
// 8 interpolations. Offsets are in pixels of the level the pattern is evaluated on; the centre (0, 0)
// is kCentre. The host side uses the offsets as they are; the target side maps them through the local
// host-to-target warp of the point (identity for the tracker, as DSO).
#pragma once

namespace rsvio {

constexpr int kPatternSize = 8;
constexpr int kPatternRadius = 2;  // max |offset| along either axis
constexpr int kPatternCentre = 4;  // index of (0, 0)

// {dx, dy} per pattern pixel.
constexpr int kPattern[kPatternSize][2] = {{0, -2}, {-1, -1}, {1, -1}, {-2, 0},
                                           {0, 0},  {2, 0},   {-1, 1}, {0, 2}};

}  // namespace rsvio
