// The schema of `rsvio run` configs. Plugin slots validate their params against the plugin's own table;
// sections here validate against the tables of the framework subsystems that own them.
#include "rsvio/backend/backend_options.h"
#include "rsvio/config/validate.h"
#include "rsvio/frontend/frontend_options.h"
#include "rsvio/imu/inertial_options.h"

namespace rsvio {

ConfigSchema runConfigSchema() {
  ConfigSchema s;
  s.what = "run config";
  s.value("name", paramString("name", "", "name of this configuration, shown in reports and comparisons"));
  s.value("description", paramString("description", "", "one line on what this configuration is for"));
  s.value("seed", paramInt("seed", 0, 0, 2147483647, "", "estimator seed (point selection); --seed overrides"));
  s.value("threads", paramInt("threads", 2, 1, 64, "", "worker threads (results are identical for any count)"));
  s.slot("source", PluginKind::Source, "source.euroc", "dataset reader");
  s.slot("camera", PluginKind::Camera, "camera.pinhole", "projection and distortion model");
  s.slot("shutter", PluginKind::Shutter, "shutter.global", "when each row is read: global or rolling shutter");
  s.slot("solver", PluginKind::Solver, "solver.dense", "linear solver of the Gauss-Newton steps");
  s.multiSlot("photometric", PluginKind::Photometric, "photometric model terms, keyed by name");
  s.multiSlot("motion", PluginKind::Motion, "motion priors, keyed by name");
  s.section("frontend", frontendParamTable(), "photometric front end: pyramid, point selection, tracking");
  s.section("backend", backendParamTable(),
            "photometric back end: window, keyframes, marginalisation, monocular start, divergence tests");
  s.section("imu", inertialParamTable(),
            "visual-inertial estimation: IMU factors, scale and gravity, twist energy, time offset (off: VO)");
  s.section("output",
            {paramBool("render", true, "render figures and index.html at the end of the run"),
             paramBool("diagnostics", true, "write diagnostics.bin for rsvio diagnose"),
             paramBool("points", true, "write points.ply"),
             paramBool("evaluate", true, "evaluate against the dataset's ground truth when it has one")},
            "what the run writes");
  return s;
}

}  // namespace rsvio
