// Gradient-based point selection spread over the image (DSO, Engel et al. 2018, section 3.2 / Fig. 6).
//
// Contract
// - Works on level 0..2 of an ImagePyramid (RAW image, pixel centres at integers); returns level-0
//   integer pixels in raster order, none closer than border_px to the image edge.
// - Region-adaptive threshold: the image is cut into block_px x block_px blocks; in each, the median
//   gradient norm (histogram quantile grad_quantile, plus grad_threshold_add) gives a threshold, which
//   is smoothed over the 3x3 neighbouring blocks (DSO's thsSmoothed). A pixel qualifies when its
//   |g|^2 exceeds the squared threshold of its block.
// - Spread: within every d x d cell (d = the "potential") the best qualifying pixel is taken, where
//   "best" is the gradient projected on a random direction (so that edges of every orientation are
//   picked). Cells where no level-0 pixel qualifies fall back to 2d x 2d cells on level 1 and 4d x 4d
//   on level 2 with thresholds lowered by level_downweight per level: weak, textureless regions still
//   get (fewer) points. d is adapted so the count lands near num_points, then the result is randomly
//   thinned to at most num_points.
// - Deterministic: the same pyramid, options and seed give the same points (std::mt19937_64 bits only;
//   no std distributions, whose output is implementation-defined).
#pragma once
#include <cstdint>
#include <vector>

#include "rsvio/photometric/image_pyramid.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

struct PixelSelectorOptions {
  int num_points = 2000;            // target count
  int block_px = 32;                // block side of the adaptive threshold
  double grad_quantile = 0.5;       // quantile of the block's gradient-norm histogram (0.5: median)
  double grad_threshold_add = 7.0;  // added to the quantile, intensity units per pixel
  double level_downweight = 0.75;   // threshold factor per pyramid level for the fallback levels
  int border_px = 5;                // no point closer than this to the image edge
  uint64_t seed = 0;                // random directions and thinning

  static ParamTable paramTable();                       // keys select_* (see frontend_options.h)
  static PixelSelectorOptions fromParams(const Params& p);
};

struct SelectedPixel {
  int u = 0;        // level-0 pixel column
  int v = 0;        // level-0 pixel row
  int level = 0;    // level at which the pixel qualified (0: strong gradient; 1, 2: fallback)
  float grad2 = 0;  // |g|^2 at level 0
};

class PixelSelector {
 public:
  explicit PixelSelector(PixelSelectorOptions options) : options_(options) {}

  // Selects about options.num_points pixels. `mask`, when non-empty (CV_8U, level-0 size), excludes
  // pixels where it is 0 (e.g. around points that already exist).
  std::vector<SelectedPixel> select(const ImagePyramid& pyramid, const cv::Mat& mask = cv::Mat()) const;
  std::vector<SelectedPixel> select(const ImagePyramid& pyramid, int num_points, const cv::Mat& mask) const;

  // Squared per-block thresholds of level 0 (after smoothing), row-major over the block grid; for tests.
  std::vector<float> blockThresholds(const ImageLevel& level0, int* blocks_x, int* blocks_y) const;

  const PixelSelectorOptions& options() const { return options_; }

 private:
  std::vector<SelectedPixel> selectWithPotential(const ImagePyramid& pyr, const std::vector<float>& ths, int bx,
                                                 int pot, const cv::Mat& mask, uint64_t seed) const;
  PixelSelectorOptions options_;
};

}  // namespace rsvio
