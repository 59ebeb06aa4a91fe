// points.ply writer and reader (rsvio/io/ply.h).
#include "rsvio/io/ply.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>

#include "rsvio/core/error.h"
#include "rsvio/io/atomic_file.h"

namespace rsvio::io {
namespace {

enum class PlyFormat { kAscii, kBinaryLE };

struct PlyProperty {
  std::string name;
  std::string type;  // normalised: int8 uint8 int16 uint16 int32 uint32 float32 float64
  bool is_list = false;
};

struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> props;
};

// PLY allows two spellings for each scalar type; returns "" for an unknown one.
std::string normaliseType(const std::string& t) {
  if (t == "char" || t == "int8") return "int8";
  if (t == "uchar" || t == "uint8") return "uint8";
  if (t == "short" || t == "int16") return "int16";
  if (t == "ushort" || t == "uint16") return "uint16";
  if (t == "int" || t == "int32") return "int32";
  if (t == "uint" || t == "uint32") return "uint32";
  if (t == "float" || t == "float32") return "float32";
  if (t == "double" || t == "float64") return "float64";
  return "";
}

size_t typeSize(const std::string& t) {
  if (t == "int8" || t == "uint8") return 1;
  if (t == "int16" || t == "uint16") return 2;
  if (t == "int32" || t == "uint32" || t == "float32") return 4;
  return 8;
}

// Reads one little-endian scalar of type t from p (the host is little-endian on every platform we build).
double readBinaryScalar(const char* p, const std::string& t) {
  if (t == "int8") { int8_t v; std::memcpy(&v, p, 1); return v; }
  if (t == "uint8") { uint8_t v; std::memcpy(&v, p, 1); return v; }
  if (t == "int16") { int16_t v; std::memcpy(&v, p, 2); return v; }
  if (t == "uint16") { uint16_t v; std::memcpy(&v, p, 2); return v; }
  if (t == "int32") { int32_t v; std::memcpy(&v, p, 4); return v; }
  if (t == "uint32") { uint32_t v; std::memcpy(&v, p, 4); return v; }
  if (t == "float32") { float v; std::memcpy(&v, p, 4); return v; }
  double v;
  std::memcpy(&v, p, 8);
  return v;
}

void writeHeader(std::ostream& f, size_t n) {
  f << "ply\nformat ascii 1.0\ncomment rsvio sparse point cloud, world frame\n"
    << "element vertex " << n << "\n"
    << "property float x\nproperty float y\nproperty float z\nproperty float intensity\nend_header\n";
}

// One vertex line; the stream's precision is 9 significant digits.
void writeVertex(std::ostream& f, const Eigen::Vector3d& p, float intensity) {
  f << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << intensity << '\n';
}

int findProp(const PlyElement& e, const char* name) {
  for (size_t i = 0; i < e.props.size(); ++i) {
    if (e.props[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace

void writePly(const std::string& path, const PointCloud& cloud) {
  if (cloud.p_W.size() != cloud.intensity.size()) {
    throw Error(path + ": point cloud has " + std::to_string(cloud.p_W.size()) + " positions but " +
                std::to_string(cloud.intensity.size()) + " intensities");
  }
  writeFileAtomic(path, [&](std::ostream& f) {
  writeHeader(f, cloud.size());
  f << std::setprecision(9);
  for (size_t i = 0; i < cloud.size(); ++i) writeVertex(f, cloud.p_W[i], cloud.intensity[i]);
  }, "point cloud");
}

PlyStreamWriter::PlyStreamWriter(const std::string& path) : path_(path), body_(atomicTempPath(path) + ".body") {
  out_ = std::make_unique<std::ofstream>(body_, std::ios::trunc);
  if (!*out_) {
    const std::string why = std::strerror(errno);
    out_.reset();
    throw Error(path_ + ": cannot write point cloud (" + why + ")");
  }
  *out_ << std::setprecision(9);
}

PlyStreamWriter::~PlyStreamWriter() { abandon(); }

void PlyStreamWriter::abandon() {
  if (!out_) return;
  out_->close();
  out_.reset();
  std::remove(body_.c_str());
}

void PlyStreamWriter::append(const Eigen::Vector3d& p_W, float intensity) {
  if (!out_) throw Error(path_ + ": point cloud already closed");
  writeVertex(*out_, p_W, intensity);
  if (!*out_) {
    abandon();
    throw Error(path_ + ": write failed (point cloud)");
  }
  ++n_;
}

void PlyStreamWriter::close() {
  if (!out_) throw Error(path_ + ": point cloud already closed");
  out_->close();
  const bool ok = static_cast<bool>(*out_);
  out_.reset();
  if (!ok) {
    std::remove(body_.c_str());
    throw Error(path_ + ": write failed (point cloud)");
  }
  try {
    writeFileAtomic(path_, [&](std::ostream& f) {
      writeHeader(f, n_);
      std::ifstream in(body_);
      if (!in) throw Error(path_ + ": cannot read back the point cloud's temporary " + body_);
      if (n_ > 0) f << in.rdbuf();  // streamed copy, bounded buffer
      if (!f) throw Error(path_ + ": write failed (point cloud)");
    }, "point cloud");
  } catch (...) {
    std::remove(body_.c_str());
    throw;
  }
  std::remove(body_.c_str());
}

PointCloud readPly(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw DataError::at(path, 0, "cannot open");
  std::string line;
  long line_no = 0;
  auto nextLine = [&]() -> bool {
    if (!std::getline(f, line)) return false;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  };
  if (!nextLine() || line != "ply") throw DataError::at(path, 1, "not a PLY file (first line is not 'ply')");

  PlyFormat format = PlyFormat::kAscii;
  bool have_format = false;
  std::vector<PlyElement> elements;
  bool ended = false;
  while (nextLine()) {
    std::istringstream ss(line);
    std::string kw;
    ss >> kw;
    if (kw.empty() || kw == "comment" || kw == "obj_info") continue;
    if (kw == "end_header") {
      ended = true;
      break;
    }
    if (kw == "format") {
      std::string fmt;
      ss >> fmt;
      if (fmt == "ascii") format = PlyFormat::kAscii;
      else if (fmt == "binary_little_endian") format = PlyFormat::kBinaryLE;
      else throw DataError::at(path, line_no, "unsupported PLY format '" + fmt + "' (ascii or binary_little_endian)");
      have_format = true;
    } else if (kw == "element") {
      PlyElement e;
      long long count = -1;
      ss >> e.name >> count;
      if (e.name.empty() || count < 0) throw DataError::at(path, line_no, "malformed element line");
      e.count = static_cast<size_t>(count);
      elements.push_back(e);
    } else if (kw == "property") {
      if (elements.empty()) throw DataError::at(path, line_no, "property before any element");
      PlyProperty p;
      std::string t;
      ss >> t;
      if (t == "list") {
        std::string count_t, item_t;
        ss >> count_t >> item_t >> p.name;
        p.is_list = true;
        p.type = normaliseType(item_t);
      } else {
        p.type = normaliseType(t);
        ss >> p.name;
      }
      if (p.type.empty() || p.name.empty()) throw DataError::at(path, line_no, "malformed property line");
      elements.back().props.push_back(p);
    } else {
      throw DataError::at(path, line_no, "unknown header keyword '" + kw + "'");
    }
  }
  if (!ended) throw DataError::at(path, line_no, "header has no end_header");
  if (!have_format) throw DataError::at(path, line_no, "header has no format line");

  size_t vi = elements.size();
  for (size_t i = 0; i < elements.size(); ++i) {
    if (elements[i].name == "vertex") {
      vi = i;
      break;
    }
  }
  if (vi == elements.size()) throw DataError::at(path, line_no, "no 'vertex' element");
  const PlyElement& v = elements[vi];
  const int ix = findProp(v, "x"), iy = findProp(v, "y"), iz = findProp(v, "z");
  if (ix < 0 || iy < 0 || iz < 0) throw DataError::at(path, line_no, "vertex element lacks x, y or z");
  const int ii = findProp(v, "intensity");
  const int ir = findProp(v, "red"), ig = findProp(v, "green"), ib = findProp(v, "blue");
  for (const auto& p : v.props) {
    if (p.is_list) throw DataError::at(path, line_no, "list property '" + p.name + "' in vertex element is not supported");
  }

  PointCloud cloud;
  // The header's count is not trusted for the allocation (a corrupt count must not ask for terabytes);
  // the file ending early is reported below.
  const size_t reserve = std::min<size_t>(v.count, size_t{1} << 20);
  cloud.p_W.reserve(reserve);
  cloud.intensity.reserve(reserve);
  std::vector<double> values(v.props.size());
  auto store = [&]() {
    cloud.p_W.emplace_back(values[ix], values[iy], values[iz]);
    float inten = std::numeric_limits<float>::quiet_NaN();
    if (ii >= 0) inten = static_cast<float>(values[ii]);
    else if (ir >= 0 && ig >= 0 && ib >= 0) inten = static_cast<float>((values[ir] + values[ig] + values[ib]) / 3.0);
    cloud.intensity.push_back(inten);
  };

  if (format == PlyFormat::kAscii) {
    // Elements before the vertices are skipped line by line (one line per item in ASCII PLY).
    for (size_t e = 0; e < vi; ++e) {
      for (size_t k = 0; k < elements[e].count; ++k) {
        if (!nextLine()) throw DataError::at(path, line_no, "file ends inside element '" + elements[e].name + "'");
      }
    }
    for (size_t k = 0; k < v.count; ++k) {
      if (!nextLine()) {
        throw DataError::at(path, line_no, "file ends after " + std::to_string(k) + " of " +
                                               std::to_string(v.count) + " vertices");
      }
      std::istringstream ss(line);
      for (size_t p = 0; p < values.size(); ++p) {
        std::string tok;
        if (!(ss >> tok)) throw DataError::at(path, line_no, "vertex has fewer than " + std::to_string(values.size()) + " values");
        char* end = nullptr;
        values[p] = std::strtod(tok.c_str(), &end);
        if (end == tok.c_str() || *end != '\0') {
          throw DataError::at(path, line_no, "not a number '" + tok + "', property " + v.props[p].name);
        }
      }
      store();
    }
    return cloud;
  }

  // Binary: skipping earlier elements needs fixed-size items.
  for (size_t e = 0; e < vi; ++e) {
    size_t item = 0;
    for (const auto& p : elements[e].props) {
      if (p.is_list) throw DataError::at(path, 0, "binary element '" + elements[e].name + "' with a list before the vertices is not supported");
      item += typeSize(p.type);
    }
    f.seekg(static_cast<std::streamoff>(item * elements[e].count), std::ios::cur);
  }
  size_t stride = 0;
  std::vector<size_t> offsets;
  for (const auto& p : v.props) {
    offsets.push_back(stride);
    stride += typeSize(p.type);
  }
  std::vector<char> buf(stride);
  for (size_t k = 0; k < v.count; ++k) {
    if (!f.read(buf.data(), static_cast<std::streamsize>(stride))) {
      throw DataError::at(path, 0, "binary data ends after " + std::to_string(k) + " of " + std::to_string(v.count) + " vertices");
    }
    for (size_t p = 0; p < values.size(); ++p) values[p] = readBinaryScalar(buf.data() + offsets[p], v.props[p].type);
    store();
  }
  return cloud;
}

}  // namespace rsvio::io
