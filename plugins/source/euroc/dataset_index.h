// The index files of the EuRoC/ASL layout: mav0/camN/data.csv ("#timestamp [ns],filename") and
// mav0/imu0/data.csv (EuRoC's 7 columns: t [ns], w_RS_S_x..z [rad/s], a_RS_S_x..z [m/s^2]).
//
// What is fatal and what is a warning with the sample dropped (docs/datasets.md has the full table):
//   fatal:   unreadable file; wrong column count; a field that is not a number / integer; an empty
//            filename; a timestamp earlier than the one before it; no frames at all; an IMU gap larger
//            than max_imu_gap_ms inside the camera's time span.
//   warning: a short or unparsable LAST line without a newline (a truncated write): dropped;
//            a duplicate timestamp: the later row dropped; a NaN/inf IMU value: the sample dropped;
//            an IMU gap outside the camera's time span.
// Every message starts "file:line:" (and ":col" with the field name for a bad field).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/io/csv.h"

namespace rsvio::euroc {

struct CameraIndexEntry {
  int64_t stamp_ns = 0;   // as written in data.csv (the row the dataset stamps, see timestamp_row)
  std::string file;       // as written (relative to camN/data/)
  long line = 0;          // line in data.csv
};

// Reads camN/data.csv. Warnings are appended to `warnings`.
std::vector<CameraIndexEntry> readCameraIndex(const std::string& csv_path, std::vector<std::string>& warnings);

// Collects repeated warnings of one kind: the first `keep` verbatim, then a count.
class WarningSink {
 public:
  WarningSink(std::vector<std::string>& out, std::string summary, size_t keep = 5)
      : out_(out), summary_(std::move(summary)), keep_(keep) {}
  void add(const std::string& msg);
  void finish();  // appends "... and N more <summary>" when more than `keep` were added

 private:
  std::vector<std::string>& out_;
  std::string summary_;
  size_t keep_;
  size_t count_ = 0;
};

// Reads imu0/data.csv one kept sample at a time (bounded memory: long recordings are streamed, never
// held). Warnings are appended to `warnings` as they come (at most a few per kind, then a count when the
// stream ends); with warnings == nullptr they are dropped (a second pass over a file open() checked).
class ImuCsvStream {
 public:
  ImuCsvStream(const std::string& csv_path, std::vector<std::string>* warnings);
  bool next(ImuSample& s);              // the next kept sample; false at the end; throws DataError
  long line() const { return line_; }   // data.csv line of the sample next() returned last

 private:
  std::vector<std::string> dropped_;    // warnings when the caller wants none
  std::vector<std::string>& warnings_;
  io::CsvReader csv_;
  WarningSink nonfinite_, dup_;
  int64_t prev_t_ = 0;
  long line_ = 0;
  bool any_ = false, done_ = false;
};

// Checks the gaps between consecutive IMU samples, fed in order, against max_gap_ns: a gap overlapping
// [t_begin_ns, t_end_ns] (the camera's span on the IMU clock) throws DataError, others become warnings
// (the first few as they come, then a count on finish()).
class ImuGapCheck {
 public:
  ImuGapCheck(std::string csv_path, int64_t max_gap_ns, int64_t t_begin_ns, int64_t t_end_ns,
              std::vector<std::string>& warnings)
      : path_(std::move(csv_path)), max_gap_ns_(max_gap_ns), t_begin_(t_begin_ns), t_end_(t_end_ns),
        outside_(warnings, "IMU gaps outside the camera's time span") {}
  void add(int64_t t_ns, long line);
  void finish() { outside_.finish(); }

 private:
  std::string path_;
  int64_t max_gap_ns_, t_begin_, t_end_;
  WarningSink outside_;
  int64_t prev_t_ = 0;
  long prev_line_ = 0;
  bool any_ = false;
};

// "1403636579.763555584 s" from ns, exactly.
std::string formatStamp(int64_t t_ns);

}  // namespace rsvio::euroc
