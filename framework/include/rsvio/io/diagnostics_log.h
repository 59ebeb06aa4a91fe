// The diagnostics log (diagnostics.bin): what `rsvio diagnose` needs from a run, compact and binary.
//
// One ObservationRow per point observation at its final linearisation (when the observation leaves the
// window: marginalised or at the end of the run; an outlier when the window drops it, with weight 0),
// one ImuRow per IMU factor (keyframe pair), and (version 3) one TrackRow per corner of the monocular
// start per frame-to-frame step (backend/mono_initializer.h, lastSteps()).
// Fields (float32 unless stated):
//   t_ns (int64)          capture time of the target frame's row y0, camera clock
//   frame, host (int32)   target and host frame indices (sequence positions)
//   u, v                  projected raw pixel in the target (the pattern centre)
//   row                   raw row minus y0 (v - y0): where a rolling shutter shows
//   radius                distance from the principal point, normalised by the half diagonal (vignetting)
//   host_radius           the same for the point's pixel in its host keyframe (version 2)
//   intensity             host intensity at the point (response, exposure)
//   grad_u, grad_v        target image gradient at (u, v)
//   vel_u, vel_v          pixel velocity in the target [px/s] from the frame's twist (d uv/dt)
//   residual, weight      mean pattern residual and its robust weight (0: an outlier)
//   exposure_ratio        exp(a_target - a_host) when affine brightness is estimated, else 1
// TrackRow fields: t_ns (int64, the frame's timestamp), frame and prev_frame (int32, the step's two
// frames), u, v (the corner in the frame, working image), intensity_prev and intensity (3x3 mean of the
// working image around the corner in prev_frame and in frame).
// File layout: magic "RSVIODG1", uint32 version, uint32 sizeof(ObservationRow), uint32 sizeof(ImuRow),
// int32 width, int32 height, float64 line delay, uint64 n_obs, uint64 n_imu; version 3 then adds uint32
// sizeof(TrackRow), uint32 0, uint64 n_track; then the observation, IMU and track rows, little-endian
// as on x86-64 / aarch64. Version 2 files (no track rows) are read too.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace rsvio {

#pragma pack(push, 1)
struct ObservationRow {
  int64_t t_ns = 0;
  int32_t frame = 0;
  int32_t host = 0;
  float u = 0, v = 0;
  float row = 0;
  float radius = 0;
  float host_radius = 0;
  float intensity = 0;
  float grad_u = 0, grad_v = 0;
  float vel_u = 0, vel_v = 0;
  float residual = 0;
  float weight = 0;
  float exposure_ratio = 1;
};

// The (target frame, host keyframe) pair of an observation as one key (probes and fits group by it).
inline int64_t pairKey(const ObservationRow& o) {
  return (static_cast<int64_t>(o.frame) << 32) | static_cast<uint32_t>(o.host);
}

struct ImuRow {
  int64_t t_i_ns = 0;
  int64_t t_j_ns = 0;
  std::array<float, 15> residual{};    // rotation, velocity, position, bias gyro, bias accel (eqs. 16-19)
  std::array<float, 15> whitened{};    // residual times the square-root information
};
struct TrackRow {
  int64_t t_ns = 0;
  int32_t frame = 0;
  int32_t prev_frame = 0;
  float u = 0, v = 0;
  float intensity_prev = 0;
  float intensity = 0;
};
#pragma pack(pop)

struct DiagnosticsLog {
  int width = 0;                       // raw image size of the run's camera
  int height = 0;
  double line_delay_s = 0.0;           // as modelled by the run (0: global shutter)
  std::vector<ObservationRow> observations;
  std::vector<ImuRow> imu;
  std::vector<TrackRow> tracks;        // the monocular start's corner steps (empty in version 2 files)

  void write(const std::string& path) const;               // throws Error on I/O failure (DiagnosticsWriter)
  static DiagnosticsLog read(const std::string& path);     // throws DataError on a bad file
};

// Writes a diagnostics log while it is made, so a long run need not hold its rows (issue 16): the
// observation rows go to the atomic temporary of `path` (io/atomic_file.h, "<path>.tmp-<pid>") as they
// are appended; close() adds the IMU and track rows and the header's row counts, then renames the temporary to
// `path`. The file is the one DiagnosticsLog::write gives for the same rows, byte for byte.
// - Until close() succeeds, `path` is not touched: a process killed at any moment leaves at most the
//   temporary (rsvio run removes such temporaries of an earlier run), never a truncated `path`.
// - Destroyed without close(), or after an I/O error, the temporary is removed.
// - Memory: the stream's buffer only (rows are not kept).
class DiagnosticsWriter {
 public:
  // Throws Error when the temporary cannot be created.
  DiagnosticsWriter(const std::string& path, int width, int height, double line_delay_s);
  ~DiagnosticsWriter();
  DiagnosticsWriter(const DiagnosticsWriter&) = delete;
  DiagnosticsWriter& operator=(const DiagnosticsWriter&) = delete;

  void append(const ObservationRow* rows, size_t n);  // throws Error on I/O failure
  void append(const std::vector<ObservationRow>& rows) { append(rows.data(), rows.size()); }
  // The IMU and track rows, the counts, then the rename; throws Error on I/O failure. Once only.
  void close(const std::vector<ImuRow>& imu, const std::vector<TrackRow>& tracks);
  uint64_t numObservations() const { return n_obs_; }

 private:
  void abandon();  // closes and removes the temporary
  std::string path_;
  std::string tmp_;
  int width_ = 0, height_ = 0;
  double line_delay_s_ = 0.0;
  uint64_t n_obs_ = 0;
  std::unique_ptr<std::ofstream> out_;  // open until close() or abandon()
};

}  // namespace rsvio
