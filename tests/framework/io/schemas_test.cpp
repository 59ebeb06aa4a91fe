// Shared schemas: report.json, states.csv and the diagnostics log round-trip, and bad files give
// messages naming the file (and line).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "rsvio/core/error.h"
#include "rsvio/io/diagnostics_log.h"
#include "rsvio/io/report.h"
#include "rsvio/io/states.h"

namespace fs = std::filesystem;
using namespace rsvio;

namespace {
std::string tmpFile(const std::string& name) {
  return (fs::temp_directory_path() / ("rsvio_schema_" + std::to_string(::getpid()) + "_" + name)).string();
}
std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}
}  // namespace

TEST(ReportSchema, RoundTrip) {
  Report r;
  r.status = "failed";
  r.error = "diverged: energy grew 1e6x in one step";
  r.frames = 120;
  r.keyframes = 14;
  r.fps = 31.5;
  r.realtime_factor = 1.575;
  r.camera_rate_hz = 20;
  r.stage_ms = {{"tracking", 4.5}, {"ba", 21.0}};
  r.scale = 1.02;
  ReportEval e;
  e.ate_rmse_m = 0.0123;
  e.align = "sim3";
  e.details["pairs"] = 14;
  r.eval = e;
  r.dataset = "/data/x";
  r.config = "gs_vo";
  r.seed = 3;
  r.warnings = {"a warning"};
  const auto path = tmpFile("report.json");
  r.write(path);
  const Report q = Report::read(path);
  fs::remove(path);
  EXPECT_EQ(q.status, "failed");
  EXPECT_EQ(q.error, r.error);
  EXPECT_EQ(q.frames, 120);
  EXPECT_DOUBLE_EQ(q.realtime_factor, 1.575);
  EXPECT_DOUBLE_EQ(q.stage_ms.at("ba"), 21.0);
  ASSERT_TRUE(q.scale.has_value());
  ASSERT_TRUE(q.eval.has_value());
  EXPECT_DOUBLE_EQ(q.eval->ate_rmse_m, 0.0123);
  EXPECT_EQ(q.eval->align, "sim3");
  EXPECT_EQ(q.eval->details["pairs"], 14);
  EXPECT_EQ(q.warnings.size(), 1u);
  // The contract's keys are at the top level of the JSON.
  const auto j = r.toJson();
  for (const char* k : {"status", "frames", "keyframes", "fps", "realtime_factor", "stage_ms", "scale", "eval"})
    EXPECT_TRUE(j.contains(k)) << k;
}

TEST(ReportSchema, BadFilesNamed) {
  const auto path = tmpFile("bad_report.json");
  std::ofstream(path) << "{\"status\": \"maybe\"}";
  EXPECT_NE(errorOf([&] { Report::read(path); }).find("status: expected \"ok\", \"failed\" or \"interrupted\""), std::string::npos);
  std::ofstream(path) << "{not json";
  EXPECT_NE(errorOf([&] { Report::read(path); }).find(path + ": invalid JSON"), std::string::npos);
  fs::remove(path);
  EXPECT_NE(errorOf([&] { Report::read(path); }).find("cannot open"), std::string::npos);
}

TEST(StatesSchema, RoundTripAndBadLine) {
  StateRow a;
  a.t_ns = 1403715524907143168;
  a.v = {0.1, -0.2, 0.3};
  a.bg = {1e-3, 2e-3, -3e-3};
  a.ba = {0.01, 0.02, 0.03};
  a.twist << 0.5, 0.1, -0.1, 0.2, 0.3, -0.4;
  a.scale = 2.5;
  a.time_offset_ms = 14.75;
  a.line_delay_us = 58.94;
  const auto path = tmpFile("states.csv");
  writeStates({a, a}, path);
  auto rows = readStates(path);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].t_ns, a.t_ns);
  EXPECT_NEAR((rows[0].twist - a.twist).norm(), 0, 1e-8);
  EXPECT_DOUBLE_EQ(rows[1].scale, 2.5);
  EXPECT_DOUBLE_EQ(rows[1].time_offset_ms, 14.75);
  EXPECT_DOUBLE_EQ(rows[1].line_delay_us, 58.94);
  // Files written before the time_offset_ms column (17 columns) and before the line_delay_us column
  // (18) still read, with those values 0.
  std::ofstream(path, std::ios::app) << "12,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,1\n"
                                     << "13,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,1,2.5\n";
  rows = readStates(path);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_DOUBLE_EQ(rows[2].time_offset_ms, 0.0);
  EXPECT_DOUBLE_EQ(rows[2].line_delay_us, 0.0);
  EXPECT_DOUBLE_EQ(rows[3].time_offset_ms, 2.5);
  EXPECT_DOUBLE_EQ(rows[3].line_delay_us, 0.0);
  std::ofstream(path, std::ios::app) << "12,1,2\n";
  const auto msg = errorOf([&] { readStates(path); });
  EXPECT_NE(msg.find(path + ":6: expected 19 columns, found 3"), std::string::npos) << msg;
  fs::remove(path);
}

TEST(DiagnosticsSchema, RoundTripAndCorruption) {
  DiagnosticsLog log;
  log.width = 640;
  log.height = 512;
  log.line_delay_s = 58.94e-6;
  for (int i = 0; i < 100; ++i) {
    ObservationRow o;
    o.t_ns = 1000 + i;
    o.frame = i;
    o.host = i / 2;
    o.row = i - 50.f;
    o.residual = 0.5f * i;
    log.observations.push_back(o);
  }
  ImuRow im;
  im.t_i_ns = 1;
  im.t_j_ns = 2;
  im.residual[14] = 3.f;
  log.imu.push_back(im);
  const auto path = tmpFile("diag.bin");
  log.write(path);
  auto back = DiagnosticsLog::read(path);
  ASSERT_EQ(back.observations.size(), 100u);
  EXPECT_EQ(back.observations[99].frame, 99);
  EXPECT_FLOAT_EQ(back.observations[10].residual, 5.f);
  EXPECT_EQ(back.width, 640);
  EXPECT_DOUBLE_EQ(back.line_delay_s, 58.94e-6);
  ASSERT_EQ(back.imu.size(), 1u);
  EXPECT_FLOAT_EQ(back.imu[0].residual[14], 3.f);
  // Truncate: the reader says so instead of reading garbage.
  fs::resize_file(path, fs::file_size(path) - 7);
  EXPECT_NE(errorOf([&] { DiagnosticsLog::read(path); }).find("truncated or corrupt"), std::string::npos);
  std::ofstream(path) << "hello";
  EXPECT_NE(errorOf([&] { DiagnosticsLog::read(path); }).find("not an rsvio diagnostics log"), std::string::npos);
  fs::remove(path);
}
