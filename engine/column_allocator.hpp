#pragma once
// The allocator of the particle columns: aligned for vector loads, and on transparent huge pages where they are
// large.
#include <cstddef>
#include <limits>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace mpm {

/// Columns start on a cache line (64 bytes), so vector loads never split one. A column of 2 MiB or more starts on
/// a 2 MiB boundary, spans whole 2 MiB pages and is advised as transparent huge pages (madvise MADV_HUGEPAGE)
/// before anything touches it: Debian's kernels back memory with huge pages only where asked (THP mode
/// "madvise"), and with 4 KiB pages the step, which streams a dozen columns and the grid, ran 6–11 % slower at
/// 1e6–1e7 particles (docs/PERFORMANCE.md). The advice is a hint: where THP is off the column works as before.
template <class T>
struct ColumnAllocator {
  using value_type = T;
  static constexpr std::size_t cache_line = 64, huge_page = std::size_t{1} << 21;
  ColumnAllocator() = default;
  template <class U>
  ColumnAllocator(const ColumnAllocator<U>&) {}
  /// At most PTRDIFF_MAX bytes, after the rounding to whole pages.
  std::size_t max_size() const {
    return (static_cast<std::size_t>(std::numeric_limits<std::ptrdiff_t>::max()) - huge_page) / sizeof(T);
  }
  T* allocate(std::size_t n) {
    if (n > max_size()) throw std::bad_array_new_length();
    const std::size_t bytes = n * sizeof(T);
    if (bytes < huge_page) return static_cast<T*>(::operator new(bytes, std::align_val_t{cache_line}));
    const std::size_t whole = rounded_to_pages(bytes);
    void* p = ::operator new(whole, std::align_val_t{huge_page});
#if defined(__linux__)
    madvise(p, whole, MADV_HUGEPAGE);  // a hint: its failure (THP not built in) changes nothing else
#endif
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t n) {
    ::operator delete(p, std::align_val_t{n * sizeof(T) < huge_page ? cache_line : huge_page});
  }
  template <class U>
  bool operator==(const ColumnAllocator<U>&) const { return true; }

 private:
  static std::size_t rounded_to_pages(std::size_t bytes) { return (bytes + huge_page - 1) / huge_page * huge_page; }
};

}  // namespace mpm
