// ConeLOD — input checks (see mesh_check.h).
#include "conelod/mesh/mesh_check.h"

#include <cmath>

namespace conelod {

namespace {
// CheckMesh's counts without the topology; with `anyArea`, the degenerate faces are counted only
// up to the first face with an area (enough for RequireValidForFaces: not all are degenerate).
MeshReport CheckFaces(const IndexedMesh& m, bool anyArea) {
  MeshReport r;
  r.vertices = m.positions.size();
  r.faces = m.faces.size();
  std::vector<char> used(m.positions.size(), 0);
  for (const auto& t : m.faces) {
    bool ok = true;
    for (uint32_t v : t)
      if (v >= m.positions.size()) ok = false;
    if (!ok) {
      ++r.badIndexFaces;
      continue;
    }
    for (uint32_t v : t) used[v] = 1;
  }
  for (size_t v = 0; v < m.positions.size(); ++v) {
    if (!used[v]) {
      ++r.unreferencedVertices;
      continue;
    }
    const auto& p = m.positions[v];
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      ++r.nonFiniteVertices;
    else if (std::fabs(p[0]) > kMaxCoordinate || std::fabs(p[1]) > kMaxCoordinate || std::fabs(p[2]) > kMaxCoordinate)
      ++r.hugeVertices;
  }
  if (r.badIndexFaces || r.nonFiniteVertices || r.hugeVertices) return r;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    vcg::Point3d n;
    double a;
    FaceNormalAndArea(m, f, n, a);
    if (a == 0)
      ++r.degenerateFaces;
    else if (anyArea)
      break;
  }
  return r;
}
}  // namespace

MeshReport CheckMesh(const IndexedMesh& m, bool withTopology) {
  MeshReport r = CheckFaces(m, false);
  if (!withTopology || r.badIndexFaces || r.nonFiniteVertices || r.hugeVertices) return r;
  const FaceAdjacency adj = BuildFaceAdjacency(m);
  r.borderEdges = adj.borderEdges;
  r.nonManifoldEdges = adj.nonManifoldEdges;
  std::vector<int> comp;
  r.components = m.faces.empty() ? 0 : ConnectedComponents(adj, comp);
  return r;
}

Status RequireValidForFaces(const IndexedMesh& m) { return RequireValidForFaces(CheckFaces(m, true)); }

Status RequireValidForFaces(const MeshReport& r) {
  if (r.faces == 0)
    return Status::Invalid("the mesh has no faces (" + std::to_string(r.vertices) +
                           " vertices): this filter works on triangle meshes");
  if (r.badIndexFaces)
    return Status::Invalid(std::to_string(r.badIndexFaces) + (r.badIndexFaces == 1 ? " face refers" : " faces refer") +
                           " to vertices that do not exist");
  if (r.nonFiniteVertices)
    return Status::Invalid(std::to_string(r.nonFiniteVertices) +
                           (r.nonFiniteVertices == 1 ? " vertex used by faces has" : " vertices used by faces have") +
                           " NaN or infinite coordinates; remove them first (e.g. Filters > Cleaning and Repairing)");
  if (r.hugeVertices)
    return Status::Invalid(std::to_string(r.hugeVertices) +
                           (r.hugeVertices == 1 ? " vertex used by faces has" : " vertices used by faces have") +
                           " coordinates beyond +-1e18, whose squares overflow single precision; scale the mesh "
                           "down first (e.g. Filters > Normals, Curvatures and Orientation > Transform: Scale)");
  if (r.degenerateFaces == r.faces)
    return Status::Invalid("every face of the mesh has zero area: there is no normal to group by");
  return Status::Ok();
}

}  // namespace conelod
