// ConeLOD — this process's memory as Linux reports it, for benchmarks and the viewer's HUD.
//
// Reads a "VmXXX:  1234 kB" line of /proc/self/status (VmRSS: resident now; VmHWM: the peak since
// start or since "5" was written to /proc/self/clear_refs). Standard library only.
#pragma once

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

namespace conelod {

// The field (e.g. "VmRSS", "VmHWM") in bytes; 0 when it is missing (not Linux).
inline size_t ProcessStatusBytes(const char* field) {
  std::ifstream in("/proc/self/status");
  std::string line;
  const size_t n = std::strlen(field);
  while (std::getline(in, line))
    if (line.compare(0, n, field) == 0 && line.size() > n && line[n] == ':')
      return size_t(std::atoll(line.c_str() + n + 1)) * 1024;
  return 0;
}

}  // namespace conelod
