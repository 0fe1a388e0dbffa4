// The parallel path of the read-ahead CSV reader (plain_segments.h): workers that parse segments of a file
// into rings of blocks, and the caller's side that takes the segments in file order.
#include "ident/io/internal/plain_segments.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string_view>

#include "ident/io/csv.h"
#include "ident/io/internal/csv_text.h"

namespace ident::io::internal {

namespace {

// Values per block at most, as in the sequential reader.
constexpr int kBlockValues = 1 << 16;

// Reads [offset, offset + size) of fd into `out`; false on an error or a short read (the file changed).
bool ReadAt(int fd, long offset, std::size_t size, char* out) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t got = ::pread(fd, out + done, size - done, static_cast<off_t>(offset + static_cast<long>(done)));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    done += static_cast<std::size_t>(got);
  }
  return true;
}

}  // namespace

PlainSegments::PlainSegments(const std::string& path, bool header, long file_size, char separator, int columns,
                             int workers, long segment_bytes)
    : file_size_(file_size),
      segment_bytes_(segment_bytes),
      separator_(separator),
      columns_(columns),
      block_rows_(std::clamp(kBlockValues / columns, 1, 2048)),
      taken_(static_cast<std::size_t>(workers), 0) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  data_start_ = fd_ < 0 ? -1 : DataStart(header);
  if (data_start_ < 0 || data_start_ >= file_size_) {
    data_start_ = 0;
    ended_ = stopped_ = true;
    return;
  }
  segments_ = (file_size - data_start_ + segment_bytes - 1) / segment_bytes;
  for (int w = 0; w < workers; ++w) {
    rings_.push_back(std::make_unique<Ring>());
    for (Block& block : rings_.back()->blocks)
      block.values.resize(static_cast<std::size_t>(block_rows_) * static_cast<std::size_t>(columns_));
  }
  for (int w = 0; w < workers; ++w) threads_.emplace_back(&PlainSegments::Work, this, w);
}

long PlainSegments::DataStart(bool header) const {
  if (!header) return 0;
  // The header's line end: in the first 64 KiB as a rule, else within the line length limit.
  std::string head;
  std::size_t lf = std::string::npos;
  for (long want = std::min<long>(file_size_, 1 << 16); lf == std::string::npos;
       want = std::min<long>(file_size_, kMaxCsvLineBytes)) {
    if (want <= std::ssize(head)) return -1;  // no LF within the limit
    head.assign(static_cast<std::size_t>(want), '\0');
    if (!ReadAt(fd_, 0, head.size(), head.data())) return -1;
    lf = head.find('\n');
  }
  std::size_t first = head.starts_with("\xEF\xBB\xBF") ? 3 : 0;  // a byte-order mark, which CsvReader skips
  if (first >= head.size() || std::string_view(" \t\r\n#").find(head[first]) != std::string_view::npos) return -1;
  if (head.find('\r') < lf) return -1;
  return static_cast<long>(lf) + 1;
}

PlainSegments::~PlainSegments() {
  stop_.store(true);
  for (auto& ring : rings_) {
    for (Block& block : ring->blocks) {  // wakes a worker that waits for a block
      block.full.store(false);
      block.full.notify_all();
    }
  }
  for (std::thread& t : threads_) t.join();
  if (fd_ >= 0) ::close(fd_);
}

void PlainSegments::Work(int worker) {
  Ring& ring = *rings_[static_cast<std::size_t>(worker)];
  std::vector<char> buffer;
  const long stride = static_cast<long>(rings_.size());
  for (long segment = worker; segment < segments_; segment += stride)
    if (ParseSegment(segment, ring, buffer) != Ending::kSegment) return;
}

void PlainSegments::Publish(Ring& ring, Block& block, Ending ending) {
  block.ending = ending;
  block.full.store(true, std::memory_order_release);
  block.full.notify_one();
  ring.next = (ring.next + 1) % kBlocks;
}

PlainSegments::Block* PlainSegments::Acquire(Ring& ring) {
  Block& block = ring.blocks[static_cast<std::size_t>(ring.next)];
  block.full.wait(true, std::memory_order_acquire);  // until Next() has emptied it
  if (stop_.load()) return nullptr;
  block.rows = 0;
  return &block;
}

PlainSegments::Ending PlainSegments::ParseSegment(long segment, Ring& ring, std::vector<char>& buffer) {
  Block* block = Acquire(ring);
  if (block == nullptr) return Ending::kStop;
  const int columns = columns_, block_rows = block_rows_;
  const char separator = separator_;
  // buffer = bytes [from, to) of the file: the segment [begin, end), the byte before it (does a line start at
  // begin?) and a tail, read on as far as the segment's last line needs (at most a line's length limit).
  const long begin = data_start_ + segment * segment_bytes_, end = std::min(begin + segment_bytes_, file_size_);
  const long from = segment == 0 ? begin : begin - 1;
  long to = std::min(end + kTailStep, file_size_);
  const long limit = std::min(end + static_cast<long>(kMaxCsvLineBytes), file_size_);
  buffer.resize(static_cast<std::size_t>(to - from));
  bool ok = ReadAt(fd_, from, buffer.size(), buffer.data());
  long p = 0;               // offset in buffer of the line to parse
  if (ok && segment > 0) {  // the first line that starts in [begin, end)
    const void* lf = std::memchr(buffer.data(), '\n', static_cast<std::size_t>(end - 1 - from));
    p = lf != nullptr ? static_cast<const char*>(lf) - buffer.data() + 1 : end - from;
  }
  while (ok && p < end - from) {
    const void* lf = std::memchr(buffer.data() + p, '\n', buffer.size() - static_cast<std::size_t>(p));
    if (lf == nullptr && to < limit) {  // read more of the tail
      const long more = std::min(to + kTailStep, limit);
      buffer.resize(static_cast<std::size_t>(more - from));
      ok = ReadAt(fd_, to, static_cast<std::size_t>(more - to), buffer.data() + (to - from));
      to = more;
      continue;
    }
    if (lf == nullptr && to < file_size_) break;  // a line longer than the limit
    const char* const line = buffer.data() + p;
    const char* const line_end = lf != nullptr ? static_cast<const char*>(lf) : buffer.data() + buffer.size();
    double* const out = block->values.data() + static_cast<std::ptrdiff_t>(block->rows) * columns;
    if (!ParsePlainFields(line, line_end, separator, columns, out)) break;
    p = line_end + 1 - buffer.data();
    if (++block->rows == block_rows) {
      Publish(ring, *block, Ending::kNone);
      if ((block = Acquire(ring)) == nullptr) return Ending::kStop;
    }
  }
  const Ending ending = !ok || p < end - from ? Ending::kStop : end == file_size_ ? Ending::kFile : Ending::kSegment;
  Publish(ring, *block, ending);
  return ending;
}

const double* PlainSegments::NextBlockRow() {
  while (!ended_) {
    const std::size_t r = static_cast<std::size_t>(ring_);
    Block& block = rings_[r]->blocks[static_cast<std::size_t>(taken_[r])];
    if (!holding_) {
      block.full.wait(false, std::memory_order_acquire);  // until the worker has filled it
      holding_ = true;
      held_ = block.values.data();
      held_rows_ = block.rows;
      row_ = 0;
      if (row_ < held_rows_) return held_ + static_cast<std::ptrdiff_t>(row_++) * columns_;
    }
    // The block held is used up: back to its worker.
    const Ending ending = block.ending;
    holding_ = false;
    held_ = nullptr;
    row_ = held_rows_ = 0;
    block.full.store(false, std::memory_order_release);
    block.full.notify_one();
    taken_[r] = (taken_[r] + 1) % kBlocks;
    if (ending == Ending::kSegment) ring_ = (ring_ + 1) % static_cast<int>(rings_.size());
    if (ending == Ending::kFile) ended_ = true;
    if (ending == Ending::kStop) ended_ = stopped_ = true;
  }
  return nullptr;
}

}  // namespace ident::io::internal
