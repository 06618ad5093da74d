// ConeLOD — a mesh's triangles as a sorted list of corner positions: equal for two meshes with the
// same triangles (same orientation) whatever their vertex and face order. The LOD round trip is
// checked with it (tests, bench_lod).
#pragma once

#include <algorithm>
#include <array>
#include <vector>

#include "conelod/mesh/indexed_mesh.h"

namespace conelod {

// Per face: its corners' positions (x,y,z three times), rotated to start at the smallest triple
// (orientation kept); the faces sorted.
inline std::vector<std::array<float, 9>> SortedFacePositions(const IndexedMesh& m) {
  std::vector<std::array<float, 9>> out;
  out.reserve(m.faces.size());
  for (const auto& t : m.faces) {
    std::array<std::array<float, 9>, 3> rot;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        for (int i = 0; i < 3; ++i) rot[size_t(r)][size_t(c * 3 + i)] = m.positions[t[size_t((r + c) % 3)]][i];
    out.push_back(*std::min_element(rot.begin(), rot.end()));
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace conelod
