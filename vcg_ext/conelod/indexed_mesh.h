// ConeLOD — the plain indexed triangle mesh the core algorithms run on, and its face adjacency.
//
// The algorithms take this compact form (no deleted elements, 32-bit indices) rather than a
// vcg mesh so that they are compiled once and run on any vcg mesh type (MeshLab's CMeshO, the
// CLI's mesh): vcg_bridge.h converts both ways.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <vcg/space/point3.h>

namespace conelod {

struct IndexedMesh {
  std::vector<vcg::Point3f> positions;
  std::vector<std::array<uint32_t, 3>> faces;

  size_t vertexCount() const { return positions.size(); }
  size_t faceCount() const { return faces.size(); }
};

// Per-face unit normal (zero vector for a zero-area or degenerate face) and area, in double.
void ComputeFaceNormalsAndAreas(const IndexedMesh& m, std::vector<vcg::Point3d>& normals,
                                std::vector<double>& areas);

// Edge adjacency of faces, CSR: the faces sharing an edge with face f are
// neighbours[offsets[f] .. offsets[f+1]). Faces sharing a non-manifold edge are all neighbours of
// each other. A face is never its own neighbour and appears once in a list.
struct FaceAdjacency {
  std::vector<uint32_t> offsets;
  std::vector<uint32_t> neighbours;
  size_t borderEdges = 0;       // edges with one face
  size_t nonManifoldEdges = 0;  // edges with three or more faces

  size_t degree(uint32_t f) const { return offsets[f + 1] - offsets[f]; }
};
FaceAdjacency BuildFaceAdjacency(const IndexedMesh& m);

// Edge-connected components: per-face component id (0..count-1, numbered by lowest face).
int ConnectedComponents(const FaceAdjacency& adj, std::vector<int>& componentOfFace);

// True when the faces listed in `faceGroup` (group id per face, -1 = not in any group) form
// edge-connected groups; `brokenGroups` (optional) receives the ids of groups in several pieces.
bool GroupsAreEdgeConnected(const FaceAdjacency& adj, const std::vector<int>& faceGroup,
                            std::vector<int>* brokenGroups = nullptr);

}  // namespace conelod
