// Nearest-timestamp association of an estimated trajectory with ground truth.
//
// Rule (the one evo and the TUM RGB-D tools use when the estimate is the shorter trajectory): every
// estimate is matched to the ground-truth pose whose stamp is nearest to it; the pair is kept when
// |t_gt - t_est| <= max_dt_ns, otherwise the estimate is left unmatched. Ties go to the earlier
// ground-truth stamp. Several estimates may share one ground-truth pose (duplicate estimate stamps do).
// No interpolation: the largest allowed difference bounds the error it can add (speed * max_dt).
// Stamps are int64 nanoseconds and must be non-decreasing (as io::readTum guarantees).
#pragma once
#include <cstdint>
#include <vector>

#include "rsvio/io/trajectory.h"

namespace rsvio::eval {

struct AssociatedPair {
  size_t i_est = 0;
  size_t i_gt = 0;
  int64_t dt_ns = 0;  // t_gt - t_est
};

struct Association {
  std::vector<AssociatedPair> pairs;  // in estimate order
  int64_t max_dt_ns = 0;              // the allowed largest |t_gt - t_est|
  int64_t largest_abs_dt_ns = 0;      // the largest |dt| among the kept pairs
  size_t n_est = 0;
  size_t n_gt = 0;
  size_t unmatched() const { return n_est - pairs.size(); }
};

Association associateNearest(const std::vector<int64_t>& t_est, const std::vector<int64_t>& t_gt, int64_t max_dt_ns);
Association associateNearest(const io::Trajectory& est, const io::Trajectory& gt, int64_t max_dt_ns);

}  // namespace rsvio::eval
