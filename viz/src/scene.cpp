// 3D views with VTK (scene.h). One off-screen window renders every view: the actors are built once,
// then each view sets the camera and its own overlays and is read back into a PNG.
#include "rsvio/viz/scene.h"

#include <vtkCamera.h>
#include <vtkDoubleArray.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkTextProperty.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "canvas.h"
#include "rsvio/core/error.h"
#include "rsvio/viz/colormap.h"
#include "scene_geometry.h"
#include "vtk_helpers.h"

namespace rsvio::viz {
using namespace detail;

const char* viewName(View v) {
  switch (v) {
    case View::kTop: return "top";
    case View::kSide: return "side";
    case View::kPerspective: return "perspective";
    case View::kOverview: return "overview";
  }
  return "?";
}

namespace {

constexpr double kBg[3] = {1.0, 1.0, 1.0};

std::string fmt(double v) { return detail::formatNumber(v); }

}  // namespace

std::vector<std::string> renderScenes(const io::Snapshot& s, const SceneOptions& o, const std::string& out_dir) {
  namespace fs = std::filesystem;
  const SceneGeometry g = detail::buildSceneGeometry(s, o.show_points, o.show_frusta, o.show_ground_truth, o.max_frusta);
  const int W = o.width, H = o.height;
  const double px = std::max(1.0, std::min(W, H) / 480.0);  // line and point sizes grow with the image
  const int font = static_cast<int>(std::clamp(std::min(W / 1.4, double(H)) / 40.0, 9.0, 24.0));
  const bool coloured = !g.est_err.empty() && std::isfinite(g.est_err.front());

  vtkNew<vtkRenderWindow> win;
  win->SetOffScreenRendering(1);
  win->SetSize(W, H);
  win->SetMultiSamples(0);  // deterministic pixels; lines are wide enough without it
  vtkNew<ErrorObserver> errors;
  win->AddObserver(vtkCommand::ErrorEvent, errors);

  // The scene on the left, the colour bar in a strip on the right of its own.
  const double split = coloured ? 0.86 : 1.0;
  vtkNew<vtkRenderer> scene;
  scene->SetViewport(0, 0, split, 1);
  scene->SetBackground(kBg[0], kBg[1], kBg[2]);
  win->AddRenderer(scene);
  vtkNew<vtkRenderer> side;
  if (coloured) {
    side->SetViewport(split, 0, 1, 1);
    side->SetBackground(kBg[0], kBg[1], kBg[2]);
    win->AddRenderer(side);
  }
  const double sw = W * split;  // scene viewport width in pixels

  std::string status = "status " + s.summary.status;
  if (std::isfinite(s.summary.ate_rmse_m)) status += ", ATE " + fmt(s.summary.ate_rmse_m) + " m (report)";
  else if (s.errors) status += ", ATE " + fmt(s.errors->ate_m.rmse) + " m";
  if (!g.empty()) status += ", " + g.align_label;

  vtkSmartPointer<vtkActor> near_points, all_points;
  if (!g.empty()) {
    if (!g.gt.empty()) scene->AddActor(makeLines(g.gt, std::vector<Rgb>(g.gt.size(), kGtColour), true, 1.5 * px));
    if (!g.points.empty()) {
      // Two clouds: the trajectory's neighbourhood for the fitted views, everything for the overview.
      SceneGeometry near = g;
      near.points.clear();
      near.point_shade.clear();
      for (size_t i = 0; i < g.points.size(); ++i) {
        if (!g.point_near[i]) continue;
        near.points.push_back(g.points[i]);
        near.point_shade.push_back(g.point_shade[i]);
      }
      if (!near.points.empty()) {
        near_points = makePoints(near, std::max(1.0, 1.5 * px));
        scene->AddActor(near_points);
      }
      all_points = makePoints(g, std::max(1.0, 1.2 * px));
      scene->AddActor(all_points);
    }
    if (!g.frusta.empty()) scene->AddActor(makeFrusta(g, std::max(1.0, 0.75 * px)));
    if (!g.est.empty()) {
      std::vector<Rgb> col(g.est.size(), kPlainEstimate);
      if (coloured) {
        for (size_t i = 0; i < g.est.size(); ++i) col[i] = errorMap(g.est_err[i] / g.err_max);
      }
      scene->AddActor(makeLines(g.est, col, true, 2.5 * px));
    }
    if (coloured) {
      vtkNew<vtkLookupTable> lut;
      lut->SetNumberOfTableValues(256);
      lut->SetRange(0, g.err_max);
      for (int i = 0; i < 256; ++i) {
        const Rgb c = errorMap(i / 255.0);
        lut->SetTableValue(i, c.r / 255.0, c.g / 255.0, c.b / 255.0, 1.0);
      }
      lut->Build();
      vtkNew<vtkScalarBarActor> bar;
      bar->SetLookupTable(lut);
      bar->SetTitle("error [m]");
      // Round tick values (0, 0.05, 0.1, ...) rather than VTK's evenly split range.
      vtkNew<vtkDoubleArray> ticks;
      for (double v : detail::niceTicks(0, g.err_max, 5)) ticks->InsertNextValue(v);
      bar->SetUseCustomLabels(true);
      bar->SetCustomLabels(ticks);
      bar->SetLabelFormat("%.3g");
      bar->UnconstrainedFontSizeOn();
      bar->GetTitleTextProperty()->SetFontSize(font);
      bar->GetLabelTextProperty()->SetFontSize(static_cast<int>(font * 0.85));
      for (auto* tp : {bar->GetTitleTextProperty(), bar->GetLabelTextProperty()}) {
        tp->SetColor(0.1, 0.1, 0.1);
        tp->ShadowOff();
        tp->ItalicOff();
        tp->BoldOff();
      }
      bar->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
      bar->GetPositionCoordinate()->SetValue(0.05, 0.12);
      bar->GetPosition2Coordinate()->SetValue(0.9, 0.76);
      bar->SetBarRatio(0.3);
      side->AddActor2D(bar);
    }
    // Legend, bottom left: a short line of each colour and its meaning.
    struct Entry {
      std::string text;
      Rgb colour;
    };
    std::vector<Entry> legend;
    if (!g.est.empty()) legend.push_back({coloured ? "estimate (colour = error)" : "estimate", coloured ? errorMap(0.1) : kPlainEstimate});
    if (!g.gt.empty()) legend.push_back({"ground truth", kGtColour});
    if (!g.points.empty()) legend.push_back({"points (grey = intensity)", Rgb{120, 120, 120}});
    if (!g.frusta.empty()) legend.push_back({"keyframes", kFrustumColour});
    const double row = font * 1.35, x0 = font * 0.8;
    for (size_t i = 0; i < legend.size(); ++i) {
      const double y = font * 0.8 + row * (legend.size() - 1 - i) + row * 0.5;
      scene->AddActor2D(make2DLine({{x0, y}, {x0 + font * 1.6, y}}, legend[i].colour, 3 * px));
      scene->AddActor2D(makeText(legend[i].text, static_cast<int>(font * 0.85), Rgb{30, 30, 30}, x0 + font * 2.1,
                                 y - font * 0.45, false));
    }
  } else {
    scene->AddActor2D(makeText(wrap(g.message, static_cast<size_t>(std::max(20.0, sw / (font * 0.55)))), font, Rgb{200, 30, 30},
                               sw / 2, H / 2.0, false, false, true));
  }

  // Each view frames its own box: the trajectory (top, side, perspective) or the whole scene (overview).
  const Eigen::AlignedBox3d unit_box(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1));
  const Eigen::AlignedBox3d fitted = g.bounds.isEmpty() ? unit_box : g.bounds;
  const Eigen::AlignedBox3d whole = g.scene_bounds.isEmpty() ? fitted : g.scene_bounds;
  auto spacingOf = [](const Eigen::AlignedBox3d& b) { return detail::niceNumber(std::max(1e-3, b.sizes().maxCoeff()) / 8.0); };
  vtkSmartPointer<vtkActor> grid_fitted, grid_whole;
  if (!g.empty()) {
    const double ef = std::max(1e-3, fitted.sizes().maxCoeff()), ew = std::max(1e-3, whole.sizes().maxCoeff());
    grid_fitted = makeGrid(fitted, spacingOf(fitted), fitted.min().z() - 0.02 * ef);
    grid_whole = makeGrid(whole, spacingOf(whole), whole.min().z() - 0.02 * ew);
    scene->AddActor(grid_fitted);
    scene->AddActor(grid_whole);
  }

  fs::create_directories(out_dir);
  std::vector<std::string> files;
  // Nothing to draw: one picture of the reason is enough (the first asked view's file).
  const std::vector<View> views = g.empty() && !o.views.empty() ? std::vector<View>{o.views.front()} : o.views;
  for (View v : views) {
    std::vector<vtkSmartPointer<vtkProp>> overlays;  // removed again after this view
    auto overlay = [&](vtkSmartPointer<vtkProp> p) {
      scene->AddViewProp(p);
      overlays.push_back(p);
    };
    const bool overview = v == View::kOverview;
    if (near_points) near_points->SetVisibility(!overview);
    if (all_points) all_points->SetVisibility(overview);
    if (grid_fitted) grid_fitted->SetVisibility(!overview);
    if (grid_whole) grid_whole->SetVisibility(overview);
    const Eigen::AlignedBox3d& bounds = overview ? whole : fitted;
    const Eigen::Vector3d c = bounds.center(), ext = bounds.sizes();
    const double extent = std::max(1e-3, ext.maxCoeff());
    const double spacing = spacingOf(bounds);
    vtkCamera* cam = scene->GetActiveCamera();
    const double aspect = sw / H;
    // Fraction of the height kept clear for the title (top) and the legend (bottom).
    const double vmargin = 1.45, hmargin = 1.12;
    double eh = 0, ew = 0;  // world extents seen vertically / horizontally
    if (v == View::kTop) {
      cam->SetFocalPoint(c.x(), c.y(), c.z());
      cam->SetPosition(c.x(), c.y(), c.z() + 10 * extent);
      cam->SetViewUp(0, 1, 0);
      cam->ParallelProjectionOn();
      ew = ext.x();
      eh = ext.y();
    } else if (v == View::kSide) {
      cam->SetFocalPoint(c.x(), c.y(), c.z());
      cam->SetPosition(c.x(), c.y() - 10 * extent, c.z());
      cam->SetViewUp(0, 0, 1);
      cam->ParallelProjectionOn();
      ew = ext.x();
      eh = ext.z();
    } else {
      const Eigen::Vector3d dir = Eigen::Vector3d(0.55, -1.0, 0.75).normalized();
      cam->SetFocalPoint(c.x(), c.y(), c.z());
      cam->SetPosition(c.x() + dir.x() * 10 * extent, c.y() + dir.y() * 10 * extent, c.z() + dir.z() * 10 * extent);
      cam->SetViewUp(0, 0, 1);
      cam->ParallelProjectionOff();
      cam->SetViewAngle(30);
      scene->ResetCamera(bounds.min().x(), bounds.max().x(), bounds.min().y(), bounds.max().y(), bounds.min().z(),
                         bounds.max().z());
      cam->Zoom(1.15);
    }
    double half_h = 0;
    const bool parallel = v == View::kTop || v == View::kSide;
    if (parallel) {
      half_h = std::max({0.5 * eh * vmargin, 0.5 * ew * hmargin / aspect, 1e-3});
      cam->SetParallelScale(half_h);
    }
    scene->ResetCameraClippingRange();

    std::string title = s.name + ": " + viewName(v) + " view";
    if (v == View::kTop) title += " (x right, y up)";
    if (v == View::kSide) title += " (x right, z up)";
    if (v == View::kOverview) title += " (whole scene)";
    overlay(makeText(title, font, Rgb{20, 20, 20}, font * 0.6, H - font * 0.5, true));
    overlay(makeText(status, static_cast<int>(font * 0.8), Rgb{90, 90, 90}, font * 0.6, H - font * 2.0, true));
    if (!g.empty()) {
      std::string grid_note = "grid " + fmt(spacing) + " " + g.unit;
      if (parallel) {
        // Scale bar: a nice length near a fifth of the view's width, bottom right.
        const double px_per_unit = H / (2.0 * half_h);
        const double len = detail::niceNumber(0.2 * sw / px_per_unit);
        const double len_px = len * px_per_unit, xr = sw - font * 1.2, yb = font * 1.4;
        overlay(make2DLine({{xr - len_px, yb + font * 0.3}, {xr - len_px, yb}, {xr, yb}, {xr, yb + font * 0.3}}, Rgb{20, 20, 20},
                           2 * px));
        overlay(makeText(fmt(len) + " " + g.unit, static_cast<int>(font * 0.85), Rgb{20, 20, 20}, xr - len_px / 2, yb + font * 0.4,
                         false, false, false));
        static_cast<vtkTextActor*>(overlays.back().Get())->GetTextProperty()->SetJustificationToCentered();
      }
      overlay(makeText(grid_note, static_cast<int>(font * 0.75), Rgb{120, 120, 120}, sw - font * 1.2, H - font * 0.5, true, true));
    }
    win->Render();
    keepGlDriverLoaded();  // sanitizer build only (vtk_helpers.h)
    if (!errors->message_.empty()) throw Error("VTK could not render: " + errors->message_);
    const std::string path = (fs::path(out_dir) / (o.file_prefix + viewName(v) + ".png")).string();
    writePng(win, path, W, H);
    if (!errors->message_.empty()) throw Error("VTK could not read back the image: " + errors->message_);
    files.push_back(path);
    for (auto& p : overlays) scene->RemoveViewProp(p);
  }
  return files;
}

}  // namespace rsvio::viz
