// The data lines of a large CSV file parsed on several threads at once and handed over in file order: the
// parallel path of ident/io/csv_read_ahead.h.
//
// The data (after the file's first line, its header, or from its start) are cut into segments of about `segment_bytes`; a
// line belongs to the segment in which it starts. Worker w parses segments w, w + W, w + 2W, … into a ring of
// blocks of its own, and Next() takes the rings in turn, one segment at a time. Only plain lines are taken:
// every line one row whose cells ParsePlainFields converts (csv_text.h). At the first line that is anything
// else (blank, a comment, CR, a space, an empty, bad or non-finite cell, a wrong number of fields, a line
// longer than kMaxCsvLineBytes) Next() returns false with stopped() true, after every row before it; the caller
// reads on from there with CsvReader, which reads that line as it would anyway (a row, a skipped line or a
// DataError). Memory: per worker one segment buffer and kBlocks blocks.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace ident::io::internal {

class PlainSegments {
 public:
  static constexpr int kBlocks = 4;
  // The tail past a segment's end is read in steps of this many bytes, as far as its last line needs.
  static constexpr long kTailStep = 1 << 12;

  // Starts `workers` threads on the file of `file_size` bytes. With `header`, the data start after the first
  // line, which must be what CsvReader takes for the header: not blank, not a comment, ended by LF (no CR).
  // Otherwise, or with an unreadable file, Next() stops at once (stopped() true).
  PlainSegments(const std::string& path, bool header, long file_size, char separator, int columns, int workers,
                long segment_bytes);
  ~PlainSegments();
  PlainSegments(const PlainSegments&) = delete;
  PlainSegments& operator=(const PlainSegments&) = delete;

  // The next row: `columns` values, valid until the next call; null at the end of the file or where the plain
  // lines stop. Inline while the current block has rows.
  const double* NextRow() {
    if (row_ < held_rows_) [[likely]]
      return held_ + static_cast<std::ptrdiff_t>(row_++) * columns_;
    return NextBlockRow();
  }
  // The same copied into row[0..columns); false at the end of the file or where the plain lines stop.
  bool Next(double* row) {
    const double* const next = NextRow();
    if (next == nullptr) return false;
    std::copy_n(next, columns_, row);
    return true;
  }
  bool stopped() const { return stopped_; }
  // The line number of the first row: 2 after a header, else 1.
  long first_line() const { return data_start_ > 0 ? 2 : 1; }

 private:
  enum class Ending { kNone, kSegment, kFile, kStop };
  struct alignas(64) Block {
    std::vector<double> values;  // rows × columns, row by row
    int rows = 0;
    Ending ending = Ending::kNone;
    std::atomic<bool> full{false};  // written by the worker, emptied by Next()
  };
  struct Ring {
    std::array<Block, kBlocks> blocks;
    alignas(64) int next = 0;  // the block the worker fills next
  };

  long DataStart(bool header) const;  // -1: the first line is not a plain header
  void Work(int worker);              // a worker thread
  Ending ParseSegment(long segment, Ring& ring, std::vector<char>& buffer);
  Block* Acquire(Ring& ring);    // the ring's next block once it is empty; null when stopping
  const double* NextBlockRow();  // NextRow() past the end of the block held (or before the first)
  void Publish(Ring& ring, Block& block, Ending ending);

  // Set before the workers start, read by all.
  int fd_ = -1;
  long data_start_ = 0, file_size_, segment_bytes_, segments_ = 0;
  char separator_;
  int columns_, block_rows_;
  std::vector<std::unique_ptr<Ring>> rings_;
  // NextRow()'s, written at every row: a cache line of its own. The ring of the current segment, the block held
  // (its values and rows; no rows while none is held) and the next row in it, per ring the block NextRow() reads.
  alignas(64) int ring_ = 0;
  int row_ = 0, held_rows_ = 0;
  const double* held_ = nullptr;
  bool holding_ = false, ended_ = false, stopped_ = false;
  std::vector<int> taken_;
  alignas(64) std::atomic<bool> stop_{false};
  std::vector<std::thread> threads_;
};

}  // namespace ident::io::internal
