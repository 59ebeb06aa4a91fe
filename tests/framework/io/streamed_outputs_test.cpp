// The outputs a run streams (issue 16): DiagnosticsWriter (io/diagnostics_log.h) and PlyStreamWriter
// (io/ply.h) give the bytes of DiagnosticsLog::write and writePly; the final file appears only at
// close(); an abandoned writer leaves nothing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>

#include "rsvio/core/error.h"
#include "rsvio/io/atomic_file.h"
#include "rsvio/io/diagnostics_log.h"
#include "rsvio/io/ply.h"

namespace fs = std::filesystem;
using namespace rsvio;

namespace {

std::string tmpDir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("rsvio_diag_writer_" + std::to_string(::getpid())) / name;
  fs::create_directories(d);
  return d.string();
}

std::string bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

DiagnosticsLog sampleLog(int n) {
  DiagnosticsLog log;
  log.width = 320;
  log.height = 256;
  log.line_delay_s = 29.5e-6;
  for (int i = 0; i < n; ++i) {
    ObservationRow o;
    o.t_ns = 5000 + 50 * i;
    o.frame = i;
    o.host = i / 3;
    o.u = 0.25f * i;
    o.residual = -0.5f * i;
    log.observations.push_back(o);
  }
  ImuRow im;
  im.t_i_ns = 7;
  im.t_j_ns = 9;
  im.whitened[3] = 1.5f;
  log.imu.push_back(im);
  for (int i = 0; i < 3; ++i) {
    TrackRow t;
    t.t_ns = 100 + i;
    t.frame = i + 1;
    t.prev_frame = i;
    t.intensity_prev = 10.f * i;
    t.intensity = 10.f * i + 0.5f;
    log.tracks.push_back(t);
  }
  return log;
}

}  // namespace

TEST(DiagnosticsWriter, StreamedRowsGiveTheBytesOfTheWholeLog) {
  const std::string dir = tmpDir("same_bytes");
  const DiagnosticsLog log = sampleLog(1000);
  const std::string whole = dir + "/whole.bin", streamed = dir + "/streamed.bin";
  log.write(whole);
  {
    DiagnosticsWriter w(streamed, log.width, log.height, log.line_delay_s);
    size_t i = 0;
    for (size_t chunk : {0, 1, 10, 300, 689}) {  // uneven chunks, an empty one
      w.append(log.observations.data() + i, chunk);
      i += chunk;
    }
    ASSERT_EQ(i, log.observations.size());
    EXPECT_EQ(w.numObservations(), 1000u);
    EXPECT_FALSE(fs::exists(streamed)) << "the final name appears only at close()";
    EXPECT_TRUE(fs::exists(io::atomicTempPath(streamed)));
    w.close(log.imu, log.tracks);
  }
  EXPECT_FALSE(fs::exists(io::atomicTempPath(streamed)));
  EXPECT_EQ(bytes(streamed), bytes(whole));
  const DiagnosticsLog back = DiagnosticsLog::read(streamed);
  ASSERT_EQ(back.observations.size(), 1000u);
  EXPECT_FLOAT_EQ(back.observations[999].residual, -499.5f);
  ASSERT_EQ(back.imu.size(), 1u);
  EXPECT_FLOAT_EQ(back.imu[0].whitened[3], 1.5f);
  ASSERT_EQ(back.tracks.size(), 3u);
  EXPECT_EQ(back.tracks[2].prev_frame, 2);
  EXPECT_FLOAT_EQ(back.tracks[2].intensity, 20.5f);
  fs::remove_all(dir);
}

// A version-2 log (before the track rows) is still read: the version-3 file without its track header
// and rows, and the version field set to 2.
TEST(DiagnosticsLog, AVersionTwoFileIsReadWithoutTrackRows) {
  const std::string dir = tmpDir("version2");
  DiagnosticsLog log = sampleLog(20);
  log.write(dir + "/v3.bin");
  std::string b = bytes(dir + "/v3.bin");
  const size_t track_head = 16, track_rows = 3 * sizeof(TrackRow);
  const size_t head = b.size() - track_head - 20 * sizeof(ObservationRow) - sizeof(ImuRow) - track_rows;
  std::string v2 = b.substr(0, head) + b.substr(head + track_head, b.size() - head - track_head - track_rows);
  v2[8] = 2;
  std::ofstream(dir + "/v2.bin", std::ios::binary) << v2;
  const DiagnosticsLog back = DiagnosticsLog::read(dir + "/v2.bin");
  EXPECT_EQ(back.observations.size(), 20u);
  EXPECT_EQ(back.imu.size(), 1u);
  EXPECT_TRUE(back.tracks.empty());
  v2[8] = 1;
  std::ofstream(dir + "/v1.bin", std::ios::binary) << v2;
  EXPECT_THROW(DiagnosticsLog::read(dir + "/v1.bin"), DataError);
  fs::remove_all(dir);
}

TEST(DiagnosticsWriter, AnAbandonedWriterLeavesNoFile) {
  const std::string dir = tmpDir("abandoned");
  const std::string path = dir + "/diagnostics.bin";
  std::ofstream(path) << "the earlier complete file";
  {
    DiagnosticsWriter w(path, 320, 256, 0.0);
    w.append(sampleLog(10).observations);
  }  // no close(): an exception unwound the run
  EXPECT_FALSE(fs::exists(io::atomicTempPath(path)));
  EXPECT_EQ(bytes(path), "the earlier complete file") << "an abandoned stream never touches the final name";
  fs::remove_all(dir);
}

TEST(DiagnosticsWriter, AnUnwritableFolderIsAnError) {
  EXPECT_THROW(DiagnosticsWriter("/nonexistent_rsvio_dir/diagnostics.bin", 1, 1, 0.0), Error);
}

TEST(PlyStreamWriter, StreamedPointsGiveTheBytesOfWritePly) {
  const std::string dir = tmpDir("ply");
  io::PointCloud cloud;
  for (int i = 0; i < 500; ++i) {
    cloud.p_W.emplace_back(0.1 * i, -1.0 / (i + 1), 3.0 + 1e-7 * i);
    cloud.intensity.push_back(i % 7 == 0 ? std::numeric_limits<float>::quiet_NaN() : 0.5f * i);
  }
  const std::string whole = dir + "/whole.ply", streamed = dir + "/streamed.ply";
  io::writePly(whole, cloud);
  {
    io::PlyStreamWriter w(streamed);
    for (size_t i = 0; i < cloud.size(); ++i) w.append(cloud.p_W[i], cloud.intensity[i]);
    EXPECT_EQ(w.size(), 500u);
    EXPECT_FALSE(fs::exists(streamed)) << "the final name appears only at close()";
    w.close();
  }
  EXPECT_EQ(bytes(streamed), bytes(whole));
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
  // No points: a valid empty cloud, as writePly writes it.
  io::writePly(whole, io::PointCloud());
  {
    io::PlyStreamWriter w(streamed);
    w.close();
  }
  EXPECT_EQ(bytes(streamed), bytes(whole));
  // Abandoned: nothing left, the earlier file untouched.
  {
    io::PlyStreamWriter w(streamed);
    w.append(cloud.p_W[0], 1.f);
  }
  EXPECT_EQ(bytes(streamed), bytes(whole));
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
  fs::remove_all(dir);
}
