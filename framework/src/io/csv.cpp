// Strict delimited-text reader (contract in rsvio/io/csv.h).
#include "rsvio/io/csv.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>

namespace rsvio::io {
namespace {

bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

}  // namespace

std::optional<int64_t> parseInt64(std::string_view text) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  if (text.empty()) return std::nullopt;
  int64_t v = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || ptr != text.data() + text.size()) return std::nullopt;
  return v;
}

std::optional<double> parseDouble(std::string_view text) {
  bool negative = false;
  std::string_view body = text;
  if (!body.empty() && (body.front() == '+' || body.front() == '-')) {
    negative = body.front() == '-';
    body.remove_prefix(1);
  }
  if (body.empty()) return std::nullopt;
  if (!(std::isdigit(static_cast<unsigned char>(body.front())) || body.front() == '.')) {
    // from_chars accepts "nan"/"inf" too, but spell the special values out so "nan(...)" junk and
    // "infinity" behave predictably across standard libraries.
    const std::string l = lower(body);
    if (l == "nan") return std::numeric_limits<double>::quiet_NaN();
    if (l == "inf" || l == "infinity")
      return negative ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
    return std::nullopt;
  }
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(body.data(), body.data() + body.size(), v);
  // Out-of-range magnitudes (1e999) are reported as not-a-number text rather than clamped silently.
  if (ec != std::errc() || ptr != body.data() + body.size()) return std::nullopt;
  return negative ? -v : v;
}

std::string quoteFound(std::string_view text, size_t max_chars) {
  std::string s;
  for (char c : text.substr(0, max_chars))
    s += std::isprint(static_cast<unsigned char>(c)) ? c : '?';  // binary junk must not break the line
  if (text.size() > max_chars) s += "...";
  return "'" + s + "'";
}

CsvReader::CsvReader(std::string path, std::vector<std::string> fields, CsvFormat format)
    : path_(std::move(path)), names_(std::move(fields)), format_(format) {
  in_.open(path_, std::ios::binary);
  if (!in_) throw DataError::at(path_, 0, "cannot open file");
}

bool CsvReader::readLine(std::string& text) {
  if (!std::getline(in_, text)) return false;
  ++line_;
  // getline sets eof when the last line had no '\n' to consume.
  unterminated_ = in_.eof();
  if (line_ == 1 && text.size() >= 3 && static_cast<unsigned char>(text[0]) == 0xEF &&
      static_cast<unsigned char>(text[1]) == 0xBB && static_cast<unsigned char>(text[2]) == 0xBF)
    text.erase(0, 3);
  if (!text.empty() && text.back() == '\r') text.pop_back();
  return true;
}

void CsvReader::split(const std::string& text) {
  values_.clear();
  columns_.clear();
  const size_t n = text.size();
  if (format_.delimiter == CsvFormat::Delimiter::kWhitespace) {
    size_t i = 0;
    while (i < n) {
      while (i < n && isBlank(text[i])) ++i;
      if (i >= n) break;
      const size_t b = i;
      while (i < n && !isBlank(text[i])) ++i;
      values_.push_back(text.substr(b, i - b));
      columns_.push_back(static_cast<int>(b) + 1);
    }
    return;
  }
  size_t start = 0;
  while (true) {
    size_t end = text.find(',', start);
    if (end == std::string::npos) end = n;
    size_t b = start, e = end;
    while (b < e && isBlank(text[b])) ++b;
    while (e > b && isBlank(text[e - 1])) --e;
    values_.push_back(text.substr(b, e - b));
    columns_.push_back(static_cast<int>(b) + 1);
    if (end == n) break;
    start = end + 1;
  }
}

bool CsvReader::next() {
  std::string text;
  while (readLine(text)) {
    size_t first = 0;
    while (first < text.size() && isBlank(text[first])) ++first;
    if (first == text.size() || text[first] == format_.comment) continue;
    split(text);
    if (first_data_row_) {
      first_data_row_ = false;
      if (format_.skip_text_header &&
          std::none_of(values_.begin(), values_.end(), [](const std::string& v) { return parseDouble(v).has_value(); })) {
        header_line_ = line_;
        continue;
      }
    }
    return true;
  }
  values_.clear();
  columns_.clear();
  return false;
}

const std::string& CsvReader::raw(size_t i) const {
  static const std::string kEmpty;
  return i < values_.size() ? values_[i] : kEmpty;
}

int CsvReader::column(size_t i) const {
  if (i < columns_.size()) return columns_[i];
  return columns_.empty() ? 1 : columns_.back() + static_cast<int>(values_.back().size());
}

std::string CsvReader::fieldName(size_t i) const {
  return i < names_.size() ? names_[i] : "column " + std::to_string(i + 1);
}

DataError CsvReader::errorAt(size_t i, const std::string& msg) const {
  return DataError(path_ + ":" + std::to_string(line_) + ":" + std::to_string(column(i)) + ": field '" +
                   fieldName(i) + "': " + msg);
}

DataError CsvReader::error(const std::string& msg) const { return DataError::at(path_, line_, msg); }

void CsvReader::expectFieldCount() const { expectFieldCount(names_.size(), names_.size()); }

void CsvReader::expectFieldCount(size_t min_fields, size_t max_fields) const {
  const size_t n = values_.size();
  if (n >= min_fields && n <= max_fields) return;
  std::string names;
  for (size_t i = 0; i < std::min(max_fields, names_.size()); ++i) names += (i ? ", " : "") + names_[i];
  const std::string want = min_fields == max_fields ? std::to_string(min_fields)
                                                    : std::to_string(min_fields) + " to " + std::to_string(max_fields);
  throw error("expected " + want + " fields (" + names + "), found " + std::to_string(n));
}

int64_t CsvReader::getInt64(size_t i) const {
  const std::string& s = raw(i);
  if (s.empty()) throw errorAt(i, "expected an integer, found an empty field");
  const auto v = parseInt64(s);
  if (!v) throw errorAt(i, "expected an integer, found " + quoteFound(s));
  return *v;
}

double CsvReader::getDouble(size_t i) const {
  const std::string& s = raw(i);
  if (s.empty()) throw errorAt(i, "expected a number, found an empty field");
  const auto v = parseDouble(s);
  if (!v) throw errorAt(i, "expected a number, found " + quoteFound(s));
  return *v;
}

double CsvReader::getFiniteDouble(size_t i) const {
  const double v = getDouble(i);
  if (!std::isfinite(v)) throw errorAt(i, "expected a finite number, found " + quoteFound(raw(i)));
  return v;
}

const std::string& CsvReader::getString(size_t i) const {
  const std::string& s = raw(i);
  if (s.empty()) throw errorAt(i, "expected text, found an empty field");
  return s;
}

}  // namespace rsvio::io
