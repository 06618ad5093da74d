// ConeLOD — welding vertices at identical positions, the working copy the grouping, the
// group-preserving collapse and the LOD build run on.
//
// Scans often repeat vertices along seams (chunked reconstruction, meshes converted from STL or
// from per-face vertex lists): the dragon of ../shared/test_meshes has 437,645 vertices, 151
// components and 4,270 border edges by index, but one component and no border once vertices at
// the same position are one. Left as they are, every algorithm that walks edges sees false
// borders there: groups stop at them, a collapse keeps them as borders, and the LOD build
// simplifies each side of a seam on its own, so its cuts open along the seam.
//
// The weld is exact (positions equal coordinate for coordinate; -0 and +0 are equal; no
// tolerance, so it never merges two distinct points nor changes a position) and deterministic:
// vertices are sorted by position (O(n log n)), each position keeps its lowest input index as its
// representative, and the welded vertices are numbered in the order of their representatives.
// Faces keep their order and their corners' positions; only unreferenced vertices are dropped. A
// mesh without repeated or unreferenced vertices comes out unchanged (same indices).
#pragma once

#include <cstdint>
#include <vector>

#include "conelod/mesh/indexed_mesh.h"

namespace conelod {

struct WeldResult {
  IndexedMesh mesh;                      // faces in the input's order; one vertex per used position
  std::vector<uint32_t> representative;  // per welded vertex: the lowest input vertex at its position
  size_t mergedVertices = 0;             // used input vertices merged into another
  size_t droppedVertices = 0;            // unreferenced input vertices dropped
  bool changed() const { return mergedVertices != 0 || droppedVertices != 0; }
};

// Welds `in`'s used vertices by exact position (see above); non-finite coordinates are compared
// by their bits. A mesh without faces, or with a face index out of range, comes back as it is
// (for RequireValidForFaces to refuse it, counting its vertices).
WeldResult WeldByPosition(const IndexedMesh& in);

// WeldByPosition in place: `mesh` becomes WeldResult::mesh without a second copy of the mesh (the
// out-of-core LOD build's input). Returns false (and leaves `mesh` as it is) where WeldByPosition
// returns its input as it is; merged / dropped: WeldResult's counts. The positions are sorted on
// `threads` threads (the result is the same for every count).
bool WeldByPositionInPlace(IndexedMesh& mesh, size_t* merged = nullptr, size_t* dropped = nullptr,
                           unsigned threads = 1);

}  // namespace conelod
