// EuRoC/ASL index files (contract in dataset_index.h).
#include "dataset_index.h"

#include <cinttypes>
#include <cmath>
#include <cstdio>

#include "rsvio/core/error.h"
#include "rsvio/io/csv.h"

namespace rsvio::euroc {

void WarningSink::add(const std::string& msg) {
  if (count_++ < keep_) out_.push_back(msg);
}

void WarningSink::finish() {
  if (count_ > keep_) out_.push_back("... and " + std::to_string(count_ - keep_) + " more " + summary_);
  count_ = 0;
}

std::string formatStamp(int64_t t_ns) {
  char buf[48];
  const int64_t s = t_ns / 1000000000, ns = t_ns % 1000000000;
  if (t_ns < 0 && ns != 0)
    std::snprintf(buf, sizeof(buf), "-%" PRId64 ".%09" PRId64 " s", -(t_ns / 1000000000), -ns);
  else
    std::snprintf(buf, sizeof(buf), "%" PRId64 ".%09" PRId64 " s", s, ns < 0 ? -ns : ns);
  return buf;
}

namespace {

std::string truncatedMessage(const io::CsvReader& csv, size_t want, const std::string& what) {
  return csv.path() + ":" + std::to_string(csv.line()) + ": last line is truncated (" + std::to_string(csv.size()) +
         " of " + std::to_string(want) + " fields, no newline at the end of the file); " + what + " dropped";
}

// A header without '#' is fine, but say so: were it a corrupt first row, it would vanish silently.
void noteHeader(const io::CsvReader& csv, std::vector<std::string>& warnings) {
  if (csv.skippedHeaderLine() > 0)
    warnings.push_back(csv.path() + ":" + std::to_string(csv.skippedHeaderLine()) +
                       ": no field is a number; taken as a column header and skipped");
}

}  // namespace

std::vector<CameraIndexEntry> readCameraIndex(const std::string& csv_path, std::vector<std::string>& warnings) {
  io::CsvFormat fmt;
  fmt.skip_text_header = true;  // tolerate "timestamp,filename" written without '#'
  io::CsvReader csv(csv_path, {"timestamp [ns]", "filename"}, fmt);
  std::vector<CameraIndexEntry> out;
  WarningSink dup(warnings, "duplicate image timestamps dropped");
  while (csv.next()) {
    CameraIndexEntry e;
    try {
      csv.expectFieldCount();
      e.stamp_ns = csv.getInt64(0);
      e.file = csv.getString(1);
    } catch (const DataError& err) {
      // A short last line without a newline is an interrupted write, not a malformed file.
      if (!csv.rowUnterminated()) throw;
      warnings.push_back(csv.size() < 2 ? truncatedMessage(csv, 2, "frame")
                                        : std::string(err.what()) + " (last line, no newline at the end of the "
                                                                    "file: truncated write?); frame dropped");
      continue;
    }
    e.line = csv.line();
    if (!out.empty()) {
      const CameraIndexEntry& prev = out.back();
      if (e.stamp_ns < prev.stamp_ns)
        throw csv.errorAt(0, "timestamp " + std::to_string(e.stamp_ns) + " ns is earlier than " +
                                 std::to_string(prev.stamp_ns) + " ns on line " + std::to_string(prev.line) +
                                 " (image timestamps must increase)");
      if (e.stamp_ns == prev.stamp_ns) {
        dup.add(csv.path() + ":" + std::to_string(csv.line()) + ":" + std::to_string(csv.column(0)) +
                ": duplicate image timestamp " + std::to_string(e.stamp_ns) + " ns (also on line " +
                std::to_string(prev.line) + "); frame '" + e.file + "' dropped");
        continue;
      }
    }
    out.push_back(std::move(e));
  }
  dup.finish();
  noteHeader(csv, warnings);
  if (out.empty()) throw DataError::at(csv_path, 0, "no frames listed (expected lines \"<timestamp [ns]>,<file>\")");
  return out;
}

ImuReadResult readImuCsv(const std::string& csv_path, std::vector<std::string>& warnings) {
  io::CsvFormat fmt;
  fmt.skip_text_header = true;
  io::CsvReader csv(csv_path,
                    {"timestamp [ns]", "w_RS_S_x [rad s^-1]", "w_RS_S_y [rad s^-1]", "w_RS_S_z [rad s^-1]",
                     "a_RS_S_x [m s^-2]", "a_RS_S_y [m s^-2]", "a_RS_S_z [m s^-2]"},
                    fmt);
  ImuReadResult out;
  WarningSink nonfinite(warnings, "IMU samples with NaN/inf values dropped");
  WarningSink dup(warnings, "duplicate IMU timestamps dropped");
  while (csv.next()) {
    ImuSample s;
    double v[6];
    try {
      csv.expectFieldCount();
      s.t_ns = csv.getInt64(0);
      for (int k = 0; k < 6; ++k) v[k] = csv.getDouble(static_cast<size_t>(k) + 1);
    } catch (const DataError& err) {
      if (!csv.rowUnterminated()) throw;
      warnings.push_back(csv.size() < 7 ? truncatedMessage(csv, 7, "sample")
                                        : std::string(err.what()) + " (last line, no newline at the end of the "
                                                                    "file: truncated write?); sample dropped");
      continue;
    }
    int bad = -1;
    for (int k = 0; k < 6 && bad < 0; ++k)
      if (!std::isfinite(v[k])) bad = k;
    if (bad >= 0) {
      const size_t f = static_cast<size_t>(bad) + 1;
      nonfinite.add(csv.path() + ":" + std::to_string(csv.line()) + ":" + std::to_string(csv.column(f)) +
                    ": field '" + csv.fieldName(f) + "' is " + csv.raw(f) + "; IMU sample dropped");
      continue;
    }
    if (!out.samples.empty()) {
      const int64_t prev = out.samples.back().t_ns;
      if (s.t_ns < prev)
        throw csv.errorAt(0, "timestamp " + std::to_string(s.t_ns) + " ns is earlier than " + std::to_string(prev) +
                                 " ns on line " + std::to_string(out.lines.back()) + " (IMU timestamps must increase)");
      if (s.t_ns == prev) {
        dup.add(csv.path() + ":" + std::to_string(csv.line()) + ":" + std::to_string(csv.column(0)) +
                ": duplicate IMU timestamp " + std::to_string(s.t_ns) + " ns (also on line " +
                std::to_string(out.lines.back()) + "); sample dropped");
        continue;
      }
    }
    s.gyro_rad_s = Vec3(v[0], v[1], v[2]);
    s.accel_m_s2 = Vec3(v[3], v[4], v[5]);
    out.samples.push_back(s);
    out.lines.push_back(csv.line());
  }
  nonfinite.finish();
  dup.finish();
  noteHeader(csv, warnings);
  return out;
}

void checkImuGaps(const std::string& csv_path, const ImuReadResult& imu, int64_t max_gap_ns, int64_t t_begin_ns,
                  int64_t t_end_ns, std::vector<std::string>& warnings) {
  WarningSink outside(warnings, "IMU gaps outside the camera's time span");
  for (size_t i = 1; i < imu.samples.size(); ++i) {
    const int64_t a = imu.samples[i - 1].t_ns, b = imu.samples[i].t_ns;
    if (b - a <= max_gap_ns) continue;
    char buf[200];
    std::snprintf(buf, sizeof(buf), "gap of %.1f ms in the IMU data between %s (line %ld) and %s exceeds "
                  "max_imu_gap_ms = %.1f", (b - a) * 1e-6, formatStamp(a).c_str(), imu.lines[i - 1],
                  formatStamp(b).c_str(), max_gap_ns * 1e-6);
    const bool inside = b > t_begin_ns && a < t_end_ns;
    if (inside)
      throw DataError::at(csv_path, imu.lines[i], std::string(buf) +
                                                      " inside the camera's time span (samples missing? raise "
                                                      "params.max_imu_gap_ms to accept it)");
    outside.add(csv_path + ":" + std::to_string(imu.lines[i]) + ": " + buf + " outside the camera's time span");
  }
  outside.finish();
}

}  // namespace rsvio::euroc
