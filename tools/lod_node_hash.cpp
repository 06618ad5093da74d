// Prints, for every node of a .clod file, its id, its vertex count and an FNV-1a hash (32 bits) of
// its vertices' positions as LodReader decodes them, sorted (float bits, x then y then z): the
// desktop side of it_web_reader_positions, which compares them with web/clod.js's
// (tests/integration/web_node_hash.mjs).
//   lod_node_hash FILE.clod
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <vector>

#include "conelod/lod/lod_read.h"

using namespace conelod;

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: lod_node_hash FILE.clod\n");
    return 1;
  }
  std::unique_ptr<LodReader> r;
  Status s = LodReader::Open(argv[1], r);
  for (uint32_t id = 0; s.ok() && id < r->info().nodeCount; ++id) {
    s = r->LoadNode(id);
    if (s.ok()) s = r->LoadGeometry(id);
    if (!s.ok()) break;
    std::vector<std::array<float, 3>> p;
    for (const auto& x : r->geometry(id)->positions) p.push_back({{x[0], x[1], x[2]}});
    std::sort(p.begin(), p.end());
    uint64_t h = 2166136261u;
    for (const auto& a : p)
      for (float x : a) {
        uint32_t u;
        std::memcpy(&u, &x, 4);
        h = ((h ^ u) * 16777619u) & 0xFFFFFFFFu;
      }
    std::printf("%u %zu %llu\n", id, p.size(), (unsigned long long)h);
    r->EvictGeometry(id);
  }
  if (!s.ok()) {
    std::fprintf(stderr, "lod_node_hash: %s\n", s.message.c_str());
    return 2;
  }
  return 0;
}
