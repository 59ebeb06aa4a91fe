// EuRoC/ASL index files (contract in dataset_index.h).
#include "dataset_index.h"

#include <cinttypes>
#include <cmath>
#include <cstdio>

#include "rsvio/core/error.h"

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

namespace {
io::CsvFormat imuCsvFormat() {
  io::CsvFormat fmt;
  fmt.skip_text_header = true;
  return fmt;
}
}  // namespace

ImuCsvStream::ImuCsvStream(const std::string& csv_path, std::vector<std::string>* warnings)
    : warnings_(warnings ? *warnings : dropped_),
      csv_(csv_path,
           {"timestamp [ns]", "w_RS_S_x [rad s^-1]", "w_RS_S_y [rad s^-1]", "w_RS_S_z [rad s^-1]",
            "a_RS_S_x [m s^-2]", "a_RS_S_y [m s^-2]", "a_RS_S_z [m s^-2]"},
           imuCsvFormat()),
      nonfinite_(warnings_, "IMU samples with NaN/inf values dropped"),
      dup_(warnings_, "duplicate IMU timestamps dropped") {}

bool ImuCsvStream::next(ImuSample& out) {
  while (!done_ && csv_.next()) {
    if (&warnings_ == &dropped_) dropped_.clear();  // nobody reads them: keep nothing
    ImuSample s;
    double v[6];
    try {
      csv_.expectFieldCount();
      s.t_ns = csv_.getInt64(0);
      for (int k = 0; k < 6; ++k) v[k] = csv_.getDouble(static_cast<size_t>(k) + 1);
    } catch (const DataError& err) {
      if (!csv_.rowUnterminated()) throw;
      warnings_.push_back(csv_.size() < 7 ? truncatedMessage(csv_, 7, "sample")
                                          : std::string(err.what()) + " (last line, no newline at the end of the "
                                                                      "file: truncated write?); sample dropped");
      continue;
    }
    int bad = -1;
    for (int k = 0; k < 6 && bad < 0; ++k)
      if (!std::isfinite(v[k])) bad = k;
    if (bad >= 0) {
      const size_t f = static_cast<size_t>(bad) + 1;
      nonfinite_.add(csv_.path() + ":" + std::to_string(csv_.line()) + ":" + std::to_string(csv_.column(f)) +
                     ": field '" + csv_.fieldName(f) + "' is " + csv_.raw(f) + "; IMU sample dropped");
      continue;
    }
    if (any_) {
      if (s.t_ns < prev_t_)
        throw csv_.errorAt(0, "timestamp " + std::to_string(s.t_ns) + " ns is earlier than " + std::to_string(prev_t_) +
                                  " ns on line " + std::to_string(line_) + " (IMU timestamps must increase)");
      if (s.t_ns == prev_t_) {
        dup_.add(csv_.path() + ":" + std::to_string(csv_.line()) + ":" + std::to_string(csv_.column(0)) +
                 ": duplicate IMU timestamp " + std::to_string(s.t_ns) + " ns (also on line " + std::to_string(line_) +
                 "); sample dropped");
        continue;
      }
    }
    s.gyro_rad_s = Vec3(v[0], v[1], v[2]);
    s.accel_m_s2 = Vec3(v[3], v[4], v[5]);
    any_ = true;
    prev_t_ = s.t_ns;
    line_ = csv_.line();
    out = s;
    return true;
  }
  if (!done_) {
    done_ = true;
    nonfinite_.finish();
    dup_.finish();
    noteHeader(csv_, warnings_);
  }
  return false;
}

void ImuGapCheck::add(int64_t t_ns, long line) {
  const bool first = !any_;
  const int64_t a = prev_t_, b = t_ns;
  const long a_line = prev_line_;
  any_ = true;
  prev_t_ = t_ns;
  prev_line_ = line;
  if (first || b - a <= max_gap_ns_) return;
  char buf[200];
  std::snprintf(buf, sizeof(buf), "gap of %.1f ms in the IMU data between %s (line %ld) and %s exceeds "
                "max_imu_gap_ms = %.1f", (b - a) * 1e-6, formatStamp(a).c_str(), a_line, formatStamp(b).c_str(),
                max_gap_ns_ * 1e-6);
  if (b > t_begin_ && a < t_end_)
    throw DataError::at(path_, line, std::string(buf) +
                                         " inside the camera's time span (samples missing? raise "
                                         "params.max_imu_gap_ms to accept it)");
  outside_.add(path_ + ":" + std::to_string(line) + ": " + buf + " outside the camera's time span");
}

}  // namespace rsvio::euroc
