// ConeLOD — indexed mesh helpers and face adjacency (see indexed_mesh.h).
#include "conelod/indexed_mesh.h"

#include <algorithm>
#include <numeric>

namespace conelod {

void ComputeFaceNormalsAndAreas(const IndexedMesh& m, std::vector<vcg::Point3d>& normals,
                                std::vector<double>& areas) {
  const size_t nf = m.faces.size();
  normals.resize(nf);
  areas.resize(nf);
  for (size_t f = 0; f < nf; ++f) FaceNormalAndArea(m, f, normals[f], areas[f]);
}

FaceAdjacency BuildFaceAdjacency(const IndexedMesh& m) {
  const uint32_t nv = uint32_t(m.positions.size());
  const uint32_t nf = uint32_t(m.faces.size());
  // Vertex -> incident corners, CSR (counting sort: no per-vertex allocation). A corner carries
  // its face's two other vertices, so that finding the faces on an edge reads the ring only,
  // not the faces of the ring (scattered reads that made this the slow part).
  struct Corner {
    uint32_t face, other1, other2;
  };
  std::vector<uint32_t> vfStart(nv + 1, 0);
  std::vector<Corner> vf(size_t(nf) * 3);
  for (const auto& t : m.faces)
    for (uint32_t v : t) ++vfStart[v + 1];
  for (uint32_t v = 0; v < nv; ++v) vfStart[v + 1] += vfStart[v];
  {
    std::vector<uint32_t> fill(vfStart.begin(), vfStart.end() - 1);
    for (uint32_t f = 0; f < nf; ++f) {
      const auto& t = m.faces[f];
      for (int k = 0; k < 3; ++k) vf[fill[t[k]]++] = Corner{f, t[(k + 1) % 3], t[(k + 2) % 3]};
    }
  }

  FaceAdjacency adj;
  adj.offsets.assign(nf + 1, 0);
  adj.neighbours.reserve(size_t(nf) * 3);
  for (uint32_t f = 0; f < nf; ++f) {
    const auto& t = m.faces[f];
    const size_t listBegin = adj.neighbours.size();
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = t[e], b = t[(e + 1) % 3];
      if (a == b) continue;  // a degenerate face's collapsed edge is no edge
      // The faces on edge (a,b) are those around a that also use b (b != a: among the others).
      uint32_t sharers = 1, lowest = f;
      for (uint32_t i = vfStart[a]; i < vfStart[a + 1]; ++i) {
        const Corner& c = vf[i];
        const uint32_t g = c.face;
        if (g == f || (i > vfStart[a] && vf[i - 1].face == g)) continue;  // a face listed twice at a
        if (c.other1 != b && c.other2 != b) continue;
        ++sharers;
        lowest = std::min(lowest, g);
        if (std::find(adj.neighbours.begin() + listBegin, adj.neighbours.end(), g) == adj.neighbours.end())
          adj.neighbours.push_back(g);
      }
      if (lowest == f) {  // count each undirected edge once, at its lowest face
        if (sharers == 1) ++adj.borderEdges;
        else if (sharers > 2) ++adj.nonManifoldEdges;
      }
    }
    adj.offsets[f + 1] = uint32_t(adj.neighbours.size());
  }
  return adj;
}

namespace {
uint32_t Find(std::vector<uint32_t>& parent, uint32_t x) {
  while (parent[x] != x) { parent[x] = parent[parent[x]]; x = parent[x]; }
  return x;
}
}  // namespace

int ConnectedComponents(const FaceAdjacency& adj, std::vector<int>& comp) {
  const uint32_t nf = uint32_t(adj.offsets.size() - 1);
  std::vector<uint32_t> parent(nf);
  std::iota(parent.begin(), parent.end(), 0u);
  for (uint32_t f = 0; f < nf; ++f)
    for (uint32_t i = adj.offsets[f]; i < adj.offsets[f + 1]; ++i) {
      uint32_t a = Find(parent, f), b = Find(parent, adj.neighbours[i]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  comp.assign(nf, -1);
  std::vector<int> idOfRoot(nf, -1);
  int count = 0;
  for (uint32_t f = 0; f < nf; ++f) {
    uint32_t r = Find(parent, f);
    if (idOfRoot[r] < 0) idOfRoot[r] = count++;
    comp[f] = idOfRoot[r];
  }
  return count;
}

bool GroupsAreEdgeConnected(const FaceAdjacency& adj, const std::vector<int>& faceGroup,
                            std::vector<int>* broken) {
  const uint32_t nf = uint32_t(faceGroup.size());
  std::vector<uint32_t> parent(nf);
  std::iota(parent.begin(), parent.end(), 0u);
  for (uint32_t f = 0; f < nf; ++f) {
    if (faceGroup[f] < 0) continue;
    for (uint32_t i = adj.offsets[f]; i < adj.offsets[f + 1]; ++i) {
      const uint32_t g = adj.neighbours[i];
      if (faceGroup[g] != faceGroup[f]) continue;
      uint32_t a = Find(parent, f), b = Find(parent, g);
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
    const int64_t r = Find(parent, f);
    if (rootOfGroup[g] < 0) rootOfGroup[g] = r;
    else if (rootOfGroup[g] != r) isBroken[g] = 1;
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
