// points.ply: the sparse point cloud a run leaves behind (user-contract.md, "Files a run writes").
//
// Contract:
// - Points are in the world frame of the run's trajectory (metres for VIO, the free scale for VO).
// - Intensity is the point's reference intensity in the host image's units (8-bit grey 0..255 for
//   8-bit data; whatever the photometric front end works in otherwise). NaN is allowed ("unknown").
// - writePly writes ASCII PLY 1.0 with one vertex element and the properties
//   "float x, float y, float z, float intensity", one point per line, 9 significant digits.
// - readPly reads ASCII and binary_little_endian PLY with a vertex element holding x, y, z (any
//   numeric type, any order, other properties ignored) and optionally intensity (or, failing that,
//   red/green/blue averaged, so PLYs from other tools load too). Other elements (faces) are skipped
//   when they come after the vertices. Bad files throw DataError "path:line: <what>".
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

namespace rsvio::io {

struct PointCloud {
  std::vector<Eigen::Vector3d> p_W;  // world-frame positions
  std::vector<float> intensity;      // same size as p_W

  size_t size() const { return p_W.size(); }
  bool empty() const { return p_W.empty(); }
};

// Throws rsvio::Error when the file cannot be written or the sizes of p_W and intensity differ.
void writePly(const std::string& path, const PointCloud& cloud);
PointCloud readPly(const std::string& path);

}  // namespace rsvio::io
