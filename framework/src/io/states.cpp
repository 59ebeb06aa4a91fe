#include "rsvio/io/states.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "rsvio/core/error.h"
#include "rsvio/io/atomic_file.h"

namespace rsvio {

namespace {
constexpr const char* kHeader =
    "# t_ns,v_x,v_y,v_z,bg_x,bg_y,bg_z,ba_x,ba_y,ba_z,xi_tx,xi_ty,xi_tz,xi_rx,xi_ry,xi_rz,scale,time_offset_ms,"
    "line_delay_us";
constexpr int kColumns = 19;
constexpr int kColumnsBeforeLineDelay = 18;  // files written before the line_delay_us column
constexpr int kColumnsBeforeOffset = 17;     // files written before the time_offset_ms column
}  // namespace

void writeStates(const std::vector<StateRow>& rows, const std::string& path) {
  io::writeFileAtomic(path, [&](std::ostream& out) {
  out << kHeader << "\n";
  char buf[64];
  for (const auto& r : rows) {
    out << r.t_ns;
    auto put = [&](double v) {
      std::snprintf(buf, sizeof(buf), ",%.9g", v);
      out << buf;
    };
    for (int i = 0; i < 3; ++i) put(r.v[i]);
    for (int i = 0; i < 3; ++i) put(r.bg[i]);
    for (int i = 0; i < 3; ++i) put(r.ba[i]);
    for (int i = 0; i < 6; ++i) put(r.twist[i]);
    put(r.scale);
    put(r.time_offset_ms);
    put(r.line_delay_us);
    out << "\n";
  }
  }, "states");
}

std::vector<StateRow> readStates(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw DataError(path + ": cannot open states file");
  std::vector<StateRow> rows;
  std::string line;
  long n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) f.push_back(cell);
    const int cols = static_cast<int>(f.size());
    if (cols != kColumns && cols != kColumnsBeforeLineDelay && cols != kColumnsBeforeOffset)
      throw DataError::at(path, n, "expected " + std::to_string(kColumns) + " columns, found " +
                                       std::to_string(f.size()));
    StateRow r;
    double v[kColumns] = {};
    for (int i = 0; i < cols; ++i) {
      char* end = nullptr;
      v[i] = std::strtod(f[i].c_str(), &end);
      if (end == f[i].c_str() || *end != '\0' || !std::isfinite(v[i]))
        throw DataError::at(path, n, "column " + std::to_string(i + 1) + ": not a finite number: '" + f[i] + "'");
    }
    r.t_ns = std::stoll(f[0]);
    r.v = Eigen::Vector3d(v[1], v[2], v[3]);
    r.bg = Eigen::Vector3d(v[4], v[5], v[6]);
    r.ba = Eigen::Vector3d(v[7], v[8], v[9]);
    for (int i = 0; i < 6; ++i) r.twist[i] = v[10 + i];
    r.scale = v[16];
    r.time_offset_ms = v[17];  // 0 in a 17-column file
    r.line_delay_us = v[18];   // 0 in files before the column
    rows.push_back(r);
  }
  return rows;
}

}  // namespace rsvio
