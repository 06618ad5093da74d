// conelod-viewer: the process's resident memory (VmRSS of /proc/self/status), for the HUD.
#pragma once

#include <cstdio>
#include <cstring>

inline size_t ProcessResidentBytes() {
  FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return 0;
  char line[256];
  size_t kib = 0;
  while (std::fgets(line, sizeof line, f))
    if (std::strncmp(line, "VmRSS:", 6) == 0) {
      std::sscanf(line + 6, "%zu", &kib);
      break;
    }
  std::fclose(f);
  return kib * 1024;
}
