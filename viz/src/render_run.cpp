// renderRun / renderCompare (render_run.h): draw what can be drawn, record what could not, never throw.
#include "rsvio/viz/render_run.h"

#include <cmath>
#include <filesystem>

#include "canvas.h"
#include "rsvio/core/error.h"

namespace rsvio::viz {
namespace fs = std::filesystem;

namespace {

// Runs one figure; a failure becomes a problem line instead of an exception.
template <class F>
void attempt(const std::string& what, RenderStatus& st, F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    st.problems.push_back(what + ": " + e.what());
  } catch (...) {
    st.problems.push_back(what + ": unknown error");
  }
}

std::string failureText(const io::Snapshot& s) {
  if (s.failed()) return "run failed" + (s.summary.error.empty() ? std::string() : ": " + s.summary.error);
  return "";
}

}  // namespace

std::vector<Panel> keyframeStatePanels(const std::vector<StateRow>& rows, bool has_scale,
                                       std::vector<std::string>* not_estimated, const nlohmann::json* dm) {
  std::vector<Panel> panels;
  if (rows.empty()) return panels;
  auto allZero = [&](auto get) {
    for (const auto& r : rows)
      if (!(get(r).array() == 0).all()) return false;
    return true;
  };
  std::vector<double> t;
  for (const auto& r : rows) t.push_back((r.t_ns - rows.front().t_ns) * 1e-9);
  const Rgb axis_colour[3] = {{214, 39, 40}, {44, 160, 44}, {31, 119, 180}};
  auto vec3 = [&](const char* title, const char* ylabel, auto get, const char* n0, const char* n1, const char* n2) {
    if (allZero([&](const StateRow& r) -> Eigen::Vector3d { return get(r); })) {
      if (not_estimated) not_estimated->push_back(title);
      return;
    }
    Panel p;
    p.title = title;
    p.y_label = ylabel;
    const char* names[3] = {n0, n1, n2};
    for (int k = 0; k < 3; ++k) {
      Series s{names[k], t, {}, axis_colour[k]};
      for (const auto& r : rows) s.y.push_back(get(r)(k));
      p.series.push_back(std::move(s));
    }
    panels.push_back(std::move(p));
  };
  vec3("Velocity (world)", "v [m/s]", [](const StateRow& r) { return r.v; }, "x", "y", "z");
  vec3("Gyroscope bias", "bg [rad/s]", [](const StateRow& r) { return r.bg; }, "x", "y", "z");
  vec3("Accelerometer bias", "ba [m/s^2]", [](const StateRow& r) { return r.ba; }, "x", "y", "z");
  const bool twist_zero = allZero([](const StateRow& r) -> Eigen::Matrix<double, 6, 1> { return r.twist; });
  if (twist_zero && not_estimated) not_estimated->push_back("Keyframe twist");
  Panel tw;
  tw.title = "Keyframe twist (per second)";
  tw.y_label = "|xi|";
  Series trans{"|translation| [unit/s]", t, {}, Rgb{31, 119, 180}};
  Series rot{"|rotation| [rad/s]", t, {}, Rgb{255, 127, 14}};
  for (const auto& r : rows) {
    trans.y.push_back(r.twist.head<3>().norm());
    rot.y.push_back(r.twist.tail<3>().norm());
  }
  tw.series = {trans, rot};
  tw.y_from_zero = true;
  if (!twist_zero) panels.push_back(std::move(tw));
  // One series over time of a scalar state.
  auto scalar = [&](const char* title, const char* ylabel, Rgb colour, double StateRow::*field) {
    Panel p;
    p.title = title;
    p.y_label = ylabel;
    Series s{"", t, {}, colour};
    for (const auto& r : rows) s.y.push_back(r.*field);
    p.series = {s};
    panels.push_back(std::move(p));
  };
  // A calibration state over time when it moved (estimated online; constant when assumed or given).
  auto calibration = [&](const char* name, const char* title, const char* ylabel, Rgb colour,
                         double StateRow::*field) {
    bool moves = false;
    for (const auto& r : rows) moves |= std::abs(r.*field - rows.front().*field) > 1e-6;
    if (moves)
      scalar(title, ylabel, colour, field);
    else if (not_estimated)
      not_estimated->push_back(name);
  };
  calibration("Time offset", "Camera-IMU time offset (t_imu = t_cam + offset)", "offset [ms]", Rgb{140, 86, 75},
              &StateRow::time_offset_ms);
  calibration("Line delay", "Rolling-shutter line delay", "line delay [us/row]", Rgb{23, 190, 207},
              &StateRow::line_delay_us);
  // The scale from the visual-inertial initialisation on (rows before it hold 0).
  Series sc{"", {}, {}, Rgb{148, 103, 189}};
  for (size_t i = 0; i < rows.size(); ++i)
    if (rows[i].scale > 0.0) {
      sc.x.push_back(t[i]);
      sc.y.push_back(rows[i].scale);
    }
  if (has_scale && !sc.x.empty()) {
    Panel p;
    p.title = "Scale (metres per visual unit)";
    p.y_label = "scale";
    p.series = {sc};
    // Dynamic marginalisation's interval, a step at each event, up to the last keyframe.
    if (dm && dm->is_object() && dm->contains("events") && dm->at("events").is_array() &&
        dm->value("interval", 0.0) > 1.0) {
      const double d = dm->at("interval").get<double>(), t_end = t.back();
      Series lo{"interval (switch when left)", {}, {}, Rgb{150, 150, 150}}, hi{"", {}, {}, Rgb{150, 150, 150}};
      Series mid{"centre", {}, {}, Rgb{200, 200, 200}};
      const nlohmann::json& ev = dm->at("events");
      for (size_t k = 0; k < ev.size(); ++k) {
        const double t0 = ev[k].value("t_s", 0.0) - rows.front().t_ns * 1e-9;
        const double t1 = k + 1 < ev.size() ? ev[k + 1].value("t_s", 0.0) - rows.front().t_ns * 1e-9 : t_end;
        const double c = ev[k].value("centre", 0.0);
        if (!(c > 0.0) || t1 < t0) continue;
        for (Series* s : {&lo, &mid, &hi}) {
          const double y = s == &lo ? c / d : (s == &hi ? c * d : c);
          s->x.insert(s->x.end(), {t0, t1});
          s->y.insert(s->y.end(), {y, y});
        }
      }
      if (!lo.x.empty()) p.series = {lo, hi, mid, sc};
    }
    panels.push_back(std::move(p));
  } else if (not_estimated)
    not_estimated->push_back("Scale");
  if (!panels.empty()) panels.back().x_label = "time since first keyframe [s]";
  return panels;
}

ResidualMapInput residualMapInput(const DiagnosticsLog& log) {
  ResidualMapInput in;
  in.image_width = log.width;
  in.image_height = log.height;
  in.obs.reserve(log.observations.size());
  for (const auto& o : log.observations) {
    if (!(o.weight > 0.f)) continue;  // an outlier the window dropped (weight 0): not a residual it fitted
    in.obs.push_back(ResidualObservation{o.t_ns, o.u, o.v, o.row, o.residual, o.weight});
  }
  return in;
}

RenderStatus renderRun(const io::Snapshot& s, const RenderOptions& o) {
  RenderStatus st;
  try {
    const fs::path run(s.run_dir);
    const fs::path out = o.out_dir.empty() ? run / "figures" : fs::path(o.out_dir);
    const fs::path index = o.index_path.empty() ? run / "index.html" : fs::path(o.index_path);
    fs::create_directories(out);
    std::vector<FigureLink> links;
    auto add = [&](const fs::path& p, const std::string& caption) {
      st.figures.push_back(p.string());
      links.push_back({p.string(), caption});
    };
    const std::string failure = failureText(s);

    // 3D views first: they are the most likely to fail, and the page should say so.
    if (o.scenes) {
      attempt("3D views", st, [&] {
        DisplayGuard guard(o.display);
        if (!guard.ok()) throw Error(guard.message());
        const auto files = renderScenes(s, o.scene, out.string());
        for (size_t i = 0; i < files.size(); ++i) {
          const View v = o.scene.views[i];
          add(files[i], files.size() < o.scene.views.size() ? std::string("3D view: nothing to draw")
                        : v == View::kOverview
                            ? std::string("3D overview: the whole scene (bulk of the point cloud) with the trajectory in it")
                            : std::string("3D, ") + viewName(v) +
                                  " view fitted to the trajectory: estimate against ground truth, coloured by error; "
                                  "points near the path; keyframes");
        }
      });
    }
    attempt("trajectory_plan.png", st, [&] {
      PlanTrajectory p;
      p.message = failure.empty() ? "no trajectory" : failure;
      if (s.errors) {
        for (const auto& e : s.errors->frames) {
          p.est_x.push_back(e.p_est_aligned.x());
          p.est_y.push_back(e.p_est_aligned.y());
          p.est_err_m.push_back(e.err_m);
        }
        const int64_t t0 = s.errors->frames.empty() ? 0 : s.errors->frames.front().t_ns - 1'000'000'000;
        const int64_t t1 = s.errors->frames.empty() ? 0 : s.errors->frames.back().t_ns + 1'000'000'000;
        for (const auto& g : s.ground_truth.poses) {
          if (g.t_ns < t0 || g.t_ns > t1) continue;
          p.gt_x.push_back(g.p_W_X.x());
          p.gt_y.push_back(g.p_W_X.y());
        }
        p.title = "Trajectory, top view (" + std::string(eval::alignModeName(s.errors->alignment.mode)) + "-aligned)";
      } else {
        const auto& tr = s.trajectory.empty() ? s.keyframes : s.trajectory;
        for (const auto& q : tr.poses) {
          p.est_x.push_back(q.p_W_X.x());
          p.est_y.push_back(q.p_W_X.y());
        }
        if (s.poseFrame() == io::PoseFrame::kCamera) p.unit = "units";
        p.title = "Trajectory, top view (no ground truth)";
      }
      const auto path = out / "trajectory_plan.png";
      renderPlanTrajectory(p, path.string(), o.figure);
      add(path, "Top view (x-y) drawn without VTK: ground truth grey, estimate coloured by error");
    });
    attempt("error_over_time.png", st, [&] {
      ErrorSeries e;
      e.message = !failure.empty() ? failure : "no ground truth to compare with";
      if (s.errors && !s.errors->frames.empty()) {
        const int64_t t0 = s.errors->frames.front().t_ns;
        for (const auto& f : s.errors->frames) {
          e.t_s.push_back((f.t_ns - t0) * 1e-9);
          e.err_m.push_back(f.err_m);
        }
        e.ate_rmse_m = std::isfinite(s.summary.ate_rmse_m) ? s.summary.ate_rmse_m : s.errors->ate_m.rmse;
        e.title = "Position error over time (" + std::string(eval::alignModeName(s.errors->alignment.mode)) +
                  " alignment on " + s.errors->aligned_on + ")";
      }
      const auto path = out / "error_over_time.png";
      renderErrorOverTime(e, path.string(), o.figure);
      add(path, "Position error of every frame after alignment; dashed: keyframe ATE RMSE");
    });
    if (!s.states.empty()) {
      attempt("states.png", st, [&] {
        const auto path = out / "states.png";
        std::vector<std::string> missing;
        const nlohmann::json* dm = nullptr;
        if (s.report.contains("extra") && s.report["extra"].is_object() && s.report["extra"].contains("vio") &&
            s.report["extra"]["vio"].is_object() && s.report["extra"]["vio"].contains("dynamic_marginalization"))
          dm = &s.report["extra"]["vio"]["dynamic_marginalization"];
        auto panels = keyframeStatePanels(s.states, std::isfinite(s.summary.scale), &missing, dm);
        std::string not_est;
        for (const auto& m : missing) not_est += (not_est.empty() ? "" : ", ") + m;
        // The figure itself says what has no panel, not only the page's caption.
        if (!panels.empty() && !not_est.empty()) panels.back().x_label += "      (not estimated, no panel: " + not_est + ")";
        std::string shown;
        for (const auto& p : panels) shown += (shown.empty() ? "" : ", ") + p.title;
        // About 0.4 of a figure's height per panel (at least one figure high).
        const int h = std::max(o.figure.height, static_cast<int>(o.figure.height * 0.42 * panels.size()));
        renderPanels(panels, "this run estimated no keyframe state besides the pose (not estimated: " + not_est + ")",
                     path.string(), FigureSize{o.figure.width, panels.empty() ? o.figure.height : h});
        add(path, panels.empty() ? "Keyframe states: none estimated besides the pose (" + not_est + ": not estimated)"
                                 : "Keyframe states this run estimated: " + shown +
                                       (not_est.empty() ? "" : ". Not estimated (no panel): " + not_est));
      });
    }
    std::optional<ResidualMapInput> residuals = o.residuals;
    if (!residuals && !s.diagnostics_path.empty()) {
      attempt("diagnostics.bin", st, [&] { residuals = residualMapInput(DiagnosticsLog::read(s.diagnostics_path)); });
    }
    if (residuals) {
      attempt("residual_row_time.png", st, [&] {
        const auto path = out / "residual_row_time.png";
        renderResidualRowTime(*residuals, path.string(), o.figure);
        add(path, "Mean |residual| by raw image row and time (a rolling shutter shows away from the middle row)");
      });
      attempt("residual_image.png", st, [&] {
        const auto path = out / "residual_image.png";
        renderResidualImage(*residuals, path.string(), o.figure);
        add(path, "Mean |residual| over the image");
      });
    }
    attempt("index.html", st, [&] {
      writeRunIndex(index.string(), s, links, st.problems);
      st.index_html = index.string();
    });
  } catch (const std::exception& e) {
    st.problems.push_back(e.what());
  }
  st.ok = st.problems.empty();
  st.message = st.ok ? "rendered " + std::to_string(st.figures.size()) + " figures and " + st.index_html
                     : "render incomplete (" + std::to_string(st.figures.size()) + " figures): " + st.problems.front();
  return st;
}

RenderStatus renderRunFolder(const std::string& run_dir, const RenderOptions& options) {
  try {
    return renderRun(io::readSnapshot(run_dir), options);
  } catch (const std::exception& e) {
    RenderStatus st;
    st.problems.push_back(e.what());
    st.message = std::string("render failed: ") + e.what();
    return st;
  }
}

RenderStatus renderCompare(const std::vector<CompareRun>& runs, const CompareRenderOptions& o) {
  RenderStatus st;
  try {
    const fs::path out(o.out_dir);
    const fs::path figs = o.figures_dir.empty() ? out / "figures" : fs::path(o.figures_dir);
    fs::create_directories(figs);
    CompareGrid g = makeCompareGrid(runs);
    g.lo_m = o.lo_m;
    g.hi_m = o.hi_m;
    std::vector<FigureLink> links;
    attempt("compare_grid.png", st, [&] {
      const auto p = figs / "compare_grid.png";
      renderCompareGrid(g, p.string(), FigureSize{0, 0});  // sized to the grid
      st.figures.push_back(p.string());
      links.push_back({p.string(), "ATE of every run (rows: configurations; columns: sequences x runs); white with a cross: failed",
                       true});
    });
    attempt("ate_per_config.png", st, [&] {
      const auto p = figs / "ate_per_config.png";
      renderAtePerConfig(g, p.string(), o.figure);
      st.figures.push_back(p.string());
      links.push_back({p.string(), "ATE per configuration over all sequences and runs"});
    });
    attempt("index.html", st, [&] {
      const auto p = out / "index.html";
      writeCompareIndex(p.string(), o.title, runs, links, o.notes);
      st.index_html = p.string();
    });
  } catch (const std::exception& e) {
    st.problems.push_back(e.what());
  }
  st.ok = st.problems.empty();
  st.message = st.ok ? "rendered comparison: " + st.index_html : "comparison render incomplete: " + st.problems.front();
  return st;
}

}  // namespace rsvio::viz
