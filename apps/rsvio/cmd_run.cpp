// rsvio run --config FILE --data DIR --out DIR [--seed N] [--set key=value ...]
// Exit codes: 0 run ok; 1 the run failed (diverged, lost, unreadable frame: report.json says why);
// 2 bad input before the run started (config, dataset, plugins); 130 interrupted by SIGINT/SIGTERM (the
// outputs so far are written, report.json status "interrupted").
#include <cstdio>
#include <iostream>

#include "commands.h"
#include "render_hook.h"
#include "run_summary.h"
#include "rsvio/pipeline/run.h"
#include "rsvio/plugin/host.h"

namespace rsvio::app {

void addRunCommand(CLI::App& root, const GlobalOptions& g, CommandResult& r) {
  auto* sub = root.add_subcommand("run", "run the estimator on a dataset and write its outputs");
  static RunRequest req;
  sub->add_option("--config", req.config_path, "run config (JSON)")->required()->check(CLI::ExistingFile);
  sub->add_option("--data", req.data_dir, "dataset folder (EuRoC/ASL layout)")->required();
  sub->add_option("--out", req.out_dir, "output folder")->required()->check(NonEmpty("output folder"));
  sub->add_option("--seed", req.seed, "estimator seed (point selection); default: the config's")
      ->check(CLI::Range(0L, 2147483647L));
  sub->add_option("--set", req.sets, "override a config key: a.b.c=value")->take_all();
  sub->callback([&g, &r] {
    req.verbosity = g.verbosity;
    PluginHost host(PluginHost::defaultSearchPath(g.plugin_path));
    installRunInterruptHandlers();  // Ctrl-C / SIGTERM: stop at the next frame, keep the outputs, exit 130
    RunResult res = runPipeline(req, host);
    const Report& rep = res.report;
    printRunWarnings(rep);  // every warning report.json records, once, on stderr
    if (rep.status == "interrupted") {
      std::cerr << "rsvio run: " << rep.error << " (outputs so far in " << res.out_dir << ")\n";
      r.exit_code = kExitInterrupted;
      return;
    }
    if (res.effective_config["output"]["render"].get<bool>()) renderRunOutputs(res.out_dir, g.verbosity);
    if (rep.ok()) {
      std::printf("run ok: %ld frames, %ld keyframes, %.1f fps (realtime factor %.2f)", rep.frames, rep.keyframes,
                  rep.fps, rep.realtime_factor);
      if (rep.eval) std::printf(", ATE %.4f m (%s, keyframes)", rep.eval->ate_rmse_m, rep.eval->align.c_str());
      std::printf("\n");
      const std::string not_used = notUsedLine(rep, req.data_dir, res.effective_config["output"]["evaluate"].get<bool>());
      if (!not_used.empty()) std::printf("%s\n", not_used.c_str());
      std::printf("outputs in %s\n", res.out_dir.c_str());
      r.exit_code = kExitOk;
    } else {
      const std::string not_used = notUsedLine(rep, req.data_dir, res.effective_config["output"]["evaluate"].get<bool>());
      if (!not_used.empty()) std::printf("%s\n", not_used.c_str());  // stdout: stderr keeps its one line
      std::fflush(stdout);
      std::cerr << "rsvio run: failed: " << rep.error << " (outputs so far in " << res.out_dir << ")\n";
      r.exit_code = kExitFailed;
    }
  });
}

}  // namespace rsvio::app
