// TUM and EuRoC trajectory files (contract in rsvio/io/trajectory.h).
#include "rsvio/io/trajectory.h"

#include <cctype>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "rsvio/core/error.h"
#include "rsvio/io/atomic_file.h"
#include "rsvio/core/time.h"

namespace rsvio::io {
namespace {

std::string trim(const std::string& s) {
  size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

std::vector<std::string> splitWhitespace(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream in(s);
  std::string tok;
  while (in >> tok) out.push_back(tok);
  return out;
}

std::vector<std::string> splitComma(const std::string& s) {
  std::vector<std::string> out;
  size_t start = 0;
  while (true) {
    const size_t c = s.find(',', start);
    out.push_back(trim(s.substr(start, c == std::string::npos ? std::string::npos : c - start)));
    if (c == std::string::npos) break;
    start = c + 1;
  }
  return out;
}

std::ifstream openOrThrow(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw DataError::at(path, 0, "cannot open file");
  return in;
}

// Reads one finite double; the message names the field so a user can find the column.
double parseField(const std::string& tok, const char* field, const std::string& path, long line) {
  const char* s = tok.c_str();
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s, &end);
  if (tok.empty() || end != s + tok.size())
    throw DataError::at(path, line, std::string("field '") + field + "' is not a number: '" + tok + "'");
  if (!std::isfinite(v))
    throw DataError::at(path, line, std::string("field '") + field + "' is " + tok + " (must be finite)");
  return v;
}

int64_t parseNsField(const std::string& tok, const char* field, const std::string& path, long line) {
  const char* s = tok.c_str();
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(s, &end, 10);
  if (tok.empty() || end != s + tok.size() || errno == ERANGE)
    throw DataError::at(path, line,
                        std::string("field '") + field + "' is not an integer nanosecond timestamp: '" + tok + "'");
  return static_cast<int64_t>(v);
}

// Quaternions in files are rounded (TUM RGB-D ground truth has 4 decimals), so a small deviation from
// unit norm is normalised away; a large one means wrong columns or garbage and is reported.
Eigen::Quaterniond makeUnitQuaternion(double w, double x, double y, double z, const std::string& path,
                                      long line, const char* fields) {
  Eigen::Quaterniond q(w, x, y, z);
  const double n = q.norm();
  if (!(std::abs(n - 1.0) <= 0.1)) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.6g", n);
    throw DataError::at(path, line, std::string("quaternion (") + fields + ") has norm " + buf +
                                        ", expected 1 (wrong column order or count?)");
  }
  q.coeffs() /= n;
  return q;
}

void checkOrder(int64_t prev_ns, int64_t t_ns, bool have_prev, const std::string& path, long line) {
  if (have_prev && t_ns < prev_ns) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "timestamp %.9f s is earlier than the previous pose's %.9f s", nsToS(t_ns),
                  nsToS(prev_ns));
    throw DataError::at(path, line, std::string(buf) + " (timestamps must not decrease)");
  }
}

}  // namespace

const char* poseFrameName(PoseFrame f) {
  switch (f) {
    case PoseFrame::kBody: return "body";
    case PoseFrame::kCamera: return "camera";
    default: return "unknown";
  }
}

namespace {

// "1.403715529112143517e+09" -> "1403715529.112143517": moves the decimal point by the exponent on the
// digit string itself, so stamps written in exponent notation (evo does) stay exact too.
std::optional<std::string> shiftExponent(const std::string& token) {
  const size_t e = token.find_first_of("eE");
  std::string mant = token.substr(0, e);
  const std::string exp_text = token.substr(e + 1);
  if (exp_text.empty() || exp_text.size() > 4) return std::nullopt;
  char* end = nullptr;
  const long exp = std::strtol(exp_text.c_str(), &end, 10);
  if (*end != '\0') return std::nullopt;
  std::string sign;
  if (!mant.empty() && (mant[0] == '+' || mant[0] == '-')) {
    sign = mant.substr(0, 1);
    mant = mant.substr(1);
  }
  const size_t dot = mant.find('.');
  std::string digits = mant;
  long point = static_cast<long>(mant.size());
  if (dot != std::string::npos) {
    digits = mant.substr(0, dot) + mant.substr(dot + 1);
    point = static_cast<long>(dot);
  }
  if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
  point += exp;
  if (point > 40 || point < -40) return std::nullopt;
  if (point <= 0) return sign + "0." + std::string(static_cast<size_t>(-point), '0') + digits;
  if (point >= static_cast<long>(digits.size())) return sign + digits + std::string(point - digits.size(), '0');
  return sign + digits.substr(0, point) + "." + digits.substr(point);
}

}  // namespace

std::optional<int64_t> parseSecondsToNs(const std::string& token) {
  if (token.empty()) return std::nullopt;
  if (token.find_first_of("eE") != std::string::npos) {
    const auto plain = shiftExponent(token);
    if (!plain || plain->find_first_of("eE") != std::string::npos) return std::nullopt;
    return parseSecondsToNs(*plain);
  }
  // Exact decimal conversion: TUM stamps carry up to 9 decimals and double would lose the last ones.
  size_t i = 0;
  bool negative = false;
  if (token[i] == '+' || token[i] == '-') negative = token[i++] == '-';
  int64_t whole = 0, frac = 0;
  int int_digits = 0, frac_digits = 0;
  bool round_up = false;
  while (i < token.size() && std::isdigit(static_cast<unsigned char>(token[i]))) {
    // Leading zeros (from exponent shifting) do not count towards the int64 limit.
    if (whole > 0 || token[i] != '0') {
      if (++int_digits > 10) return std::nullopt;  // > 9.2e9 s does not fit int64 nanoseconds
    }
    whole = whole * 10 + (token[i++] - '0');
  }
  const bool had_int = i > (negative || token[0] == '+' ? 1u : 0u);
  if (i < token.size() && token[i] == '.') {
    ++i;
    while (i < token.size() && std::isdigit(static_cast<unsigned char>(token[i]))) {
      if (frac_digits < 9) {
        frac = frac * 10 + (token[i] - '0');
      } else if (frac_digits == 9) {
        round_up = token[i] >= '5';
      }
      ++frac_digits;
      ++i;
    }
  }
  if (i != token.size() || (!had_int && frac_digits == 0)) return std::nullopt;
  for (int k = std::min(frac_digits, 9); k < 9; ++k) frac *= 10;
  if (whole > std::numeric_limits<int64_t>::max() / 1000000000LL - 1) return std::nullopt;
  const int64_t ns = whole * 1000000000LL + frac + (round_up ? 1 : 0);
  return negative ? -ns : ns;
}

std::string formatSeconds(int64_t t) {
  const uint64_t mag = t < 0 ? static_cast<uint64_t>(-(t + 1)) + 1 : static_cast<uint64_t>(t);
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%s%" PRIu64 ".%09" PRIu64, t < 0 ? "-" : "", mag / 1000000000ULL,
                mag % 1000000000ULL);
  return buf;
}

std::string formatTumLine(const StampedPose& pose) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%s %.9f %.9f %.9f %.9f %.9f %.9f %.9f", formatSeconds(pose.t_ns).c_str(),
                pose.p_W_X.x(), pose.p_W_X.y(),
                pose.p_W_X.z(), pose.q_W_X.x(), pose.q_W_X.y(), pose.q_W_X.z(), pose.q_W_X.w());
  return buf;
}

void writeTum(const std::string& path, const Trajectory& traj) {
  writeFileAtomic(path, [&](std::ostream& out) {
    if (traj.frame != PoseFrame::kUnknown) out << "# frame: " << poseFrameName(traj.frame) << "\n";
    for (const auto& p : traj.poses) out << formatTumLine(p) << "\n";
  }, "trajectory");
}

Trajectory readTum(const std::string& path) {
  std::ifstream in = openOrThrow(path);
  static const char* kFields[8] = {"t", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  Trajectory traj;
  traj.source = path;
  std::string raw;
  long line = 0;
  while (std::getline(in, raw)) {
    ++line;
    const std::string s = trim(raw);
    if (s.empty()) continue;
    if (s[0] == '#') {
      if (line != 1) continue;
      // Only the first line may carry the frame header: "# frame: body|camera".
      const std::string body = trim(s.substr(1));
      if (body.rfind("frame:", 0) != 0) continue;
      const std::string value = trim(body.substr(6));
      if (value == "body") {
        traj.frame = PoseFrame::kBody;
      } else if (value == "camera") {
        traj.frame = PoseFrame::kCamera;
      } else {
        throw DataError::at(path, line, "header 'frame' is '" + value + "', expected 'body' or 'camera'");
      }
      continue;
    }
    const auto tok = splitWhitespace(s);
    if (tok.size() != 8) {
      std::string msg = "expected 8 columns (t tx ty tz qx qy qz qw), found " + std::to_string(tok.size());
      if (s.find(',') != std::string::npos) msg += " (TUM files are space separated, not comma separated)";
      throw DataError::at(path, line, msg);
    }
    const auto t_ns = parseSecondsToNs(tok[0]);
    if (!t_ns) throw DataError::at(path, line, "field 't' is not a time in seconds: '" + tok[0] + "'");
    double v[8];
    for (int k = 1; k < 8; ++k) v[k] = parseField(tok[k], kFields[k], path, line);
    StampedPose p;
    p.t_ns = *t_ns;
    p.p_W_X = Eigen::Vector3d(v[1], v[2], v[3]);
    p.q_W_X = makeUnitQuaternion(v[7], v[4], v[5], v[6], path, line, "qx qy qz qw");
    checkOrder(traj.poses.empty() ? 0 : traj.poses.back().t_ns, p.t_ns, !traj.poses.empty(), path, line);
    traj.poses.push_back(p);
  }
  return traj;
}

namespace {

// Shared by both EuRoC readers: n_cols columns, the first 8 being t_ns, p, q (w first).
template <typename Row>
std::vector<Row> readEurocCsv(const std::string& path, size_t n_cols, const char* const* fields,
                              const char* columns_text, Row (*make)(const double*, int64_t, const std::string&, long)) {
  std::ifstream in = openOrThrow(path);
  std::vector<Row> rows;
  std::string raw;
  long line = 0;
  while (std::getline(in, raw)) {
    ++line;
    const std::string s = trim(raw);
    if (s.empty() || s[0] == '#') continue;
    const auto tok = splitComma(s);
    if (tok.size() != n_cols) {
      throw DataError::at(path, line, "expected " + std::to_string(n_cols) + " comma-separated columns (" +
                                          columns_text + "), found " + std::to_string(tok.size()));
    }
    const int64_t t_ns = parseNsField(tok[0], fields[0], path, line);
    double v[17];
    for (size_t k = 1; k < n_cols; ++k) v[k] = parseField(tok[k], fields[k], path, line);
    checkOrder(rows.empty() ? 0 : rows.back().t_ns, t_ns, !rows.empty(), path, line);
    rows.push_back(make(v, t_ns, path, line));
  }
  return rows;
}

const char* const kEurocFields[17] = {"timestamp", "p_x", "p_y", "p_z", "q_w", "q_x", "q_y", "q_z", "v_x",
                                      "v_y",       "v_z", "bg_x", "bg_y", "bg_z", "ba_x", "ba_y", "ba_z"};

GroundTruthState makeState(const double* v, int64_t t_ns, const std::string& path, long line) {
  GroundTruthState g;
  g.t_ns = t_ns;
  g.p_W_B = Eigen::Vector3d(v[1], v[2], v[3]);
  g.q_W_B = makeUnitQuaternion(v[4], v[5], v[6], v[7], path, line, "q_w q_x q_y q_z");
  g.v_W_B = Eigen::Vector3d(v[8], v[9], v[10]);
  g.bg = Eigen::Vector3d(v[11], v[12], v[13]);
  g.ba = Eigen::Vector3d(v[14], v[15], v[16]);
  return g;
}

StampedPose makePose(const double* v, int64_t t_ns, const std::string& path, long line) {
  StampedPose p;
  p.t_ns = t_ns;
  p.p_W_X = Eigen::Vector3d(v[1], v[2], v[3]);
  p.q_W_X = makeUnitQuaternion(v[4], v[5], v[6], v[7], path, line, "q_w q_x q_y q_z");
  return p;
}

}  // namespace

std::vector<GroundTruthState> readEurocStateGroundTruth(const std::string& path) {
  return readEurocCsv<GroundTruthState>(path, 17, kEurocFields, "t_ns, p xyz, q wxyz, v xyz, bg xyz, ba xyz",
                                        &makeState);
}

Trajectory readEurocMocap(const std::string& path) {
  Trajectory traj;
  traj.frame = PoseFrame::kBody;
  traj.source = path;
  traj.poses = readEurocCsv<StampedPose>(path, 8, kEurocFields, "t_ns, p xyz, q wxyz", &makePose);
  return traj;
}

Trajectory readGroundTruth(const std::string& path) {
  std::ifstream in = openOrThrow(path);
  std::string raw;
  long line = 0;
  while (std::getline(in, raw)) {
    ++line;
    const std::string s = trim(raw);
    if (s.empty() || s[0] == '#') continue;
    if (s.find(',') == std::string::npos) break;  // whitespace separated: TUM
    const size_t n_cols = splitComma(s).size();
    if (n_cols == 17) {
      // Straight to poses (every column still parsed and checked): no full GroundTruthState copy
      // beside them (on a 10-minute sequence at 200 Hz that copy was 16 MB of the run's peak memory).
      Trajectory traj;
      traj.frame = PoseFrame::kBody;
      traj.source = path;
      traj.poses = readEurocCsv<StampedPose>(path, 17, kEurocFields, "t_ns, p xyz, q wxyz, v xyz, bg xyz, ba xyz",
                                             &makePose);
      return traj;
    }
    if (n_cols == 8) return readEurocMocap(path);
    throw DataError::at(path, line, "comma-separated ground truth needs 17 columns (EuRoC state: t_ns, p, q, v, "
                                    "bg, ba) or 8 (EuRoC mocap: t_ns, p, q), found " + std::to_string(n_cols));
  }
  return readTum(path);
}

std::optional<std::string> findDatasetGroundTruth(const std::string& dataset_dir) {
  namespace fs = std::filesystem;
  for (const char* rel : {"mav0/state_groundtruth_estimate0/data.csv", "mav0/mocap0/data.csv"}) {
    const fs::path p = fs::path(dataset_dir) / rel;
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) return p.string();
  }
  return std::nullopt;
}

}  // namespace rsvio::io
