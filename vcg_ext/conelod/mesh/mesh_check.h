// ConeLOD — input checks shared by every filter and CLI command.
//
// MeshLab users feed scans straight from the scanner: unreferenced vertices, NaN coordinates,
// zero-area faces, non-manifold edges and many components are all common. CheckMesh counts them
// once; RequireValidForFaces turns the fatal ones into a clear message.
#pragma once

#include <string>

#include "conelod/mesh/indexed_mesh.h"
#include "conelod/status.h"

namespace conelod {

// The largest coordinate magnitude the algorithms take: squared distances between such points
// (up to 3 (2e18)^2 = 1.2e37) stay inside single precision (3.4e38); beyond, they overflow to
// infinity and distances, normals and quadrics become NaN.
constexpr double kMaxCoordinate = 1e18;

struct MeshReport {
  size_t vertices = 0;
  size_t faces = 0;
  size_t unreferencedVertices = 0;
  size_t nonFiniteVertices = 0;  // referenced vertices with a NaN or infinite coordinate
  size_t hugeVertices = 0;       // referenced vertices with a coordinate beyond +-kMaxCoordinate
  size_t badIndexFaces = 0;      // faces that index past the vertex array
  size_t degenerateFaces = 0;    // zero area (repeated vertex or collinear corners)
  size_t borderEdges = 0;
  size_t nonManifoldEdges = 0;
  int components = 0;  // edge-connected face components
};

// Counts everything above. Border/non-manifold edges and components are computed only with
// `withTopology` and when indices and coordinates are valid.
MeshReport CheckMesh(const IndexedMesh& m, bool withTopology = true);

// Ok, or the reason why a face-based algorithm cannot run: no faces, faces with out-of-range
// indices, or referenced vertices with non-finite coordinates or coordinates beyond kMaxCoordinate. Zero-area faces,
// non-manifold edges, unreferenced vertices and several components are accepted (documented behaviour).
Status RequireValidForFaces(const MeshReport& r);

// RequireValidForFaces(CheckMesh(m, false)), the same status, without counting every zero-area
// face (it stops at the first face with an area).
Status RequireValidForFaces(const IndexedMesh& m);

}  // namespace conelod
