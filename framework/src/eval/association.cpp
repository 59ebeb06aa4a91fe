// Nearest-timestamp association (rule in rsvio/eval/association.h).
#include "rsvio/eval/association.h"

#include <algorithm>
#include <cstdlib>

namespace rsvio::eval {

Association associateNearest(const std::vector<int64_t>& t_est, const std::vector<int64_t>& t_gt, int64_t max_dt_ns) {
  Association a;
  a.max_dt_ns = max_dt_ns;
  a.n_est = t_est.size();
  a.n_gt = t_gt.size();
  if (t_gt.empty()) return a;
  for (size_t i = 0; i < t_est.size(); ++i) {
    const int64_t t = t_est[i];
    // First ground-truth stamp >= t; the nearest is it or the one before. lower_bound lands on the first
    // of equal stamps, and a tie in distance keeps the earlier one (strict < below).
    const auto it = std::lower_bound(t_gt.begin(), t_gt.end(), t);
    size_t best = static_cast<size_t>(it - t_gt.begin());
    if (best == t_gt.size()) {
      best = t_gt.size() - 1;
    } else if (best > 0) {
      // Step back to the first of a run of equal earlier stamps so ties resolve to the earliest index.
      size_t prev = best - 1;
      while (prev > 0 && t_gt[prev - 1] == t_gt[prev]) --prev;
      if (std::llabs(t - t_gt[prev]) <= std::llabs(t_gt[best] - t)) best = prev;
    }
    const int64_t dt = t_gt[best] - t;
    if (std::llabs(dt) > max_dt_ns) continue;
    a.pairs.push_back({i, best, dt});
    a.largest_abs_dt_ns = std::max<int64_t>(a.largest_abs_dt_ns, std::llabs(dt));
  }
  return a;
}

Association associateNearest(const io::Trajectory& est, const io::Trajectory& gt, int64_t max_dt_ns) {
  std::vector<int64_t> te, tg;
  te.reserve(est.size());
  tg.reserve(gt.size());
  for (const auto& p : est.poses) te.push_back(p.t_ns);
  for (const auto& p : gt.poses) tg.push_back(p.t_ns);
  return associateNearest(te, tg, max_dt_ns);
}

}  // namespace rsvio::eval
