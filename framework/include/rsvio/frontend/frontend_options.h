// The "frontend" section of the run config: one options struct per front-end subsystem, one parameter
// table for the whole section (register it with ConfigSchema::section("frontend", frontendParamTable(),
// ...) in run_schema.cpp).
//
// Keys (flat, prefixed by subsystem):
//   points, select_*      point selection        (PixelSelectorOptions, photometric/pixel_selector.h)
//   residual_*            photometric residual   (ResidualOptions, photometric/photometric_residual.h)
//   pyramid_levels        levels of every frame's image pyramid
//   track_*               frame tracker          (TrackerOptions, frontend/frame_tracker.h)
//   trace_*               candidate points       (CandidateOptions, frontend/candidate_points.h)
// Not here on purpose: the selection seed and the thread count (top-level "seed" and "threads" of the
// run config; frontendOptions() takes them), and which brightness parameters the tracker estimates
// (set from the photometric models: TrackerOptions::estimate_a/b).
#pragma once
#include <cstdint>

#include "rsvio/frontend/candidate_points.h"
#include "rsvio/frontend/frame_tracker.h"
#include "rsvio/photometric/pixel_selector.h"
#include "rsvio/plugin/plugin.h"

namespace rsvio {

struct FrontendOptions {
  int pyramid_levels = 5;
  PixelSelectorOptions select;
  ResidualOptions residual;
  TrackerOptions track;        // track.residual == residual
  CandidateOptions trace;
};

// Every key of the "frontend" section with its default, range, unit and description.
ParamTable frontendParamTable();

// From a validated "frontend" section (defaults filled). seed: the run's seed (point selection);
// threads: the run's thread count (the tracker uses at most 2).
FrontendOptions frontendOptions(const Params& section, uint64_t seed, int threads);

}  // namespace rsvio
