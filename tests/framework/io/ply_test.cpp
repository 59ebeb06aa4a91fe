// points.ply: write/read round trip, and files from other tools (property order, binary, colour).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "rsvio/core/error.h"
#include "rsvio/io/ply.h"

namespace rsvio::io {
namespace {
namespace fs = std::filesystem;

fs::path tmpFile(const std::string& name) {
  return fs::temp_directory_path() / ("rsvio_ply_" + std::to_string(::getpid()) + "_" + name);
}

TEST(Ply, RoundTripKeepsPositionsAndIntensity) {
  PointCloud pc;
  pc.p_W = {{1.5, -2.25, 3.125}, {1e-4, 123456.7, -0.5}, {0, 0, 0}};
  pc.intensity = {0.f, 254.5f, std::nanf("")};
  const auto p = tmpFile("rt.ply");
  writePly(p.string(), pc);
  std::ifstream f(p);
  std::string first;
  std::getline(f, first);
  EXPECT_EQ(first, "ply");
  const PointCloud back = readPly(p.string());
  ASSERT_EQ(back.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    // Written as float: relative precision of a float.
    EXPECT_NEAR((back.p_W[i] - pc.p_W[i]).norm(), 0.0, 1e-6 * (1 + pc.p_W[i].norm())) << i;
  }
  EXPECT_FLOAT_EQ(back.intensity[0], 0.f);
  EXPECT_FLOAT_EQ(back.intensity[1], 254.5f);
  EXPECT_TRUE(std::isnan(back.intensity[2]));
  fs::remove(p);
}

TEST(Ply, EmptyCloudAndMismatchedSizes) {
  const auto p = tmpFile("empty.ply");
  writePly(p.string(), PointCloud{});
  EXPECT_EQ(readPly(p.string()).size(), 0u);
  PointCloud bad;
  bad.p_W = {{0, 0, 0}};
  EXPECT_THROW(writePly(p.string(), bad), Error);
  fs::remove(p);
}

TEST(Ply, OtherToolsAsciiWithColourAndFaces) {
  const auto p = tmpFile("colour.ply");
  std::ofstream(p) << "ply\nformat ascii 1.0\ncomment from elsewhere\nelement vertex 2\n"
                      "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                      "property double z\nproperty double y\nproperty double x\n"
                      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                      "30 60 90 3 2 1\n0 0 0 -1 -2 -3\n3 0 1 1\n";
  const PointCloud pc = readPly(p.string());
  ASSERT_EQ(pc.size(), 2u);
  EXPECT_EQ(pc.p_W[0], Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(pc.p_W[1], Eigen::Vector3d(-3, -2, -1));
  EXPECT_FLOAT_EQ(pc.intensity[0], 60.f);
  fs::remove(p);
}

TEST(Ply, BinaryLittleEndian) {
  const auto p = tmpFile("bin.ply");
  {
    std::ofstream f(p, std::ios::binary);
    f << "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
         "property float z\nproperty float intensity\nend_header\n";
    const float v[8] = {1, 2, 3, 100, -4, 5.5f, 6, 7};
    f.write(reinterpret_cast<const char*>(v), sizeof v);
  }
  const PointCloud pc = readPly(p.string());
  ASSERT_EQ(pc.size(), 2u);
  EXPECT_EQ(pc.p_W[1], Eigen::Vector3d(-4, 5.5, 6));
  EXPECT_FLOAT_EQ(pc.intensity[0], 100.f);
  fs::remove(p);
}

TEST(Ply, BadFilesNameTheLine) {
  const auto p = tmpFile("bad.ply");
  std::ofstream(p) << "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                      "end_header\n1 2 3\n4 five 6\n";
  try {
    readPly(p.string());
    FAIL() << "no exception";
  } catch (const DataError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(p.string() + ":9:"), std::string::npos) << m;
    EXPECT_NE(m.find("five"), std::string::npos) << m;
  }
  std::ofstream(p) << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n";
  EXPECT_THROW(readPly(p.string()), DataError);  // no z
  std::ofstream(p) << "ply\nformat binary_big_endian 1.0\nelement vertex 0\nend_header\n";
  EXPECT_THROW(readPly(p.string()), DataError);
  std::ofstream(p) << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                      "end_header\n1 2 3\n";
  EXPECT_THROW(readPly(p.string()), DataError);  // truncated
  EXPECT_THROW(readPly(tmpFile("missing.ply").string()), DataError);
  fs::remove(p);
}

}  // namespace
}  // namespace rsvio::io
