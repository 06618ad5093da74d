// ConeLOD — an allocator for the large temporary arrays of the core algorithms (see BigAlloc).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <utility>
#include <vector>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace conelod {

// While a BigRecycler is alive on a thread, the mapped blocks that BigAlloc frees on that thread are
// kept rather than unmapped, and BigAlloc takes its next blocks from them (trimmed to the size asked
// for) before mapping fresh ones. Fresh memory is not free: the kernel zeroes every page on its
// first touch and, on a busy machine, compacts memory to find huge pages (a fifth of a first
// build's time on the dragon). The grouping's phases free large arrays just before the next phase
// allocates its own (the face adjacency's, level 1's), which then reuse those pages. Blocks are
// handed out as they are: users of BigAlloc write what they size. Kept blocks count in the
// process's memory until taken: a recycler spans only the phases whose frees the next
// allocations take, and unmaps what is left when it ends.
class BigRecycler {
 public:
  BigRecycler() : outer_(Current()) { Current() = this; }
  BigRecycler(const BigRecycler&) = delete;
  BigRecycler& operator=(const BigRecycler&) = delete;
  ~BigRecycler() {
#ifdef __linux__
    for (const Block& b : kept_) munmap(b.p, b.size);
#endif
    Current() = outer_;
  }
  static BigRecycler*& Current() {
    static thread_local BigRecycler* current = nullptr;
    return current;
  }
  // The smallest kept block of at least `size` bytes (a multiple of the page size), trimmed to it;
  // for a huge-page block (`huge`), only one that was mapped as such (aligned, advised). Null: none.
  void* take(size_t size, bool huge) {
    size_t best = kept_.size();
    for (size_t i = 0; i < kept_.size(); ++i)
      if (kept_[i].size >= size && (kept_[i].huge || !huge) &&
          (best == kept_.size() || kept_[i].size < kept_[best].size))
        best = i;
    if (best == kept_.size()) return nullptr;
    const Block b = kept_[best];
    kept_.erase(kept_.begin() + std::ptrdiff_t(best));
#ifdef __linux__
    if (b.size > size) munmap(b.p + size, b.size - size);
#endif
    return b.p;
  }
  void keep(void* p, size_t size, bool huge) { kept_.push_back(Block{static_cast<char*>(p), size, huge}); }

 private:
  struct Block {
    char* p;
    size_t size;
    bool huge;  // mapped huge-page aligned and advised
  };
  std::vector<Block> kept_;
  BigRecycler* outer_;
};

// Large arrays of the grouping are read at random, all over: backed by 2 MiB pages where the
// kernel offers transparent huge pages on request, they cost far fewer TLB misses (and page
// faults). Mid-sized arrays are mapped too, so that they go back to the system when freed instead
// of staying in the heap as holes the next allocations may not fit (the builder's peak memory is
// then what it uses, whatever the caller's heap looks like). Every block is cache-line aligned
// (C++14's operator new does not honour alignas(64)).
template <class T>
struct BigAlloc {
  using value_type = T;
  BigAlloc() = default;
  template <class U>
  BigAlloc(const BigAlloc<U>&) {}
  static constexpr size_t kPage = 4096;
  static constexpr size_t kHugePage = size_t(2) << 20;
  static constexpr size_t kMapped = 64 * kPage;   // mapped from this size on
  static constexpr size_t kHuge = 4 * kHugePage;  // huge pages from this size on: below, the
                                                  // TLB's reach suffices and rounding costs
  static size_t MappedSize(size_t bytes) {
    const size_t unit = bytes >= kHuge ? kHugePage : kPage;
    return (bytes + unit - 1) / unit * unit;
  }
  T* allocate(size_t n) {
    const size_t bytes = n * sizeof(T);
#ifdef __linux__
    if (bytes >= kMapped) {
      const size_t size = MappedSize(bytes);
      if (BigRecycler* r = BigRecycler::Current())
        if (void* kept = r->take(size, bytes >= kHuge)) return static_cast<T*>(kept);
      if (bytes < kHuge) {
        void* p = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (p == MAP_FAILED) throw std::bad_alloc();
        return static_cast<T*>(p);
      }
      // Map one huge page more than needed and trim it to a huge-page-aligned block.
      void* raw = mmap(nullptr, size + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      if (raw == MAP_FAILED) throw std::bad_alloc();
      const uintptr_t begin = reinterpret_cast<uintptr_t>(raw);
      const uintptr_t aligned = (begin + kHugePage - 1) / kHugePage * kHugePage;
      if (aligned > begin) munmap(raw, aligned - begin);
      munmap(reinterpret_cast<void*>(aligned + size), begin + kHugePage - aligned);
      madvise(reinterpret_cast<void*>(aligned), size, MADV_HUGEPAGE);
      return reinterpret_cast<T*>(aligned);
    }
#endif
    void* p = nullptr;
    if (posix_memalign(&p, 64, std::max<size_t>(bytes, 1)) != 0) throw std::bad_alloc();
    return static_cast<T*>(p);
  }
  // resize() and sized construction default-initialise (trivial types are left unwritten) where
  // std::allocator value-initialises: every user of a BigVector writes what it sizes, and zeroing it
  // first cost a pass over fresh memory. Values given are copied as usual (assign(n, x)).
  template <class U>
  void construct(U* p) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  void deallocate(T* p, size_t n) {
#ifdef __linux__
    if (n * sizeof(T) >= kMapped) {
      const size_t size = MappedSize(n * sizeof(T));
      if (BigRecycler* r = BigRecycler::Current())
        r->keep(p, size, n * sizeof(T) >= kHuge);
      else
        munmap(p, size);
      return;
    }
#endif
    free(p);
  }
};
template <class T, class U>
bool operator==(const BigAlloc<T>&, const BigAlloc<U>&) {
  return true;
}
template <class T, class U>
bool operator!=(const BigAlloc<T>&, const BigAlloc<U>&) {
  return false;
}
template <class T>
using BigVector = std::vector<T, BigAlloc<T>>;

// Gives the whole pages of a vector's unused capacity back to the system (Linux: madvise
// MADV_DONTNEED), keeping its size, capacity and data: a vector shrunk in place (resize) then holds
// only the memory of its elements, without the copy of shrink_to_fit, and pages it grows into
// again come back zeroed (no element lives there). Only pages wholly inside [end of the elements,
// end of the capacity) are touched, so an allocator's records around the block are not.
template <class V>
void ReleaseUnusedCapacity(V& v) {
#ifdef __linux__
  using T = typename V::value_type;
  constexpr uintptr_t kPage = 4096;
  const uintptr_t begin = reinterpret_cast<uintptr_t>(v.data() + v.size());
  const uintptr_t end = reinterpret_cast<uintptr_t>(v.data()) + v.capacity() * sizeof(T);
  const uintptr_t first = (begin + kPage - 1) / kPage * kPage, last = end / kPage * kPage;
  if (v.data() && last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_DONTNEED);
#else
  (void)v;
#endif
}

}  // namespace conelod
