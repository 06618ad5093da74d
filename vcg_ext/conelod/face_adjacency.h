// ConeLOD — the construction of FaceAdjacency (indexed_mesh.h), into vectors with the caller's
// allocator: the grouping builds it into memory that goes back to the system when freed.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "conelod/indexed_mesh.h"

namespace conelod {
namespace detail {
// A face seen from one of its vertices, with its two other vertices: finding the faces on an
// edge then reads the vertex's ring only, not the faces of the ring (scattered reads).
struct Corner {
  uint32_t face, other1, other2;
};
}  // namespace detail

// The lists of FaceAdjacency: neighbours[offsets[f] .. offsets[f+1]) for face f, in the same
// order as BuildFaceAdjacency's.
template <class Alloc>
void BuildFaceAdjacencyInto(const IndexedMesh& m, std::vector<uint32_t, Alloc>& offsets,
                            std::vector<uint32_t, Alloc>& neighbours, size_t& borderEdges, size_t& nonManifoldEdges) {
  using CornerAlloc = typename std::allocator_traits<Alloc>::template rebind_alloc<detail::Corner>;
  const uint32_t nv = uint32_t(m.positions.size());
  const uint32_t nf = uint32_t(m.faces.size());
  // Vertex -> incident corners, CSR (counting sort: no per-vertex allocation).
  std::vector<uint32_t, Alloc> vfStart(nv + 1, 0);
  std::vector<detail::Corner, CornerAlloc> vf(size_t(nf) * 3);
  for (const auto& t : m.faces)
    for (uint32_t v : t) ++vfStart[v + 1];
  for (uint32_t v = 0; v < nv; ++v) vfStart[v + 1] += vfStart[v];
  {
    std::vector<uint32_t, Alloc> fill(vfStart.begin(), vfStart.end() - 1);
    for (uint32_t f = 0; f < nf; ++f) {
      const auto& t = m.faces[f];
      for (int k = 0; k < 3; ++k) vf[fill[t[k]]++] = detail::Corner{f, t[(k + 1) % 3], t[(k + 2) % 3]};
    }
  }

  offsets.assign(nf + 1, 0);
  neighbours.clear();
  neighbours.reserve(size_t(nf) * 3);
  borderEdges = nonManifoldEdges = 0;
  for (uint32_t f = 0; f < nf; ++f) {
    const auto& t = m.faces[f];
    const size_t listBegin = neighbours.size();
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = t[e], b = t[(e + 1) % 3];
      if (a == b) continue;  // a degenerate face's collapsed edge is no edge
      // The faces on edge (a,b) are those around a that also use b (b != a: among the others).
      uint32_t sharers = 1, lowest = f;
      // The ring's bounds in locals: the pushes below store uint32_t too, and would otherwise make
      // the compiler reload them at every corner.
      const uint32_t ringBegin = vfStart[a], ringEnd = vfStart[a + 1];
      uint32_t previous = f;  // the face of the corner before (f before the first: skipped anyway)
      for (uint32_t i = ringBegin; i < ringEnd; ++i) {
        const detail::Corner& c = vf[i];
        const uint32_t g = c.face;
        const uint32_t before = previous;
        previous = g;
        if (g == f || g == before) continue;  // f itself, or a face listed twice at a
        if (c.other1 != b && c.other2 != b) continue;
        ++sharers;
        lowest = std::min(lowest, g);
        if (std::find(neighbours.begin() + listBegin, neighbours.end(), g) == neighbours.end())
          neighbours.push_back(g);
      }
      if (lowest == f) {  // count each undirected edge once, at its lowest face
        if (sharers == 1) ++borderEdges;
        else if (sharers > 2) ++nonManifoldEdges;
      }
    }
    offsets[f + 1] = uint32_t(neighbours.size());
  }
}

}  // namespace conelod
