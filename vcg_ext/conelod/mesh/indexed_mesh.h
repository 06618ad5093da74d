// ConeLOD — the plain indexed triangle mesh the core algorithms run on, and its face adjacency.
//
// The algorithms take this compact form (no deleted elements, 32-bit indices) rather than a
// vcg mesh so that they are compiled once and run on any vcg mesh type (MeshLab's CMeshO, the
// CLI's mesh): vcg_bridge.h converts both ways.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include <vcg/space/box3.h>
#include <vcg/space/point3.h>

namespace conelod {

struct IndexedMesh {
  std::vector<vcg::Point3f> positions;
  std::vector<std::array<uint32_t, 3>> faces;

  size_t vertexCount() const { return positions.size(); }
  size_t faceCount() const { return faces.size(); }
};

// A face with a repeated vertex index: a point or a segment, no surface (after a weld by position,
// an input face whose corners shared a position).
inline bool UsesAVertexTwice(const std::array<uint32_t, 3>& t) { return t[0] == t[1] || t[1] == t[2] || t[0] == t[2]; }

// The unit normal (zero vector for a zero-area or degenerate face) and the area of face f, in
// double. Inline and bit-for-bit the same everywhere: the grouping recomputes normals on demand
// instead of keeping an array of them, and must get exactly the values the array would hold.
inline void FaceNormalAndArea(const IndexedMesh& m, size_t f, vcg::Point3d& normal, double& area) {
  const auto& t = m.faces[f];
  const vcg::Point3d a = vcg::Point3d::Construct(m.positions[t[0]]);
  const vcg::Point3d b = vcg::Point3d::Construct(m.positions[t[1]]);
  const vcg::Point3d c = vcg::Point3d::Construct(m.positions[t[2]]);
  const vcg::Point3d n = (b - a) ^ (c - a);
  const double len = n.Norm();
  // A face is degenerate when its area is negligible against its edge lengths (relative test,
  // so that it does not depend on the model's scale).
  const double scale = std::max({(b - a).SquaredNorm(), (c - a).SquaredNorm(), (c - b).SquaredNorm()});
  if (!(len > 1e-12 * scale) || !(len > 0)) {
    normal = vcg::Point3d(0, 0, 0);
    area = 0;
  } else {
    normal = n / len;
    area = 0.5 * len;
  }
}

// Squared distance from p to the triangle (a, b, c) (Ericson, Real-Time Collision Detection 5.1.5).
inline double PointTriangleDistance2(const vcg::Point3d& p, const vcg::Point3d& a, const vcg::Point3d& b,
                                     const vcg::Point3d& c) {
  const vcg::Point3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab * ap, d2 = ac * ap;
  if (d1 <= 0 && d2 <= 0) return ap.SquaredNorm();
  const vcg::Point3d bp = p - b;
  const double d3 = ab * bp, d4 = ac * bp;
  if (d3 >= 0 && d4 <= d3) return bp.SquaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return (ap - ab * v).SquaredNorm();
  }
  const vcg::Point3d cp = p - c;
  const double d5 = ab * cp, d6 = ac * cp;
  if (d6 >= 0 && d5 <= d6) return cp.SquaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return (ap - ac * w).SquaredNorm();
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return (bp - (c - b) * w).SquaredNorm();
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return (ap - ab * v - ac * w).SquaredNorm();
}

// Per-face unit normal and area (FaceNormalAndArea) of every face.
void ComputeFaceNormalsAndAreas(const IndexedMesh& m, std::vector<vcg::Point3d>& normals, std::vector<double>& areas);

// Bounding box of the vertices that faces use (unreferenced vertices and out-of-range indices
// ignored); null when there are none.
vcg::Box3d UsedVertexBox(const IndexedMesh& m);

// The power of two 2^-round(log2(d)), d the diagonal of UsedVertexBox (1 when there is no
// box, a zero or non-finite diagonal): coordinates times it span about 1. Multiplying by a power
// of two is exact, so what is computed on scaled coordinates (in float, where squares of areas of
// a model 2^34 times too large overflow and those of one 2^34 times too small vanish) is the
// unscaled result times a power of two, bit for bit, at any scale of the model.
double NormalizingScale(const IndexedMesh& m);

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
// `threads` (>= 1) share the work; the result does not depend on their number.
FaceAdjacency BuildFaceAdjacency(const IndexedMesh& m, unsigned threads = 1);

// Edge-connected components: per-face component id (0..count-1, numbered by lowest face).
int ConnectedComponents(const FaceAdjacency& adj, std::vector<int>& componentOfFace);

// True when the faces listed in `faceGroup` (group id per face, -1 = not in any group) form
// edge-connected groups; `brokenGroups` (optional) receives the ids of groups in several pieces.
bool GroupsAreEdgeConnected(const FaceAdjacency& adj, const std::vector<int>& faceGroup,
                            std::vector<int>* brokenGroups = nullptr);

}  // namespace conelod
