// The run loop behind `rsvio run` and `rsvio demo` (contract in rsvio/pipeline/run.h): validate the
// config, open the source, feed IMU samples and frames to rsvio::Odometry in time order with progress
// lines, write the user contract's files (also after a failure) and evaluate against ground truth.
#include "rsvio/pipeline/run.h"

#include <signal.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>

#include "rsvio/config/config.h"
#include "rsvio/config/validate.h"
#include "rsvio/core/error.h"
#include "rsvio/core/time.h"
#include "rsvio/eval/eval_output.h"
#include "rsvio/eval/evaluate_files.h"
#include "rsvio/imu/inertial_options.h"
#include "rsvio/interfaces/data_source.h"
#include "rsvio/io/diagnostics_log.h"
#include "rsvio/io/ply.h"
#include "rsvio/io/trajectory.h"
#include "rsvio/plugin/host.h"
#include "rsvio/system/odometry.h"

namespace fs = std::filesystem;

namespace rsvio {

namespace {

using Clock = std::chrono::steady_clock;

volatile std::sig_atomic_t g_interrupt_signal = 0;

extern "C" void onRunInterrupt(int sig) {
  if (g_interrupt_signal != 0) {
    // Second signal: the default action, now (outputs are atomic, so nothing is left half-written).
    ::signal(sig, SIG_DFL);
    ::raise(sig);
    return;
  }
  g_interrupt_signal = sig;
}

// Removes what an earlier run left in `out` (report.json first), so no stale file outlives its run.
void cleanRunFolder(const std::string& out) {
  std::error_code ec;
  if (!fs::is_directory(out, ec)) return;
  for (const auto& name : runOutputFiles()) {
    fs::remove(fs::path(out) / name, ec);
    if (ec) throw Error((fs::path(out) / name).string() + ": cannot remove the earlier run's file: " + ec.message());
  }
  fs::remove_all(fs::path(out) / "figures", ec);
  // Temporaries of a killed run: "<output>.tmp-<pid>".
  std::vector<fs::path> stale;
  for (const auto& e : fs::directory_iterator(out, ec)) {
    const std::string n = e.path().filename().string();
    for (const auto& name : runOutputFiles())
      if (n.rfind(name + ".tmp-", 0) == 0) stale.push_back(e.path());
  }
  for (const auto& p : stale) fs::remove(p, ec);
}

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// diagnostics.bin and points.ply are written while the run goes (issue 16: a long run's memory stays
// flat): the diagnostics rows and the points that left the window are taken from the estimator after
// every frame and appended to the files' temporaries (DiagnosticsWriter, PlyStreamWriter), which
// close() completes and renames with the other outputs, so the final names appear only complete.
// Without output.diagnostics / output.points they are taken and dropped. An I/O error becomes a
// warning and that file is not written (as for every output).
class OutputStreams {
 public:
  OutputStreams(Odometry& odo, const std::string& out, const nlohmann::json& cfg, std::vector<std::string>& warnings)
      : odo_(odo), warnings_(warnings) {
    if (cfg.at("output").at("diagnostics").get<bool>()) {
      const DiagnosticsLog& d = odo.diagnostics();
      guarded("diagnostics.bin", [&] {
        diag_ = std::make_unique<DiagnosticsWriter>((fs::path(out) / "diagnostics.bin").string(), d.width, d.height,
                                                    d.line_delay_s);
      });
    }
    if (cfg.at("output").at("points").get<bool>())
      guarded("points.ply",
              [&] { ply_ = std::make_unique<io::PlyStreamWriter>((fs::path(out) / "points.ply").string()); });
  }
  // What the estimator made since the last call goes to the files (or is dropped). The buffers keep
  // their capacity: bounded by what one frame makes.
  void take() {
    odo_.takeDiagnostics(&rows_);
    if (diag_ && !rows_.empty() && !guarded("diagnostics.bin", [&] { diag_->append(rows_); })) diag_.reset();
    rows_.clear();
    odo_.takePoints(&points_);
    if (ply_ && !points_.empty() && !guarded("points.ply", [&] { appendPoints(points_); })) ply_.reset();
    points_.clear();
  }
  // points.ply complete: the points taken, then those still in the estimator (its window's).
  void closePoints() {
    take();
    if (!ply_) return;
    guarded("points.ply", [&] {
      appendPoints(odo_.points());
      ply_->close();
    });
    ply_.reset();
  }
  // diagnostics.bin complete: the rows taken, then the IMU rows.
  void closeDiagnostics() {
    take();
    if (!diag_) return;
    guarded("diagnostics.bin", [&] { diag_->close(odo_.diagnostics().imu, odo_.diagnostics().tracks); });
    diag_.reset();
  }

 private:
  bool guarded(const char* what, const std::function<void()>& f) {
    try {
      f();
      return true;
    } catch (const std::exception& e) {
      warnings_.push_back(std::string("could not write ") + what + ": " + e.what());
      return false;
    }
  }
  void appendPoints(const std::vector<MapPoint>& points) {
    for (const MapPoint& p : points) ply_->append(p.p_w.cast<double>(), p.intensity);
  }

  Odometry& odo_;
  std::vector<std::string>& warnings_;
  std::unique_ptr<DiagnosticsWriter> diag_;
  std::unique_ptr<io::PlyStreamWriter> ply_;
  std::vector<ObservationRow> rows_;
  std::vector<MapPoint> points_;
};

// Writes everything the odometry has, even after a failure. Returns problems as warnings.
void writeOutputs(const Odometry& odo, const std::string& out, OutputStreams& streams,
                  std::vector<std::string>& warnings) {
  auto guarded = [&](const char* what, const std::function<void()>& f) {
    try {
      f();
    } catch (const std::exception& e) {
      warnings.push_back(std::string("could not write ") + what + ": " + e.what());
    }
  };
  guarded("trajectory.tum", [&] { io::writeTum((fs::path(out) / "trajectory.tum").string(), odo.frameTrajectory()); });
  guarded("keyframes.tum",
          [&] { io::writeTum((fs::path(out) / "keyframes.tum").string(), odo.keyframeTrajectory()); });
  guarded("states.csv", [&] { writeStates(odo.states(), (fs::path(out) / "states.csv").string()); });
  streams.closePoints();       // with output.points: points.ply, written during the run, now complete
  streams.closeDiagnostics();  // with output.diagnostics: diagnostics.bin likewise
}

// ATE on keyframes (conventions.md: report.json's ATE is on keyframes, paper eq. 35).
void evaluate(const std::string& data_dir, const std::string& out, Report& report) {
  if (!io::findDatasetGroundTruth(data_dir)) return;
  const std::string est = (fs::path(out) / "keyframes.tum").string();
  try {
    eval::FileEvalRequest req;
    req.dataset_dir = data_dir;
    req.est_path = est;
    auto outcome = eval::evaluateFiles(req);
    ReportEval e;
    e.ate_rmse_m = outcome.result.ate_m.rmse;
    e.align = eval::alignModeName(outcome.result.alignment.mode);
    e.details = eval::evalToJson(outcome.result, outcome.context);
    e.details["on"] = "keyframes";
    report.eval = e;
  } catch (const std::exception& ex) {
    report.warnings.push_back(std::string("evaluation skipped: ") + ex.what());
  }
}

}  // namespace

void installInterruptHandler(void (*handler)(int)) {
  struct sigaction sa {};
  sa.sa_handler = handler;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

void installRunInterruptHandlers() { installInterruptHandler(onRunInterrupt); }

int runInterruptSignal() { return g_interrupt_signal; }

void requestRunInterrupt(int sig) { g_interrupt_signal = sig; }

const std::vector<std::string>& runOutputFiles() {
  // report.json first: while the others are removed, no report claims them.
  static const std::vector<std::string> files{"report.json",    "config.json", "trajectory.tum", "keyframes.tum",
                                              "states.csv",     "points.ply",  "diagnostics.bin", "index.html"};
  return files;
}

nlohmann::json loadRunConfig(const std::string& path, const std::vector<std::string>& sets, PluginHost& host) {
  nlohmann::json raw = loadConfigWithSets(path, sets);
  return validateConfig(raw, runConfigSchema(), host, path, sets);  // problems of a --set blame it
}

RunResult runPipeline(const RunRequest& request, PluginHost& host) {
  RunResult result;
  nlohmann::json cfg = loadRunConfig(request.config_path, request.sets, host);
  if (request.seed >= 0) cfg["seed"] = request.seed;
  if (cfg["name"].get<std::string>().empty()) cfg["name"] = fs::path(request.config_path).stem().string();
  result.effective_config = cfg;
  result.out_dir = request.out_dir;

  if (request.out_dir.empty()) throw ConfigError("--out: empty output folder name; give a folder to write the run into");
  // The dataset is opened before the output folder is created: a wrong --data leaves nothing behind.
  auto source = host.create<DataSource>(cfg["source"]["plugin"], slotParams(cfg, "source"), "source");
  source->open(request.data_dir);

  std::error_code ec;
  fs::create_directories(request.out_dir, ec);
  if (ec) throw Error(request.out_dir + ": cannot create output folder: " + ec.message());
  if (!fs::is_directory(request.out_dir, ec))
    throw Error(request.out_dir + ": cannot create output folder: a file of that name exists");
  cleanRunFolder(request.out_dir);
  writeConfig(cfg, (fs::path(request.out_dir) / "config.json").string());
  const SensorSetup& sensors = source->sensors();

  Report& report = result.report;
  report.dataset = fs::absolute(request.data_dir).lexically_normal().string();
  report.config = cfg["name"];
  report.seed = cfg["seed"];
  report.threads = cfg["threads"];
  report.camera_rate_hz = sensors.camera.rate_hz;
  for (const auto& w : source->warnings()) report.warnings.push_back(w);

  const auto t_start = Clock::now();
  const double rate = sensors.camera.rate_hz > 0 ? sensors.camera.rate_hz : 20.0;
  {  // The odometry and the dataset live until the outputs are written; evaluation runs without them.
    Odometry odo(cfg, host, sensors);
    OutputStreams streams(odo, request.out_dir, cfg, report.warnings);
    // IMU samples are streamed from the dataset, not held: memory stays flat on long recordings.
    std::unique_ptr<ImuReader> imu = sensors.has_imu ? source->imuReader() : nullptr;
    ImuSample imu_next;
    // The first sample is read inside the loop's guard, like every other, so a file that changed since
    // open() fails the run with report.json written, not the process.
    bool imu_pending = static_cast<bool>(imu), imu_primed = false;
    const size_t n = source->numFrames();
    // IMU samples up to half a frame past the frame's time on the IMU clock (more is harmless).
    const double offset_s = inertialOptionsFromConfig(cfg).assumedTimeOffsetS(sensors.camera);
    const int64_t lookahead_ns = static_cast<int64_t>(0.5e9 / rate) + sToNs(std::abs(offset_s));
    auto last_print = Clock::now();
    long processed = 0;
    auto interrupted = [&] {
      if (runInterruptSignal() == 0) return false;
      report.status = "interrupted";
      report.error = std::string("interrupted by ") + (runInterruptSignal() == SIGTERM ? "SIGTERM" : "SIGINT") +
                     " after " + std::to_string(processed) + " of " + std::to_string(n) + " frames";
      return true;
    };
    for (size_t i = 0; i < n && !odo.failed(); ++i) {
      if (interrupted()) break;
      const int64_t t_f = source->frameTime(i);
      Frame frame;
      try {
        if (!imu_primed) {
          imu_pending = imu_pending && imu->next(imu_next);
          imu_primed = true;
        }
        while (imu_pending && imu_next.t_ns <= t_f + lookahead_ns) {
          odo.addImu(imu_next);
          imu_pending = imu->next(imu_next);
        }
        frame = source->readFrame(i);
      } catch (const Error& e) {
        report.status = "failed";
        report.error = e.what();
        break;
      }
      FrameStatus st;
      try {
        st = odo.addFrame(frame);  // throws DataError for a frame that does not fit the calibration
      } catch (const Error& e) {
        report.status = "failed";
        report.error = e.what();
        break;
      }
      ++processed;
      streams.take();
      const bool print_now = request.verbosity >= 2 || (request.verbosity >= 1 && secondsSince(last_print) > 2.0);
      if (print_now || (request.verbosity >= 1 && i + 1 == n)) {
        const double el = secondsSince(t_start);
        std::printf("[%zu/%zu] %.1f fps (camera %.0f Hz), %ld keyframes%s%s\n", i + 1, n,
                    el > 0 ? processed / el : 0.0, rate, odo.numKeyframes(), st.message.empty() ? "" : ", ",
                    st.message.c_str());
        std::fflush(stdout);
        last_print = Clock::now();
      }
    }
    if (report.status == "ok") interrupted();  // a signal during the last frame
    if (!odo.failed() && report.status == "ok") {
      odo.finish();
    } else if (odo.failed() && report.status == "ok") {
      // A run the odometry gave up on still logs its window (diagnostics rows of the observations in it,
      // the keyframes' last states, the points): `rsvio diagnose` works from what was there when it
      // failed, also when it failed before anything was marginalised. finish() skips the optimisation of
      // a failed estimator.
      try {
        odo.finish();
      } catch (const std::exception& e) {
        report.warnings.push_back(std::string("the failed run's window could not be written out: ") + e.what());
      }
    }
    const double wall = secondsSince(t_start);
    if (odo.failed() && report.status != "interrupted") {
      report.status = "failed";
      report.error = odo.failureReason();
    }
    report.frames = processed;
    report.keyframes = odo.numKeyframes();
    report.fps = wall > 0 ? processed / wall : 0.0;
    report.realtime_factor = report.fps / rate;
    report.stage_ms = odo.stageMs();
    if (odo.usesImu()) report.scale = odo.scale();
    if (const nlohmann::json vio = odo.inertialReport(); !vio.is_null()) {
      report.extra["vio"] = vio;
      if (!odo.usesImu()) {
        std::string why = vio["status"].get<std::string>();
        if (const int n = vio.value("init_refusals", 0); n > 0)
          why += "; " + std::to_string(n) + " attempts refused since t " +
                 std::to_string(vio["init_first_refusal_at_s"].get<double>()) + " s";
        report.warnings.push_back("the visual-inertial initialisation did not succeed (" + why +
                                  "): the outputs are visual odometry, camera poses without metric scale");
      }
    }
    if (const nlohmann::json sh = odo.shutterReport(); !sh.is_null()) report.extra["shutter"] = sh;
    if (const nlohmann::json ph = odo.photometricReport(); !ph.is_null()) report.extra["photometric"] = ph;
    for (const auto& w : odo.warnings()) report.warnings.push_back(w);

    writeOutputs(odo, request.out_dir, streams, report.warnings);
  }
  source.reset();
  // A failed run is evaluated too: what it estimated before the failure is worth a figure.
  if (cfg["output"]["evaluate"].get<bool>()) evaluate(request.data_dir, request.out_dir, report);
  report.write((fs::path(request.out_dir) / "report.json").string());
  return result;
}

}  // namespace rsvio
