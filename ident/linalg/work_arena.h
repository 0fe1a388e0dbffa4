// WorkArena: one zero-initialised block of memory that a solver carves into its work arrays.
//
// Why: the first touch of every 4 KiB page is a page fault, which is dear on virtual machines; one 2 MiB
// huge page replaces 512 of them. A solver whose work arrays are a few MB (the MAP smoother at T = 10^4)
// spends more time in page faults than in arithmetic unless its arrays share one block mapped with huge
// pages.
// Blocks of at least kHugePageThreshold bytes are mapped 2 MiB-aligned, with MADV_HUGEPAGE up to the caller's
// `huge_page_limit` (Linux; the kernel may ignore the advice, which only costs speed); smaller ones come from the
// ordinary heap. A caller whose passes stream a block far larger than the last-level cache sets a limit: such a
// pass runs as fast on 4 KiB pages, and on a virtual machine whose host takes back the guest's free memory a fresh
// 2 MiB page costs more to fault in than its 512 small pages.
//
// Example:
//   std::size_t size = ident::WorkArena::Padded(n) + ident::WorkArena::Padded(m);
//   ident::WorkArena arena(size);         // doubles, all zero
//   double* a = arena.Take(n);            // 64-byte aligned
//   double* b = arena.Take(m);
//
// Allocation: one, in the constructor; Take() never allocates and throws InvalidArgument when the
// requested arrays exceed the size given to the constructor.
#pragma once

#include <cstddef>
#include <limits>

namespace ident {

class WorkArena {
 public:
  static constexpr std::size_t kHugePageThreshold = std::size_t{1} << 20;  // bytes

  // Room for `num_doubles` doubles (sum Padded(count) over the arrays to be taken); huge pages for a block of
  // kHugePageThreshold to `huge_page_limit` bytes.
  explicit WorkArena(std::size_t num_doubles, std::size_t huge_page_limit = std::numeric_limits<std::size_t>::max());
  ~WorkArena();
  WorkArena(const WorkArena&) = delete;
  WorkArena& operator=(const WorkArena&) = delete;

  // `count` doubles rounded up to a multiple of 8 (64 bytes): what Take(count) uses up.
  static std::size_t Padded(std::size_t count) { return (count + 7) & ~std::size_t{7}; }

  // The next `count` zero doubles, 64-byte aligned.
  double* Take(std::size_t count);

  std::size_t capacity() const { return capacity_; }  // doubles
  std::size_t used() const { return used_; }          // doubles
  bool huge_pages_requested() const { return huge_pages_; }

 private:
  double* data_ = nullptr;
  std::size_t capacity_ = 0, used_ = 0;
  void* mapping_ = nullptr;  // the mmap'ed block of a large arena, else nullptr
  std::size_t mapped_bytes_ = 0;
  bool huge_pages_ = false;
};

}  // namespace ident
