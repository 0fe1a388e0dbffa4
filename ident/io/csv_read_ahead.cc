// The read-ahead CSV reader (ident/io/csv_read_ahead.h): a ring of blocks, each filled by the reading thread
// and emptied by the caller, handed over by an atomic flag per block; or the segments of
// internal/plain_segments.h, then such a reader from the first line they do not take.
#include "ident/io/csv_read_ahead.h"

#include <algorithm>
#include <filesystem>
#include <system_error>

#include <fmt/format.h>

#include "common/error.h"
#include "ident/io/internal/csv_text.h"

namespace ident::io {

namespace {

// Values per block at most: wide files get blocks of fewer rows.
constexpr int kBlockValues = 1 << 16;

}  // namespace

CsvReadAhead::CsvReadAhead(const std::string& path, const CsvOptions& options, int threads) : options_(options) {
  auto reader = std::make_unique<CsvReader>(path, options);
  path_ = reader->path();
  names_ = reader->names();
  generated_names_ = reader->generated_names();
  const int n = num_columns();
  long file_size = 0;
  threads = std::min(threads, std::max(1, static_cast<int>(std::thread::hardware_concurrency())));
  if (threads >= 1 && ReadsInSegments(path, *reader, &file_size)) {
    segments_ = std::make_unique<internal::PlainSegments>(
        path, !generated_names_, file_size, internal::SeparatorOf(reader->delimiter()), n, threads, kSegmentBytes);
    return;
  }
  block_rows_ = std::clamp(kBlockValues / n, 1, kBlockRows);
  for (Block& block : blocks_) {
    block.values.resize(static_cast<std::size_t>(block_rows_) * static_cast<std::size_t>(n));
    block.lines.resize(static_cast<std::size_t>(block_rows_));
  }
  thread_ = std::thread(&CsvReadAhead::Read, this, std::move(reader));
}

bool CsvReadAhead::ReadsInSegments(const std::string& path, const CsvReader& reader, long* file_size) const {
  if (options_.on_read || options_.on_bytes || reader.delimiter() == Delimiter::kWhitespace || !CanReadTwice(path))
    return false;
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec || size < static_cast<std::uintmax_t>(kSegmentedFileBytes)) return false;
  *file_size =
      options_.prefix_bytes >= 0 ? std::min(static_cast<long>(size), options_.prefix_bytes) : static_cast<long>(size);
  return true;
}

CsvReadAhead::~CsvReadAhead() {
  if (!thread_.joinable()) return;
  stop_.store(true);
  for (Block& block : blocks_) {  // wakes the reading thread if it waits for a block
    block.full.store(false);
    block.full.notify_one();
  }
  thread_.join();
}

void CsvReadAhead::Read(std::unique_ptr<CsvReader> reader) {
  const int n = num_columns(), block_rows = block_rows_;
  for (int b = 0;; b = (b + 1) % kBlocks) {
    Block& block = blocks_[static_cast<std::size_t>(b)];
    block.full.wait(true, std::memory_order_acquire);  // until the caller has emptied it
    if (stop_.load()) return;
    int rows = 0;
    double* const values = block.values.data();
    long* const lines = block.lines.data();
    try {
      for (; rows < block_rows; ++rows) {
        if (!reader->Next(Eigen::Map<Eigen::VectorXd>(values + static_cast<std::ptrdiff_t>(rows) * n, n))) {
          block.last = true;
          break;
        }
        lines[rows] = reader->line();
      }
    } catch (...) {
      block.error = std::current_exception();
      block.last = true;
    }
    block.rows = rows;
    const bool last = block.last;
    block.full.store(true, std::memory_order_release);
    block.full.notify_one();
    if (last) return;
  }
}

const double* CsvReadAhead::NextRowOtherwise() {
  if (ended_) return nullptr;
  if (segments_) {  // their rows have ended
    const bool stopped = segments_->stopped();
    line_ = line();
    segments_.reset();
    if (!stopped) {
      ended_ = true;
      return nullptr;
    }
    // A line that is not a plain row: CsvReader reads on from there, after the rows given.
    rest_ = std::make_unique<CsvReadAhead>(path_, options_, 0);
    for (long r = 0; r < rows_; ++r)
      if (rest_->NextRow() == nullptr) throw DataError(fmt::format("{}: the file changed while it was read", path_));
  }
  if (rest_) {
    const double* const row = rest_->NextRow();
    line_ = rest_->line();
    ended_ = row == nullptr;
    return row;
  }
  while (!ended_) {
    Block& block = blocks_[static_cast<std::size_t>(block_)];
    if (!holding_) {
      block.full.wait(false, std::memory_order_acquire);  // until the reading thread has filled it
      holding_ = true;
      row_ = 0;
    }
    if (row_ < block.rows) {
      line_ = block.lines[static_cast<std::size_t>(row_)];
      return block.values.data() + static_cast<std::ptrdiff_t>(row_++) * num_columns();
    }
    if (block.last) {
      ended_ = true;
      if (block.error) std::rethrow_exception(block.error);
      return nullptr;
    }
    holding_ = false;
    block.full.store(false, std::memory_order_release);
    block.full.notify_one();
    block_ = (block_ + 1) % kBlocks;
  }
  return nullptr;
}

bool CsvReadAhead::Next(Eigen::Ref<Eigen::VectorXd> row) {
  IDENT_REQUIRE(row.size() == num_columns(), "row has {} entries; the file has {} columns", row.size(), num_columns());
  const double* const next = NextRow();
  if (next == nullptr) return false;
  row = Eigen::Map<const Eigen::VectorXd>(next, row.size());
  return true;
}

}  // namespace ident::io
