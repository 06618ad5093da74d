// ConeLOD — the small things every part of the core uses: pi, and a prefetch hint for the loops
// that are bound by memory latency (the grouping's merges, the feature simplification's queue).
#pragma once

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

}  // namespace conelod
