// ConeLOD — indexed mesh helpers and face adjacency (see indexed_mesh.h).
#include "conelod/mesh/indexed_mesh.h"

#include "conelod/mesh/face_adjacency.h"
#include "conelod/common.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace conelod {

void ComputeFaceNormalsAndAreas(const IndexedMesh& m, std::vector<vcg::Point3d>& normals, std::vector<double>& areas) {
  const size_t nf = m.faces.size();
  normals.resize(nf);
  areas.resize(nf);
  for (size_t f = 0; f < nf; ++f) FaceNormalAndArea(m, f, normals[f], areas[f]);
}

vcg::Box3d UsedVertexBox(const IndexedMesh& m) {
  vcg::Box3d box;
  std::vector<char> used(m.positions.size(), 0);
  for (const auto& t : m.faces)
    for (uint32_t v : t)
      if (v < used.size()) used[v] = 1;
  for (size_t v = 0; v < m.positions.size(); ++v)
    if (used[v]) box.Add(vcg::Point3d::Construct(m.positions[v]));
  return box;
}

double NormalizingScale(const IndexedMesh& m) {
  const vcg::Box3d box = UsedVertexBox(m);
  if (box.IsNull()) return 1;
  const double d = box.Diag();
  if (!(d > 0) || !std::isfinite(d)) return 1;
  // Within float's normal range both ways (coordinates are floats), so the scale and its inverse
  // are exact in float as in double.
  const int e = std::max(-120, std::min(120, int(std::lround(std::log2(d)))));
  return std::ldexp(1.0, -e);
}

FaceAdjacency BuildFaceAdjacency(const IndexedMesh& m, unsigned threads) {
  FaceAdjacency adj;
  BuildFaceAdjacencyInto(m, adj.offsets, adj.neighbours, adj.borderEdges, adj.nonManifoldEdges, threads);
  return adj;
}

int ConnectedComponents(const FaceAdjacency& adj, std::vector<int>& comp) {
  const uint32_t nf = uint32_t(adj.offsets.size() - 1);
  std::vector<uint32_t> parent(nf);
  std::iota(parent.begin(), parent.end(), 0u);
  for (uint32_t f = 0; f < nf; ++f)
    for (uint32_t i = adj.offsets[f]; i < adj.offsets[f + 1]; ++i) {
      uint32_t a = FindRoot(parent, f), b = FindRoot(parent, adj.neighbours[i]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  comp.assign(nf, -1);
  std::vector<int> idOfRoot(nf, -1);
  int count = 0;
  for (uint32_t f = 0; f < nf; ++f) {
    uint32_t r = FindRoot(parent, f);
    if (idOfRoot[r] < 0) idOfRoot[r] = count++;
    comp[f] = idOfRoot[r];
  }
  return count;
}

bool GroupsAreEdgeConnected(const FaceAdjacency& adj, const std::vector<int>& faceGroup, std::vector<int>* broken) {
  const uint32_t nf = uint32_t(faceGroup.size());
  std::vector<uint32_t> parent(nf);
  std::iota(parent.begin(), parent.end(), 0u);
  for (uint32_t f = 0; f < nf; ++f) {
    if (faceGroup[f] < 0) continue;
    for (uint32_t i = adj.offsets[f]; i < adj.offsets[f + 1]; ++i) {
      const uint32_t g = adj.neighbours[i];
      if (faceGroup[g] != faceGroup[f]) continue;
      uint32_t a = FindRoot(parent, f), b = FindRoot(parent, g);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  // A group is connected iff all its faces share one root.
  int maxGroup = -1;
  for (int g : faceGroup) maxGroup = std::max(maxGroup, g);
  std::vector<int64_t> rootOfGroup(size_t(maxGroup + 1), -1);
  std::vector<char> isBroken(size_t(maxGroup + 1), 0);
  for (uint32_t f = 0; f < nf; ++f) {
    const int g = faceGroup[f];
    if (g < 0) continue;
    const int64_t r = FindRoot(parent, f);
    if (rootOfGroup[g] < 0)
      rootOfGroup[g] = r;
    else if (rootOfGroup[g] != r)
      isBroken[g] = 1;
  }
  bool ok = true;
  for (int g = 0; g <= maxGroup; ++g)
    if (isBroken[g]) {
      ok = false;
      if (broken) broken->push_back(g);
    }
  return ok;
}

}  // namespace conelod
