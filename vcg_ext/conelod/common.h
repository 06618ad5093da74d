// ConeLOD — the small things every part of the core uses: pi, a prefetch hint for the loops that
// are bound by memory latency (the grouping's merges, the feature simplification's queue), the
// root lookup of a union-find forest (connected pieces of faces, of corners, of a vertex's link),
// and the bit spreading of a Morton code (the PCA partition's, the LOD groups' distance scan).
#pragma once

#include <cstdint>
#include <vector>

namespace conelod {

constexpr double kPi = 3.14159265358979323846;

// Asks the CPU to start loading the cache line at p (a hint: never faults, does nothing elsewhere).
inline void Prefetch(const void* p) {
#if defined(__GNUC__) || defined(__clang__)
  __builtin_prefetch(p);
#else
  (void)p;
#endif
}

// The root of x's set in a union-find forest (parent[r] == r at a root), halving the path on the
// way up.
inline uint32_t FindRoot(std::vector<uint32_t>& parent, uint32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

// The 10 low bits of x moved to every third bit (bit i to bit 3i): one axis of a 30-bit Morton code.
inline uint32_t SpreadBits10(uint32_t x) {
  x = (x | (x << 16)) & 0x030000FFu;
  x = (x | (x << 8)) & 0x0300F00Fu;
  x = (x | (x << 4)) & 0x030C30C3u;
  return (x | (x << 2)) & 0x09249249u;
}

}  // namespace conelod
