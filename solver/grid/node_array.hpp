// Per-node (and per-cell) arrays that cost memory only where the points are.
//
// A formulation's nodal arrays are indexed by the grid's flat node index, so they are as long as
// the whole grid; a step touches only its active box (the nodes the points' supports reach,
// solver/grid/grid.hpp). Filled with zeros by std::vector, every page of such an array is written
// once at construction: physical memory and the zeroing follow the grid's bounding box (the 16x
// empty-space column of bench/active_region.py: semi-implicit-single-point 111 -> 224 MB).
// NodeArray takes its memory straight from the kernel (an anonymous mapping, whose pages read as
// zeros until first written) and does not write the zeros itself: a page outside every step's box
// is never touched and never becomes memory. Reads see the same zeros, so results do not change.
// (calloc would do the same only for blocks above malloc's mmap threshold, which glibc raises as
// large blocks are freed: at 16x, 43 MB of the arrays came from the heap and were zeroed by memset.)
//
// Contract: only for element types whose zero value is all-zero bytes (double, integers, Vec, and
// aggregates of them without non-zero default members), and sized once, from empty (NodeArray<T>
// a(n), or resize on an empty array): growing an array that had been shrunk would not zero the
// regrown elements. assign() and fill write as usual.
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace swmpm {

template <class T>
struct ZeroPages {
  using value_type = T;
  static_assert(std::is_trivially_destructible_v<T>, "NodeArray holds plain numbers (zero = all-zero bytes)");
  ZeroPages() = default;
  template <class U>
  ZeroPages(const ZeroPages<U>&) noexcept {}
  T* allocate(std::size_t n) {
    if (n == 0) return nullptr;
    void* p = ::mmap(nullptr, n * sizeof(T), PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    return static_cast<T*>(p);  // page-aligned: as aligned as any Eigen type needs
  }
  void deallocate(T* p, std::size_t n) noexcept {
    if (p) ::munmap(p, n * sizeof(T));
  }
  /// Value-initialisation (resize, the size constructor) writes nothing: the mapping reads as zeros.
  template <class U>
  void construct(U*) noexcept {}
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <class U>
  bool operator==(const ZeroPages<U>&) const noexcept { return true; }
};

/// A grid-sized array of T, zero until written, that holds memory only where written.
template <class T>
using NodeArray = std::vector<T, ZeroPages<T>>;

}  // namespace swmpm
