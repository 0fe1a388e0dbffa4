// The header of a CSV file and its delimiter (ident/io/csv.h): detection among ',', ';', tab and runs of
// spaces, the column names, and the messages that show cells and names.
#include "ident/io/csv.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "common/error.h"
#include "ident/io/internal/csv_text.h"

namespace ident::io {

using internal::CountFields;
using internal::IsBlank;
using internal::IsComment;
using internal::IsSpace;
using internal::SeparatorOf;
using internal::Trim;

namespace {

// Splits on `separator` (0: runs of spaces and tabs) into `fields` (views into `line`).
void Split(std::string_view line, char separator, std::vector<std::string_view>& fields) {
  fields.clear();
  if (separator == 0) {
    std::size_t pos = 0;
    while (true) {
      while (pos < line.size() && (IsSpace(line[pos]) || line[pos] == '\r')) ++pos;
      if (pos == line.size()) break;
      std::size_t end = pos;
      while (end < line.size() && !IsSpace(line[end]) && line[end] != '\r') ++end;
      fields.push_back(line.substr(pos, end - pos));
      pos = end;
    }
    return;
  }
  std::size_t start = 0;
  while (true) {
    const std::size_t at = line.find(separator, start);
    fields.push_back(Trim(line.substr(start, at == std::string_view::npos ? at : at - start)));
    if (at == std::string_view::npos) break;
    start = at + 1;
  }
}

// True if every field is a number (NaN and Inf included) or empty and at least one is a finite number:
// the line is data, not a header.
bool AllNumbers(const std::vector<std::string_view>& fields) {
  bool finite = false;
  for (std::string_view f : fields) {
    if (f.empty()) continue;
    if (f.front() == '+') f.remove_prefix(1);
    double v = 0;
    const auto [ptr, ec] = std::from_chars(f.data(), f.data() + f.size(), v);
    if (ptr != f.data() + f.size() || f.empty() || (ec != std::errc() && ec != std::errc::result_out_of_range))
      return false;
    finite = finite || (ec == std::errc() && std::isfinite(v));
  }
  return finite;
}

Delimiter DelimiterOf(char separator) {
  switch (separator) {
    case ';':
      return Delimiter::kSemicolon;
    case '\t':
      return Delimiter::kTab;
    case 0:
      return Delimiter::kWhitespace;
    default:
      return Delimiter::kComma;
  }
}

// Detection (see csv.h). The one of ',', ';' and tab that splits the header; when several do, the one
// that splits the first data line (`data`, null if none) into as many fields, and when two still fit
// (or none does), both in `ambiguous` (*fits_data: whether they fit the data line). When none splits
// the header: whitespace (0) if runs of spaces split the header and the data line, else ',' (one column).
char DetectSeparator(std::string_view header, const std::string_view* data, std::pair<char, char>* ambiguous,
                     bool* fits_data) {
  *fits_data = true;
  std::vector<char> fit, splits;
  for (const char c : {',', ';', '\t'}) {
    const std::size_t h = CountFields(header, c);
    if (h > 1) splits.push_back(c);
    if (h > 1 && (data == nullptr || CountFields(*data, c) == h)) fit.push_back(c);
  }
  if (splits.size() == 1) return splits[0];  // the rows will say what does not fit
  if (splits.size() > 1) {
    if (fit.size() == 1) return fit[0];
    *fits_data = fit.size() > 1;
    *ambiguous = fit.size() > 1 ? std::pair{fit[0], fit[1]} : std::pair{splits[0], splits[1]};
    return ',';
  }
  if (CountFields(header, 0) > 1 && (data == nullptr || CountFields(*data, 0) > 1)) return 0;
  return ',';  // one column
}

// True if DetectSeparator (or the check of a given delimiter) needs the first data line: the header
// alone does not decide. Otherwise the reader reads no line ahead (a stream's header is checked as soon
// as it arrives).
bool NeedsDataLine(std::string_view header, Delimiter given) {
  if (given != Delimiter::kAuto) return CountFields(header, SeparatorOf(given)) == 1;
  int splits = 0;
  for (const char c : {',', ';', '\t'}) splits += CountFields(header, c) > 1;
  return splits > 1 || (splits == 0 && CountFields(header, 0) > 1);
}

constexpr std::size_t kShownBytes = 32;     // of a cell or name echoed in a message
constexpr std::size_t kListedColumns = 20;  // names listed by ThrowUnknownColumn

// The bytes of `s` as a message shows them (no quotes): control bytes as \xNN, at most kShownBytes of
// them (cut at a UTF-8 character boundary) and "..." if there are more.
std::string Shown(std::string_view s) {
  std::size_t n = std::min(s.size(), kShownBytes);
  if (n < s.size())
    while (n > 0 && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;  // not inside a character
  std::string out;
  out.reserve(n + 8);
  for (const char c : s.substr(0, n)) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7F)
      out += fmt::format("\\x{:02x}", u);
    else
      out += c;
  }
  if (n < s.size()) out += "...";
  return out;
}

}  // namespace

std::string ShowCell(std::string_view cell) {
  if (cell.size() <= kShownBytes) return fmt::format("'{}'", Shown(cell));
  return fmt::format("'{}' ({} bytes)", Shown(cell), cell.size());
}

Delimiter ParseDelimiter(std::string_view text) {
  if (text == "auto") return Delimiter::kAuto;
  if (text == ",") return Delimiter::kComma;
  if (text == ";") return Delimiter::kSemicolon;
  if (text == "tab" || text == "\t") return Delimiter::kTab;
  if (text == "space" || text == " ") return Delimiter::kWhitespace;
  throw InvalidArgument(fmt::format("delimiter {}: need ',', ';', tab, space or auto", ShowCell(text)));
}

std::string DelimiterName(Delimiter delimiter) {
  switch (delimiter) {
    case Delimiter::kAuto:
      return "auto";
    case Delimiter::kComma:
      return "','";
    case Delimiter::kSemicolon:
      return "';'";
    case Delimiter::kTab:
      return "tab";
    case Delimiter::kWhitespace:
      return "space";
  }
  return "?";
}

[[noreturn]] void ThrowUnknownColumn(const std::string& source, std::string_view name,
                                     const std::vector<std::string>& names) {
  std::string listed;
  for (std::size_t i = 0; i < names.size() && i < kListedColumns; ++i) listed += (i ? ", " : "") + Shown(names[i]);
  if (names.size() > kListedColumns) listed += fmt::format(", ... ({} columns)", names.size());
  throw DataError(fmt::format("{}: no column '{}' (columns: {})", source, Shown(name), listed));
}

void CsvReader::ReadHeader() {
  const std::string& path = path_;
  // Header: the first line that is neither blank nor a comment.
  bool got_header = false;
  while (ReadLine()) {
    if (line_ == 1 && text_.starts_with("\xEF\xBB\xBF")) text_.remove_prefix(3);
    if (!IsBlank(text_) && !IsComment(text_)) {
      got_header = true;
      break;
    }
  }
  if (!got_header) throw DataError(fmt::format("{}: the file is empty", path));
  header_.assign(text_);
  header_line_ = line_;
  // The first data line, read ahead for the delimiter when the header does not decide it, and held for
  // Next().
  const bool read_ahead = NeedsDataLine(header_, options_.delimiter);
  while (read_ahead && ReadLine()) {
    if (!IsBlank(text_) && !IsComment(text_)) {
      held_row_.assign(text_);
      held_ = true;
      held_line_ = line_;
      break;
    }
  }
  const std::string_view data_line(held_row_);
  ChooseDelimiter(header_, held_ ? &data_line : nullptr);
  std::vector<std::string_view> fields;
  Split(header_, separator_, fields);
  if (fields.size() > static_cast<std::size_t>(kMaxCsvColumns))
    throw DataError(fmt::format("{}:{}: the header has {} columns; at most {} are supported", path, header_line_,
                                fields.size(), kMaxCsvColumns));
  if (AllNumbers(fields)) {  // no header: the line is the first row
    generated_names_ = true;
    names_.reserve(fields.size());
    for (std::size_t j = 0; j < fields.size(); ++j) names_.push_back(fmt::format("c{}", j + 1));
    header_is_row_ = true;
    return;
  }
  std::unordered_map<std::string_view, std::size_t> seen;  // name (a view into header_) -> 0-based column
  seen.reserve(fields.size());
  names_.reserve(fields.size());
  for (std::size_t j = 0; j < fields.size(); ++j) {
    std::string_view name = fields[j];
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"') name = name.substr(1, name.size() - 2);
    if (name.empty()) throw DataError(fmt::format("{}:{}: column {} has an empty name", path, header_line_, j + 1));
    if (name.find('\0') != std::string_view::npos)
      throw DataError(fmt::format("{}:{}: column {} name contains a NUL byte", path, header_line_, j + 1));
    const auto [it, inserted] = seen.emplace(name, j);
    if (!inserted)
      throw DataError(fmt::format("{}:{}: duplicate column name {} (columns {} and {})", path, header_line_,
                                  ShowCell(name), it->second + 1, j + 1));
    names_.emplace_back(name);
  }
  header_.clear();
  header_.shrink_to_fit();
}

void CsvReader::ChooseDelimiter(std::string_view header, const std::string_view* data) {
  std::pair<char, char> ambiguous{0, 0};
  bool fits_data = true;
  const char detected = DetectSeparator(header, data, &ambiguous, &fits_data);
  if (options_.delimiter == Delimiter::kAuto) {
    if (ambiguous.first != 0)
      throw DataError(
          fmt::format("{}:{}: cannot tell the delimiter: {} and {} both split the header{} into several fields (pass "
                      "--delimiter)",
                      path_, header_line_, DelimiterName(DelimiterOf(ambiguous.first)),
                      DelimiterName(DelimiterOf(ambiguous.second)),
                      data && fits_data ? fmt::format(" and line {}", held_line_) : ""));
    delimiter_ = DelimiterOf(detected);
    separator_ = detected;
    return;
  }
  delimiter_ = options_.delimiter;
  separator_ = SeparatorOf(delimiter_);
  // A header of one column that another delimiter splits as it splits the first data line: a wrong
  // --delimiter.
  if (CountFields(header, separator_) == 1 && ambiguous.first == 0 && detected != separator_ &&
      CountFields(header, detected) > 1 && data != nullptr &&
      CountFields(*data, detected) == CountFields(header, detected))
    throw DataError(
        fmt::format("{}:{}: the header has one column with the delimiter {}; the file looks {}-separated (pass "
                    "--delimiter {})",
                    path_, header_line_, DelimiterName(delimiter_), DelimiterName(DelimiterOf(detected)),
                    DelimiterName(DelimiterOf(detected))));
}

int CsvReader::ColumnIndex(std::string_view name) const {
  for (std::size_t i = 0; i < names_.size(); ++i)
    if (names_[i] == name) return static_cast<int>(i);
  ThrowUnknownColumn(path_, name, names_);
}

char internal::SeparatorOf(Delimiter d) {
  switch (d) {
    case Delimiter::kSemicolon:
      return ';';
    case Delimiter::kTab:
      return '\t';
    case Delimiter::kWhitespace:
      return 0;
    default:
      return ',';
  }
}

}  // namespace ident::io
