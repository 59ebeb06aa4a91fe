// VTK building blocks of the 3D views (vtk_helpers.h).
#include "vtk_helpers.h"

#include <vtkCellArray.h>
#include <vtkCoordinate.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkPolyDataMapper2D.h>
#include <vtkProperty.h>
#include <vtkProperty2D.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>

#include "rsvio/core/error.h"
#include "rsvio/io/image_file.h"

#ifdef RSVIO_SANITIZE
#include <dlfcn.h>
#include <link.h>
#endif

namespace rsvio::viz::detail {
namespace {

void insertColour(vtkUnsignedCharArray* a, const Rgb& c) {
  const unsigned char v[3] = {c.r, c.g, c.b};
  a->InsertNextTypedTuple(v);
}

}  // namespace

vtkSmartPointer<vtkActor> makeLines(const std::vector<Eigen::Vector3d>& pts, const std::vector<Rgb>& colours,
                                    bool polyline, double width) {
  vtkNew<vtkPoints> points;
  vtkNew<vtkUnsignedCharArray> rgb;
  rgb->SetNumberOfComponents(3);
  rgb->SetName("rgb");
  for (size_t i = 0; i < pts.size(); ++i) {
    points->InsertNextPoint(pts[i].x(), pts[i].y(), pts[i].z());
    insertColour(rgb, colours[i]);
  }
  vtkNew<vtkCellArray> cells;
  if (polyline) {
    cells->InsertNextCell(static_cast<vtkIdType>(pts.size()));
    for (size_t i = 0; i < pts.size(); ++i) cells->InsertCellPoint(static_cast<vtkIdType>(i));
  } else {
    for (size_t i = 0; i + 1 < pts.size(); i += 2) {
      const vtkIdType ids[2] = {static_cast<vtkIdType>(i), static_cast<vtkIdType>(i + 1)};
      cells->InsertNextCell(2, ids);
    }
  }
  vtkNew<vtkPolyData> pd;
  pd->SetPoints(points);
  pd->SetLines(cells);
  pd->GetPointData()->SetScalars(rgb);
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(pd);
  mapper->SetColorModeToDirectScalars();
  mapper->ScalarVisibilityOn();
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetLineWidth(static_cast<float>(width));
  actor->GetProperty()->LightingOff();
  return actor;
}

vtkSmartPointer<vtkActor> makePoints(const SceneGeometry& g, double size) {
  vtkNew<vtkPoints> points;
  vtkNew<vtkUnsignedCharArray> rgb;
  rgb->SetNumberOfComponents(3);
  vtkNew<vtkCellArray> verts;
  for (size_t i = 0; i < g.points.size(); ++i) {
    points->InsertNextPoint(g.points[i].x(), g.points[i].y(), g.points[i].z());
    // Bright points light grey, dark points dark grey: visible on white either way.
    insertColour(rgb, grey(g.point_shade[i], 60, 200));
    const vtkIdType id = static_cast<vtkIdType>(i);
    verts->InsertNextCell(1, &id);
  }
  vtkNew<vtkPolyData> pd;
  pd->SetPoints(points);
  pd->SetVerts(verts);
  pd->GetPointData()->SetScalars(rgb);
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(pd);
  mapper->SetColorModeToDirectScalars();
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetPointSize(static_cast<float>(size));
  actor->GetProperty()->LightingOff();
  return actor;
}

vtkSmartPointer<vtkActor> makeFrusta(const SceneGeometry& g, double width) {
  std::vector<Eigen::Vector3d> seg;
  const double d = g.frustum_size, w = 0.6 * d, h = 0.45 * d;
  for (const auto& f : g.frusta) {
    // Camera x right, y down, z forward: the image plane's corners at depth d.
    const Eigen::Vector3d c[4] = {f.p_W_C + f.R_W_C * Eigen::Vector3d(-w, -h, d), f.p_W_C + f.R_W_C * Eigen::Vector3d(w, -h, d),
                                  f.p_W_C + f.R_W_C * Eigen::Vector3d(w, h, d), f.p_W_C + f.R_W_C * Eigen::Vector3d(-w, h, d)};
    for (int k = 0; k < 4; ++k) {
      seg.push_back(f.p_W_C);
      seg.push_back(c[k]);
      seg.push_back(c[k]);
      seg.push_back(c[(k + 1) % 4]);
    }
    // A tick on the top edge says which way is up in the image.
    seg.push_back(0.5 * (c[0] + c[1]));
    seg.push_back(0.5 * (c[0] + c[1]) + f.R_W_C * Eigen::Vector3d(0, -0.3 * h, 0));
  }
  return makeLines(seg, std::vector<Rgb>(seg.size(), kFrustumColour), false, width);
}

vtkSmartPointer<vtkActor> makeGrid(const Eigen::AlignedBox3d& b, double spacing, double z0) {
  std::vector<Eigen::Vector3d> seg;
  const double x0 = std::floor(b.min().x() / spacing) * spacing, x1 = std::ceil(b.max().x() / spacing) * spacing;
  const double y0 = std::floor(b.min().y() / spacing) * spacing, y1 = std::ceil(b.max().y() / spacing) * spacing;
  for (double x = x0; x <= x1 + 1e-9 * spacing; x += spacing) {
    seg.emplace_back(x, y0, z0);
    seg.emplace_back(x, y1, z0);
  }
  for (double y = y0; y <= y1 + 1e-9 * spacing; y += spacing) {
    seg.emplace_back(x0, y, z0);
    seg.emplace_back(x1, y, z0);
  }
  return makeLines(seg, std::vector<Rgb>(seg.size(), kGridColour), false, 1.0);
}

vtkSmartPointer<vtkTextActor> makeText(const std::string& s, int size, const Rgb& c, double x, double y, bool top,
                                       bool right, bool centred) {
  auto t = vtkSmartPointer<vtkTextActor>::New();
  t->SetInput(s.c_str());
  auto* p = t->GetTextProperty();
  p->SetFontSize(size);
  p->SetColor(c.r / 255.0, c.g / 255.0, c.b / 255.0);
  p->SetFontFamilyToArial();
  if (top) p->SetVerticalJustificationToTop();
  else p->SetVerticalJustificationToBottom();
  if (right) p->SetJustificationToRight();
  if (centred) {
    p->SetJustificationToCentered();
    p->SetVerticalJustificationToCentered();
  }
  t->SetDisplayPosition(static_cast<int>(x), static_cast<int>(y));
  return t;
}

vtkSmartPointer<vtkActor2D> make2DLine(const std::vector<Eigen::Vector2d>& pts, const Rgb& c, double width) {
  vtkNew<vtkPoints> points;
  vtkNew<vtkCellArray> cells;
  cells->InsertNextCell(static_cast<vtkIdType>(pts.size()));
  for (size_t i = 0; i < pts.size(); ++i) {
    points->InsertNextPoint(pts[i].x(), pts[i].y(), 0);
    cells->InsertCellPoint(static_cast<vtkIdType>(i));
  }
  vtkNew<vtkPolyData> pd;
  pd->SetPoints(points);
  pd->SetLines(cells);
  vtkNew<vtkCoordinate> coord;
  coord->SetCoordinateSystemToViewport();
  vtkNew<vtkPolyDataMapper2D> mapper;
  mapper->SetInputData(pd);
  mapper->SetTransformCoordinate(coord);
  auto a = vtkSmartPointer<vtkActor2D>::New();
  a->SetMapper(mapper);
  a->GetProperty()->SetColor(c.r / 255.0, c.g / 255.0, c.b / 255.0);
  a->GetProperty()->SetLineWidth(static_cast<float>(width));
  return a;
}

std::string wrap(const std::string& s, size_t width) {
  std::string out, line, word;
  auto flush_word = [&] {
    if (word.empty()) return;
    if (!line.empty() && line.size() + 1 + word.size() > width) {
      out += line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
    word.clear();
  };
  for (char c : s) {
    if (c == ' ') flush_word();
    else word += c;
  }
  flush_word();
  return out + line;
}

void writePng(vtkRenderWindow* win, const std::string& path, int width, int height) {
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(win);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->Update();
  vtkImageData* img = grab->GetOutput();
  int dims[3];
  img->GetDimensions(dims);
  if (dims[0] != width || dims[1] != height) {
    throw Error("VTK rendered " + std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + " instead of " +
                std::to_string(width) + "x" + std::to_string(height));
  }
  cv::Mat rgb(height, width, CV_8UC3, img->GetScalarPointer());
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  cv::flip(bgr, bgr, 0);  // VTK's rows start at the bottom
  io::writePng(path, bgr, 1);  // zlib level 1: fast, as cv::imwrite's default was; throws Error naming path
}

void keepGlDriverLoaded() {
#ifdef RSVIO_SANITIZE
  std::vector<std::string> drivers;
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void* out) {
        const char* n = info->dlpi_name;
        const size_t len = n ? std::strlen(n) : 0;
        if (len > 7 && std::strcmp(n + len - 7, "_dri.so") == 0) static_cast<std::vector<std::string>*>(out)->push_back(n);
        return 0;
      },
      &drivers);
  // RTLD_NOLOAD: only takes a reference on what is loaded already; RTLD_NODELETE: never unloaded.
  for (const auto& d : drivers) dlopen(d.c_str(), RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
#endif
}

}  // namespace rsvio::viz::detail
