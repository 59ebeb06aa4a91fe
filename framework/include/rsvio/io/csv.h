// A small strict reader for delimited text files (EuRoC/ASL data.csv, DSO's times.txt, ...) whose every
// error names file, line, column and field, so a user can open the file at the right place:
//   mav0/imu0/data.csv:12:31: field 'a_RS_S_x': expected a number, found 'abc'
//
// Contract
// - Lines end in "\n" or "\r\n"; a UTF-8 byte-order mark at the start is skipped. Blank lines and lines
//   whose first non-blank character is the comment character ('#') are skipped: EuRoC's header line
//   "#timestamp [ns],filename" is such a comment. With skip_text_header, a first data row in which no
//   field is a number is taken as a header without '#' and skipped too; skippedHeaderLine() tells which
//   line that was, so a reader can say so (a corrupt first row must not vanish silently).
// - Fields are split on the delimiter (',') or on runs of blanks (Delimiter::kWhitespace); blanks around
//   a field are trimmed. There is no quoting: none of the formats rsvio reads quote.
// - Lines and columns are 1-based; a field's column is the column of its first character (of the place
//   it would be, for an empty field).
// - Numbers are parsed locale-independently (std::from_chars) and must use the whole field. getDouble
//   accepts "nan" and "inf" and returns them, so the caller decides what a non-finite value means (the
//   IMU reader drops such samples); getFiniteDouble rejects them.
// - rowUnterminated() is true for the file's last line when it has no newline: a short row there is
//   most likely a truncated write (an interrupted copy or download), which a reader may treat more
//   leniently than a malformed row in the middle of a file.
// - Nothing here crashes or exits on bad input: errors are DataError (rsvio/core/error.h).
#pragma once
#include <cstdint>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rsvio/core/error.h"

namespace rsvio::io {

struct CsvFormat {
  enum class Delimiter { kComma, kWhitespace };
  Delimiter delimiter = Delimiter::kComma;
  char comment = '#';
  bool skip_text_header = false;  // skip a first data row in which no field is a number
};

class CsvReader {
 public:
  // Opens `path`; throws DataError "path: cannot open file" when it is missing or unreadable.
  // `fields` names the expected columns in order; messages use these names ("column N" beyond them).
  CsvReader(std::string path, std::vector<std::string> fields, CsvFormat format = {});

  // Advances to the next data row. Returns false at the end of the file.
  bool next();

  const std::string& path() const { return path_; }
  long line() const { return line_; }
  size_t size() const { return values_.size(); }
  bool rowUnterminated() const { return unterminated_; }
  const std::vector<std::string>& fieldNames() const { return names_; }
  long skippedHeaderLine() const { return header_line_; }  // 0 when no header row was skipped

  const std::string& raw(size_t i) const;  // field text, trimmed ("" beyond the row's fields)
  int column(size_t i) const;              // 1-based column of field i
  std::string fieldName(size_t i) const;   // fields[i] or "column N"

  // Throws "path:line: expected N fields (a, b, c), found M" unless the row has exactly the named fields.
  void expectFieldCount() const;
  // Same with a range (for formats with optional trailing columns).
  void expectFieldCount(size_t min_fields, size_t max_fields) const;

  int64_t getInt64(size_t i) const;       // integer, e.g. a nanosecond timestamp
  double getDouble(size_t i) const;       // number; nan and inf accepted
  double getFiniteDouble(size_t i) const; // number; nan and inf rejected
  const std::string& getString(size_t i) const;  // non-empty text

  // "path:line:col: field 'name': msg" for field i; "path:line: msg" for the row.
  DataError errorAt(size_t i, const std::string& msg) const;
  DataError error(const std::string& msg) const;

 private:
  bool readLine(std::string& text);
  void split(const std::string& text);

  std::string path_;
  std::vector<std::string> names_;
  CsvFormat format_;
  std::ifstream in_;
  long line_ = 0;
  bool first_data_row_ = true;
  long header_line_ = 0;
  bool unterminated_ = false;
  std::vector<std::string> values_;
  std::vector<int> columns_;
};

// Parsers usable without a reader; nullopt when the text is not entirely a number.
std::optional<int64_t> parseInt64(std::string_view text);
std::optional<double> parseDouble(std::string_view text);  // accepts nan / inf (any case), leading '+'

// Quotes a found value for messages, shortened to `max_chars`: 'abc', '' for empty.
std::string quoteFound(std::string_view text, size_t max_chars = 40);

}  // namespace rsvio::io
