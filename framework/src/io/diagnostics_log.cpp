#include "rsvio/io/diagnostics_log.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "rsvio/core/error.h"
#include "rsvio/io/atomic_file.h"

namespace rsvio {

namespace {
constexpr char kMagic[8] = {'R', 'S', 'V', 'I', 'O', 'D', 'G', '1'};
constexpr uint32_t kVersion = 3;  // 2: ObservationRow::host_radius; 3: track rows

struct Header {
  char magic[8];
  uint32_t version;
  uint32_t obs_size;
  uint32_t imu_size;
  int32_t width;
  int32_t height;
  double line_delay_s;
  uint64_t n_obs;
  uint64_t n_imu;
};

struct TrackHeader {  // version 3
  uint32_t track_size;
  uint32_t zero;
  uint64_t n_track;
};

// Filled in place with its padding zeroed, so the file's bytes are deterministic.
void fillHeader(Header& h, int width, int height, double line_delay_s, uint64_t n_obs, uint64_t n_imu) {
  std::memset(&h, 0, sizeof(h));
  std::memcpy(h.magic, kMagic, 8);
  h.version = kVersion;
  h.obs_size = sizeof(ObservationRow);
  h.imu_size = sizeof(ImuRow);
  h.width = width;
  h.height = height;
  h.line_delay_s = line_delay_s;
  h.n_obs = n_obs;
  h.n_imu = n_imu;
}
}  // namespace

void DiagnosticsLog::write(const std::string& path) const {
  DiagnosticsWriter w(path, width, height, line_delay_s);
  w.append(observations);
  w.close(imu, tracks);
}

DiagnosticsWriter::DiagnosticsWriter(const std::string& path, int width, int height, double line_delay_s)
    : path_(path), tmp_(io::atomicTempPath(path)), width_(width), height_(height), line_delay_s_(line_delay_s) {
  out_ = std::make_unique<std::ofstream>(tmp_, std::ios::binary | std::ios::trunc);
  if (!*out_) {
    const std::string why = std::strerror(errno);
    out_.reset();
    throw Error(path_ + ": cannot write diagnostics log (" + why + ")");
  }
  Header h;
  fillHeader(h, width_, height_, line_delay_s_, 0, 0);  // the counts: written by close()
  const TrackHeader th{static_cast<uint32_t>(sizeof(TrackRow)), 0, 0};
  out_->write(reinterpret_cast<const char*>(&h), sizeof(h));
  out_->write(reinterpret_cast<const char*>(&th), sizeof(th));
  if (!*out_) {
    abandon();
    throw Error(path_ + ": write failed (diagnostics log)");
  }
}

DiagnosticsWriter::~DiagnosticsWriter() { abandon(); }

void DiagnosticsWriter::abandon() {
  if (!out_) return;
  out_->close();
  out_.reset();
  std::remove(tmp_.c_str());
}

void DiagnosticsWriter::append(const ObservationRow* rows, size_t n) {
  if (!out_) throw Error(path_ + ": diagnostics log already closed");
  if (n == 0) return;
  out_->write(reinterpret_cast<const char*>(rows), static_cast<std::streamsize>(n * sizeof(ObservationRow)));
  if (!*out_) {
    abandon();
    throw Error(path_ + ": write failed (diagnostics log)");
  }
  n_obs_ += n;
}

void DiagnosticsWriter::close(const std::vector<ImuRow>& imu, const std::vector<TrackRow>& tracks) {
  if (!out_) throw Error(path_ + ": diagnostics log already closed");
  out_->write(reinterpret_cast<const char*>(imu.data()), static_cast<std::streamsize>(imu.size() * sizeof(ImuRow)));
  out_->write(reinterpret_cast<const char*>(tracks.data()),
              static_cast<std::streamsize>(tracks.size() * sizeof(TrackRow)));
  Header h;
  fillHeader(h, width_, height_, line_delay_s_, n_obs_, imu.size());
  const TrackHeader th{static_cast<uint32_t>(sizeof(TrackRow)), 0, tracks.size()};
  out_->seekp(0);
  out_->write(reinterpret_cast<const char*>(&h), sizeof(h));
  out_->write(reinterpret_cast<const char*>(&th), sizeof(th));
  out_->flush();
  if (!*out_) {
    abandon();
    throw Error(path_ + ": write failed (diagnostics log)");
  }
  out_->close();
  const bool closed = static_cast<bool>(*out_);
  out_.reset();
  if (!closed) {
    std::remove(tmp_.c_str());
    throw Error(path_ + ": write failed (diagnostics log)");
  }
  if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(tmp_.c_str());
    throw Error(path_ + ": cannot write diagnostics log (rename: " + why + ")");
  }
}

DiagnosticsLog DiagnosticsLog::read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DataError(path + ": cannot open diagnostics log");
  Header h{};
  in.read(reinterpret_cast<char*>(&h), sizeof(h));
  if (!in || std::memcmp(h.magic, kMagic, 8) != 0) throw DataError(path + ": not an rsvio diagnostics log");
  if ((h.version != kVersion && h.version != 2) || h.obs_size != sizeof(ObservationRow) ||
      h.imu_size != sizeof(ImuRow))
    throw DataError(path + ": diagnostics log version " + std::to_string(h.version) + " not supported (expected 2 or " +
                    std::to_string(kVersion) + ")");
  TrackHeader th{static_cast<uint32_t>(sizeof(TrackRow)), 0, 0};
  if (h.version >= 3) {
    in.read(reinterpret_cast<char*>(&th), sizeof(th));
    if (!in || th.track_size != sizeof(TrackRow))
      throw DataError(path + ": truncated or corrupt diagnostics log (track header)");
  }
  const uint64_t head = sizeof(h) + (h.version >= 3 ? sizeof(th) : 0);
  in.seekg(0, std::ios::end);
  const auto size = static_cast<uint64_t>(in.tellg());
  // Row counts are checked against the file size before any product, so a corrupt count can neither
  // wrap the expected size around nor ask for a huge allocation.
  const uint64_t body = size >= head ? size - head : 0;
  if (h.n_obs > body / sizeof(ObservationRow) || h.n_imu > body / sizeof(ImuRow) ||
      th.n_track > body / sizeof(TrackRow))
    throw DataError(path + ": truncated or corrupt diagnostics log (" + std::to_string(size) + " bytes for " +
                    std::to_string(h.n_obs) + " observation rows, " + std::to_string(h.n_imu) + " IMU rows and " +
                    std::to_string(th.n_track) + " track rows)");
  const uint64_t expect =
      head + h.n_obs * sizeof(ObservationRow) + h.n_imu * sizeof(ImuRow) + th.n_track * sizeof(TrackRow);
  if (size != expect)
    throw DataError(path + ": truncated or corrupt diagnostics log (" + std::to_string(size) + " bytes, expected " +
                    std::to_string(expect) + ")");
  in.seekg(static_cast<std::streamoff>(head));
  DiagnosticsLog log;
  log.width = h.width;
  log.height = h.height;
  log.line_delay_s = h.line_delay_s;
  log.observations.resize(h.n_obs);
  log.imu.resize(h.n_imu);
  log.tracks.resize(th.n_track);
  in.read(reinterpret_cast<char*>(log.observations.data()),
          static_cast<std::streamsize>(h.n_obs * sizeof(ObservationRow)));
  in.read(reinterpret_cast<char*>(log.imu.data()), static_cast<std::streamsize>(h.n_imu * sizeof(ImuRow)));
  in.read(reinterpret_cast<char*>(log.tracks.data()), static_cast<std::streamsize>(th.n_track * sizeof(TrackRow)));
  if (!in) throw DataError(path + ": read failed");
  return log;
}

}  // namespace rsvio
