// Internal VTK building blocks of the 3D views (scene.cpp): line, point, frustum and grid actors,
// 2D overlays in viewport pixels, reading the window back into a PNG. Colours are Rgb (colormap.h).
#pragma once
#include <vtkActor.h>
#include <vtkActor2D.h>
#include <vtkCommand.h>
#include <vtkRenderWindow.h>
#include <vtkSmartPointer.h>
#include <vtkTextActor.h>

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "rsvio/viz/colormap.h"
#include "scene_geometry.h"

namespace rsvio::viz::detail {

constexpr Rgb kGtColour{20, 20, 20};
constexpr Rgb kFrustumColour{150, 90, 200};
constexpr Rgb kPlainEstimate{31, 119, 180};
constexpr Rgb kGridColour{222, 222, 222};

// Collects VTK error events so a failed render becomes an exception with VTK's own words.
class ErrorObserver : public vtkCommand {
 public:
  static ErrorObserver* New() { return new ErrorObserver; }
  void Execute(vtkObject*, unsigned long, void* data) override {
    if (message_.empty() && data) message_ = static_cast<const char*>(data);
  }
  std::string message_;
};

// Line actor: a polyline through pts, or segments (pts[0], pts[1]), (pts[2], pts[3]), ...; one colour
// per point, unlit.
vtkSmartPointer<vtkActor> makeLines(const std::vector<Eigen::Vector3d>& pts, const std::vector<Rgb>& colours,
                                    bool polyline, double width);
vtkSmartPointer<vtkActor> makePoints(const SceneGeometry& g, double size);
vtkSmartPointer<vtkActor> makeFrusta(const SceneGeometry& g, double width);
// Ground grid on the plane z = z0 spanning the bounds (xy).
vtkSmartPointer<vtkActor> makeGrid(const Eigen::AlignedBox3d& b, double spacing, double z0);
// Text at display pixel (x, y) (origin bottom left); top: (x, y) is its top, else its bottom.
vtkSmartPointer<vtkTextActor> makeText(const std::string& s, int size, const Rgb& c, double x, double y, bool top,
                                       bool right = false, bool centred = false);
// 2D polyline in viewport pixels (origin bottom left).
vtkSmartPointer<vtkActor2D> make2DLine(const std::vector<Eigen::Vector2d>& pts, const Rgb& c, double width);
// Breaks text into lines of at most `width` characters at spaces (long words stay whole).
std::string wrap(const std::string& s, size_t width);
// Reads the rendered window back and writes it as PNG; throws rsvio::Error on a size mismatch or I/O error.
void writePng(vtkRenderWindow* win, const std::string& path, int width, int height);
// Sanitizer build only (RSVIO_SANITIZE; no-op otherwise): marks the GL driver modules loaded so far
// (Mesa's *_dri.so, dlopen'ed per X display and dlclose'd when the window's display closes) as never
// to be unloaded. Unloaded, the driver's globals are unmapped: LeakSanitizer then reports what they
// pointed to as leaks from "<unknown module>" that no suppression can name. Call after a Render().
void keepGlDriverLoaded();

}  // namespace rsvio::viz::detail
