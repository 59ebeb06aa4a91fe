#include "rsvio/frontend/frontend_options.h"

#include <algorithm>

namespace rsvio {

ParamTable frontendParamTable() {
  ParamTable t = PixelSelectorOptions::paramTable();
  const ParamTable r = ResidualOptions::paramTable();
  t.insert(t.end(), r.begin(), r.end());
  t.push_back(paramInt("pyramid_levels", 5, 1, 8, "", "levels of each frame's image pyramid (coarsest >= 16 px)"));
  const ParamTable k = TrackerOptions::paramTable();
  t.insert(t.end(), k.begin(), k.end());
  const ParamTable c = CandidateOptions::paramTable();
  t.insert(t.end(), c.begin(), c.end());
  return t;
}

FrontendOptions frontendOptions(const Params& p, uint64_t seed, int threads) {
  FrontendOptions o;
  o.pyramid_levels = static_cast<int>(p.getInt("pyramid_levels"));
  o.select = PixelSelectorOptions::fromParams(p);
  o.select.seed = seed;
  o.residual = ResidualOptions::fromParams(p);
  o.track = TrackerOptions::fromParams(p);
  o.track.residual = o.residual;
  o.track.threads = std::clamp(threads, 1, 2);
  o.track.max_levels = std::min(o.track.max_levels, o.pyramid_levels);
  o.trace = CandidateOptions::fromParams(p);
  return o;
}

}  // namespace rsvio
