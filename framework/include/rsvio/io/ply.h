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
#include <iosfwd>
#include <memory>
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

// Writes points.ply while a run makes its points, so a long run need not hold them (issue 16): the
// vertex lines go to a body temporary ("<path>.tmp-<pid>.body") as they are appended; close() writes
// the header with the count and copies the body into the atomic temporary (atomic_file.h), then renames
// it to `path`. The file is the one writePly gives for the same points, byte for byte.
// - Until close() succeeds, `path` is not touched; a killed process leaves at most the temporaries
//   (both start with "<path>.tmp-", which rsvio run removes from its folder).
// - Destroyed without close(), or after an I/O error, the temporaries are removed.
class PlyStreamWriter {
 public:
  explicit PlyStreamWriter(const std::string& path);  // throws Error when the body cannot be created
  ~PlyStreamWriter();
  PlyStreamWriter(const PlyStreamWriter&) = delete;
  PlyStreamWriter& operator=(const PlyStreamWriter&) = delete;

  void append(const Eigen::Vector3d& p_W, float intensity);  // throws Error on I/O failure
  void close();                                              // throws Error on I/O failure; once only
  size_t size() const { return n_; }

 private:
  void abandon();
  std::string path_, body_;
  size_t n_ = 0;
  std::unique_ptr<std::ofstream> out_;
};

}  // namespace rsvio::io
