// What a 3D view shows, computed from a snapshot without VTK (so it can be reasoned about and tested
// apart from rendering). All positions in the display world (see scene.h).
#pragma once
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "rsvio/io/snapshot.h"

namespace rsvio::viz::detail {

struct Frustum {
  Eigen::Matrix3d R_W_C = Eigen::Matrix3d::Identity();  // camera axes in the display world
  Eigen::Vector3d p_W_C = Eigen::Vector3d::Zero();
};

struct SceneGeometry {
  std::vector<Eigen::Vector3d> est;
  std::vector<double> est_err;          // same size as est; NaN without ground truth
  double err_max = 0;                   // colour scale top (max error)
  std::vector<Eigen::Vector3d> gt;
  std::vector<Eigen::Vector3d> points;
  std::vector<double> point_shade;      // [0, 1] per point
  std::vector<bool> point_near;         // per point: inside the trajectory's neighbourhood (near_bounds)
  std::vector<Frustum> frusta;
  double frustum_size = 0.1;            // depth of a frustum, display units: sized to the path
  Eigen::AlignedBox3d bounds;           // what the trajectory views frame: the trajectory (and ground truth)
  Eigen::AlignedBox3d near_bounds;      // bounds grown by half the trajectory's extent: points shown there
  Eigen::AlignedBox3d scene_bounds;     // the overview: trajectory and the bulk of the point cloud
  std::string unit = "m";               // "m" when metric, "units" for an unaligned VO run
  std::string align_label;              // e.g. "Sim(3)-aligned on keyframes"
  std::string message;                  // set when there is nothing to draw: why

  bool empty() const { return est.empty() && gt.empty() && points.empty(); }
};

SceneGeometry buildSceneGeometry(const io::Snapshot& s, bool points, bool frusta, bool ground_truth, int max_frusta);

}  // namespace rsvio::viz::detail
