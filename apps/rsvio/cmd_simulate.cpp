// rsvio simulate --config FILE --out DIR [--seed N] [--set key=value ...] [--threads N]
// Writes a synthetic rolling-shutter visual-inertial dataset in the EuRoC/ASL layout plus truth.json
// (framework/include/rsvio/sim/simulator.h). Progress goes to stderr; a one-line summary at the end.
#include <chrono>
#include <filesystem>
#include <cstdio>
#include <iostream>
#include <optional>
#include <unistd.h>

#include "commands.h"
#include "rsvio/core/error.h"
#include "rsvio/plugin/host.h"
#include "rsvio/sim/simulator.h"

namespace rsvio::app {

namespace {

struct SimulateOptions {
  std::string config;
  std::string out;
  int64_t seed = -1;
  int threads = 0;
  std::vector<std::string> sets;
};

int runSimulate(const SimulateOptions& o, const GlobalOptions& g) {
  PluginHost host(PluginHost::defaultSearchPath(g.plugin_path));
  std::vector<std::string> sets = o.sets;
  if (o.threads > 0) sets.push_back("threads=" + std::to_string(o.threads));
  const std::optional<int64_t> seed = o.seed >= 0 ? std::optional<int64_t>(o.seed) : std::nullopt;
  const nlohmann::json effective = sim::loadSimConfig(o.config, sets, seed, host);
  // The output folder first: one that cannot be made is said before any progress line.
  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  if (ec) throw Error(o.out + ": cannot create output folder (" + ec.message() + ")");
  sim::Simulator simulator(effective, host);
  const auto& s = simulator.settings();
  if (g.verbosity > 0) {
    std::string effects;
    for (const auto& [name, slot] : effective.at("effects").items()) effects += (effects.empty() ? "" : ", ") + name;
    std::fprintf(stderr, "rsvio simulate: %s, %dx%d at %g Hz, %.1f s, %zu images, seed %llu, effects: %s\n",
                 o.config.c_str(), s.sensor.camera.width, s.sensor.camera.height, s.sensor.camera.rate_hz,
                 s.motion.duration_s, simulator.frameStamps().size(), static_cast<unsigned long long>(s.seed),
                 effects.empty() ? "none" : effects.c_str());
  }
  double last_print = -1.0;
  const bool tty = isatty(fileno(stderr)) != 0;  // a log file gets one line per update, a terminal one line
  auto progress = [&](const sim::SimProgress& p) {
    if (g.verbosity <= 0) return;
    if (p.stage == "scene" && p.done == 0) {
      std::fprintf(stderr, "  building the scene ...\n");
    } else if (p.stage == "frames") {
      if (p.elapsed_s - last_print < (tty ? 0.5 : 5.0) && p.done != p.total) return;
      last_print = p.elapsed_s;
      std::fprintf(stderr, "%s  images %lld/%lld  %.1f s%s", tty ? "\r" : "", static_cast<long long>(p.done),
                   static_cast<long long>(p.total), p.elapsed_s, tty && p.done != p.total ? "" : "\n");
    }
  };
  const auto t0 = std::chrono::steady_clock::now();
  simulator.write(o.out, progress);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (g.verbosity > 0) {
    const auto st = simulator.motionStats();
    std::fprintf(stderr,
                 "rsvio simulate: wrote %s in %.1f s (path %.1f m, mean %.2f m/s, %.0f deg/s, %.2f m/s^2, %.0f deg/s^2)\n",
                 o.out.c_str(), secs, st.path_length_m, st.mean_speed_m_s, st.mean_rot_speed_deg_s, st.mean_accel_m_s2,
                 st.mean_rot_accel_deg_s2);
  }
  return 0;
}

}  // namespace

void addSimulateCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r) {
  auto opts = std::make_shared<SimulateOptions>();
  auto* sub = root.add_subcommand("simulate", "write a synthetic rolling-shutter visual-inertial dataset (EuRoC layout + truth.json)");
  sub->add_option("--config", opts->config, "simulation config, e.g. configs/sim/rs.json")->required();
  sub->add_option("--out", opts->out, "output folder")->required()->check(NonEmpty("output folder"));
  sub->add_option("--seed", opts->seed, "seed of every random stream (overrides the config's)")->check(CLI::NonNegativeNumber);
  sub->add_option("--set", opts->sets, "override one config key, e.g. --set motion.duration_s=10")->take_all();
  sub->add_option("--threads", opts->threads, "worker threads (same output for any count)")->check(CLI::PositiveNumber);
  sub->callback([opts, &g, &r] { r.exit_code = runSimulate(*opts, g); });
}

}  // namespace rsvio::app
