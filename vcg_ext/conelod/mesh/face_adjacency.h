// ConeLOD — the construction of FaceAdjacency (indexed_mesh.h), into vectors with the caller's
// allocator: the grouping builds it into memory that its next arrays reuse (BigRecycler).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "conelod/mesh/indexed_mesh.h"
#include "conelod/parallel.h"

namespace conelod {
namespace detail {
// A face seen from one of its vertices, with its two other vertices: finding the faces on an
// edge then reads the vertex's ring only, not the faces of the ring (scattered reads). The
// corner is named 3 * face + k (t[k] is the vertex): the face is corner / 3, and the edge
// (t[k], t[k+1]) that starts at the vertex is the face's edge k. (3 * faces fits in 32 bits, as
// the ring offsets need.)
struct Corner {
  uint32_t corner, other1, other2;
};
}  // namespace detail

// The lists of FaceAdjacency: neighbours[offsets[f] .. offsets[f+1]) for face f, in the same
// order as BuildFaceAdjacency's: edge by edge (edge e = (t[e], t[e+1])), the faces on each edge
// in increasing order, each face once.
//
// The faces on edge (a, b) are those around a that also use b, so every edge that starts at a is
// found from a's ring alone: the rings are scanned vertex by vertex, in memory order (rather than
// face by face, which visits each ring from each of its faces, far apart in time), and each
// edge's other face is noted in its face's slot for that edge. The lists are then made face by
// face from the slots; a face with an edge shared by more than two faces (rare) is made by
// scanning its rings as before. The slots are kept in `neighbours` (3 per face) and the lists
// written over them from the front: no memory beyond the lists' own. The rings are scanned on
// `threads` threads (the result does not depend on it).
template <class Alloc>
void BuildFaceAdjacencyInto(const IndexedMesh& m, std::vector<uint32_t, Alloc>& offsets,
                            std::vector<uint32_t, Alloc>& neighbours, size_t& borderEdges, size_t& nonManifoldEdges,
                            unsigned threads = 1) {
  using CornerAlloc = typename std::allocator_traits<Alloc>::template rebind_alloc<detail::Corner>;
  const uint32_t nv = uint32_t(m.positions.size());
  const uint32_t nf = uint32_t(m.faces.size());
  // Vertex -> incident corners, CSR (counting sort: no per-vertex allocation). Each ring lists
  // its corners in corner order, hence in face order.
  std::vector<uint32_t, Alloc> vfStart(nv + 1, 0);
  std::vector<detail::Corner, CornerAlloc> vf(size_t(nf) * 3);
  for (const auto& t : m.faces)
    for (uint32_t v : t) ++vfStart[v + 1];
  for (uint32_t v = 0; v < nv; ++v) vfStart[v + 1] += vfStart[v];
  {
    std::vector<uint32_t, Alloc> fill(vfStart.begin(), vfStart.end() - 1);
    for (uint32_t f = 0; f < nf; ++f) {
      const auto& t = m.faces[f];
      for (uint32_t k = 0; k < 3; ++k) vf[fill[t[k]]++] = detail::Corner{3 * f + k, t[(k + 1) % 3], t[(k + 2) % 3]};
    }
  }

  // Per edge of every face (slot 3 * f + e): its one other face, or kNone (a border edge or a
  // degenerate face's collapsed edge, which is no edge), or kMany (shared by three faces or more).
  constexpr uint32_t kNone = 0xFFFFFFFFu, kMany = 0xFFFFFFFEu;
  neighbours.resize(size_t(nf) * 3);
  uint32_t* slot = neighbours.data();
  borderEdges = nonManifoldEdges = 0;
  // Each corner's slot is written from its own vertex's ring only: the rings are scanned in
  // ranges of vertices on `threads` threads, and the counts (sums) do not depend on the split.
  auto scanRings = [&](uint32_t aBegin, uint32_t aEnd, size_t& border, size_t& nonManifold) {
    std::vector<uint32_t> ringFace;  // the faces of the ring's corners
    for (uint32_t a = aBegin; a < aEnd; ++a) {
      const uint32_t ringBegin = vfStart[a], ringSize = vfStart[a + 1] - ringBegin;
      const detail::Corner* ring = vf.data() + ringBegin;
      ringFace.resize(ringSize);
      for (uint32_t i = 0; i < ringSize; ++i) ringFace[i] = ring[i].corner / 3;
      for (uint32_t i = 0; i < ringSize; ++i) {
        const uint32_t f = ringFace[i], b = ring[i].other1;
        if (a == b) {
          slot[ring[i].corner] = kNone;
          continue;
        }
        // Skip f itself, and a face listed twice at a (a degenerate face: its corners are adjacent).
        uint32_t sharers = 1, lowest = f, other = kNone;
        uint32_t previous = f;
        for (uint32_t j = 0; j < ringSize; ++j) {
          const uint32_t g = ringFace[j];
          const uint32_t before = previous;
          previous = g;
          if (g == f || g == before) continue;
          if (ring[j].other1 != b && ring[j].other2 != b) continue;
          ++sharers;
          lowest = std::min(lowest, g);
          other = g;
        }
        if (lowest == f) {  // count each undirected edge once, at its lowest face
          if (sharers == 1)
            ++border;
          else if (sharers > 2)
            ++nonManifold;
        }
        slot[ring[i].corner] = sharers > 2 ? kMany : other;
      }
    }
  };
  constexpr uint32_t kRingChunk = 1u << 15;  // vertices per piece of work
  if (threads <= 1 || nv <= kRingChunk) {
    scanRings(0, nv, borderEdges, nonManifoldEdges);
  } else {
    std::mutex sums;
    ParallelChunks(nv, threads, kRingChunk, [&](size_t begin, size_t end, unsigned) {
      size_t border = 0, nonManifold = 0;
      scanRings(uint32_t(begin), uint32_t(end), border, nonManifold);
      std::lock_guard<std::mutex> lock(sums);
      borderEdges += border;
      nonManifoldEdges += nonManifold;
    });
  }

  // Face f's list is written where its slots were (read first): while every face before it had at
  // most 3 neighbours, the lists end at or before f's slots, so no slot still to read is
  // overwritten. A face with more (an edge of 3+ faces) moves the slots after it aside first.
  offsets.assign(nf + 1, 0);
  std::vector<uint32_t, Alloc> aside;  // the slots of faces [asideFrom, nf), once moved
  uint32_t asideFrom = nf;
  std::vector<uint32_t> many;  // the list of a face with an edge of 3+ faces
  size_t size = 0;             // the lists' entries so far
  for (uint32_t f = 0; f < nf; ++f) {
    const uint32_t* s = f < asideFrom ? &neighbours[size_t(f) * 3] : &aside[size_t(f - asideFrom) * 3];
    const uint32_t s0 = s[0], s1 = s[1], s2 = s[2];
    if (s0 != kMany && s1 != kMany && s2 != kMany) {
      if (size + 3 > neighbours.size()) neighbours.resize(size + 3 + neighbours.size() / 2);
      uint32_t* list = neighbours.data() + size;
      size_t n = 0;
      if (s0 != kNone) list[n++] = s0;
      if (s1 != kNone && (n == 0 || list[0] != s1)) list[n++] = s1;
      if (s2 != kNone && (n == 0 || list[0] != s2) && (n < 2 || list[1] != s2)) list[n++] = s2;
      size += n;
    } else {
      many.clear();
      const auto& t = m.faces[f];
      for (int e = 0; e < 3; ++e) {
        const uint32_t a = t[e], b = t[(e + 1) % 3];
        if (a == b) continue;
        uint32_t previous = f;
        for (uint32_t i = vfStart[a]; i < vfStart[a + 1]; ++i) {
          const detail::Corner& c = vf[i];
          const uint32_t g = c.corner / 3;
          const uint32_t before = previous;
          previous = g;
          if (g == f || g == before) continue;
          if (c.other1 != b && c.other2 != b) continue;
          if (std::find(many.begin(), many.end(), g) == many.end()) many.push_back(g);
        }
      }
      if (asideFrom == nf && size + many.size() > size_t(f + 1) * 3) {
        aside.assign(neighbours.begin() + std::ptrdiff_t(size_t(f + 1) * 3), neighbours.end());
        asideFrom = f + 1;
      }
      if (size + many.size() > neighbours.size()) neighbours.resize(size + many.size() + neighbours.size() / 2);
      std::copy(many.begin(), many.end(), neighbours.begin() + std::ptrdiff_t(size));
      size += many.size();
    }
    offsets[f + 1] = uint32_t(size);
  }
  neighbours.resize(size);
}

}  // namespace conelod
