// Reading a CSV file's rows while they are used, a few blocks of rows ahead of the caller, on other threads.
//
// A large regular file whose first line is its header (or first row) is cut into segments that `threads`
// threads parse in turn (internal/plain_segments.h), for as long as its lines are plain rows; from the first
// line that is not, a CsvReader on one thread reads on. Any other input is read by a CsvReader on one thread.
// More than one thread pays where the caller does little with each row (a sum, a count); where its work per
// row is as large as the parsing, one thread keeps up.
//
// The rows, their line numbers and the reader's errors arrive in file order, as CsvReader::Next gives
// them: a DataError at some row is thrown by the Next() that would have returned that row, after every
// row before it. Parsing (most of what reading a long record costs) overlaps with the caller's work on the
// rows before; memory stays constant (a few blocks of at most kBlockRows rows, and one segment per thread).
// Destroying the reader early stops the threads. CsvOptions::on_read and on_bytes, if set, are called on the
// reading thread (such a reader takes the CsvReader path).
//
// Example:
//   ident::io::CsvReadAhead reader("long.csv");
//   Eigen::VectorXd row(reader.num_columns());
//   while (reader.Next(row)) { ... }   // row and reader.line() as CsvReader's
#pragma once

#include <array>
#include <atomic>
#include <exception>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Core>

#include "ident/io/csv.h"
#include "ident/io/internal/plain_segments.h"

namespace ident::io {

class CsvReadAhead {
 public:
  static constexpr int kBlocks = 4;
  static constexpr int kBlockRows = 2048;
  // Files of at least this many bytes are read in segments.
  static constexpr long kSegmentedFileBytes = 8L << 20;
  static constexpr long kSegmentBytes = 1L << 20;

  // Opens the file and reads its header on the calling thread (throws DataError as CsvReader does), then
  // starts reading rows: segments on `threads` threads (at most the machine's cores), or, with `threads` 0 or
  // a file that is not read in segments, a CsvReader.
  explicit CsvReadAhead(const std::string& path, const CsvOptions& options = {}, int threads = 1);
  ~CsvReadAhead();
  CsvReadAhead(const CsvReadAhead&) = delete;
  CsvReadAhead& operator=(const CsvReadAhead&) = delete;

  const std::string& path() const { return path_; }
  const std::vector<std::string>& names() const { return names_; }
  int num_columns() const { return static_cast<int>(names_.size()); }
  bool generated_names() const { return generated_names_; }
  // As CsvReader::Next: the next row into `row` (size num_columns()), false at the end; throws the
  // reader's DataError at the row where it arose.
  bool Next(Eigen::Ref<Eigen::VectorXd> row);
  // The same row in place: num_columns() values, valid until the next call; null at the end. Throws as Next().
  // Inline while the segments' current block has rows.
  const double* NextRow() {
    if (segments_) [[likely]] {
      if (const double* const row = segments_->NextRow()) [[likely]] {
        ++rows_;
        return row;
      }
    }
    return NextRowOtherwise();
  }
  // 1-based line number of the row last returned by Next() or NextRow().
  long line() const { return segments_ ? segments_->first_line() + rows_ - 1 : line_; }

 private:
  // Rows [0, rows) of a block; then, if `last`, the end of the file or `error`. A cache line of its own:
  // the two threads work on different blocks.
  struct alignas(64) Block {
    std::vector<double> values;  // rows × columns, row by row
    std::vector<long> lines;
    int rows = 0;
    bool last = false;
    std::exception_ptr error;
    std::atomic<bool> full{false};  // written by the reading thread, emptied by the caller
  };

  void Read(std::unique_ptr<CsvReader> reader);  // the reading thread
  // Whether the file is one to read in segments (*file_size its size): a large regular file, read without
  // CsvOptions::on_read and on_bytes, whose delimiter is one character. PlainSegments checks its first line.
  bool ReadsInSegments(const std::string& path, const CsvReader& reader, long* file_size) const;
  // NextRow() where the segments give no row: after their last, from the reader that goes on from there, or
  // from the reading thread's blocks.
  const double* NextRowOtherwise();

  // Set before the reading thread starts, read by both.
  std::string path_;
  std::vector<std::string> names_;
  bool generated_names_ = false;
  int block_rows_ = kBlockRows;  // rows per block: fewer for wide files (at most 65 536 values a block)
  // The caller's: its block, the next row in it, whether it has waited for the block to be filled, the line of
  // the last row (while not in segments). A cache line of its own, written at every row.
  alignas(64) int block_ = 0;
  int row_ = 0;
  bool holding_ = false;
  bool ended_ = false;
  long line_ = 0;
  std::array<Block, kBlocks> blocks_;
  alignas(64) std::atomic<bool> stop_{false};
  std::thread thread_;
  // The segments, the rows given from them; then the reader that goes on from the first line that is not a
  // plain row.
  CsvOptions options_;
  std::unique_ptr<internal::PlainSegments> segments_;
  long rows_ = 0;
  std::unique_ptr<CsvReadAhead> rest_;
};

}  // namespace ident::io
