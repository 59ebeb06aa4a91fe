// 3D views of a run, rendered off-screen with VTK to PNG.
//
// What is drawn (all in the ground truth's world when the snapshot has errors, i.e. the estimate is
// mapped by the snapshot's alignment p_gt ~ s R p_est + t; otherwise in the estimate's own world):
// - the estimated trajectory (every frame), coloured by position error (colormap.h errorMap; plain blue
//   without ground truth), line width scaled with the image;
// - the ground-truth trajectory (black);
// - the sparse point cloud, grey levels from intensity (2nd..98th percentile stretched);
// - keyframe frusta (camera poses: body poses are composed with T_B_C when the snapshot has it);
// - a ground grid, a title (run, view, status, ATE), a legend, a colour bar for the error and, in the
//   parallel top and side views, a scale bar.
// Views: top (looking down -z, y up in the image), side (looking along +y, z up), perspective: all three
// fitted to the trajectory (estimate and ground truth), with the points cropped to its neighbourhood
// (the trajectory's box grown by half its extent) and frusta sized to the path; overview: a perspective
// of the whole scene (the bulk of the point cloud and the trajectory in it).
// A snapshot without any geometry (a failed run) still gives a picture: the first asked view's file,
// showing the reason (the other views are not written).
//
// Needs an X display: construct a viz::DisplayGuard first and check ok(). Throws rsvio::Error when VTK
// cannot render or the PNG cannot be written.
#pragma once
#include <string>
#include <vector>

#include "rsvio/io/snapshot.h"

namespace rsvio::viz {

enum class View { kTop, kSide, kPerspective, kOverview };
const char* viewName(View v);  // "top", "side", "perspective", "overview"

struct SceneOptions {
  int width = 1280;
  int height = 960;
  std::vector<View> views = {View::kTop, View::kSide, View::kPerspective, View::kOverview};
  bool show_points = true;
  bool show_frusta = true;
  bool show_ground_truth = true;
  int max_frusta = 30;              // evenly subsampled beyond this
  std::string file_prefix = "trajectory_";  // files are <out_dir>/<prefix><view>.png
};

// Renders every asked view; returns the written files in the order of options.views (one file when
// there is nothing to draw).
std::vector<std::string> renderScenes(const io::Snapshot& snapshot, const SceneOptions& options,
                                      const std::string& out_dir);

}  // namespace rsvio::viz
