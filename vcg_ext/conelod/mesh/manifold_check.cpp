// ConeLOD — manifold check (see manifold_check.h).
#include "conelod/mesh/manifold_check.h"
#include "conelod/common.h"

#include <algorithm>
#include <numeric>
#include <vector>

namespace conelod {
ManifoldReport CheckManifold(const IndexedMesh& m) {
  ManifoldReport r;
  const uint32_t nf = uint32_t(m.faces.size());
  std::vector<vcg::Point3d> normals;
  std::vector<double> areas;
  ComputeFaceNormalsAndAreas(m, normals, areas);
  // Directed edges (a, b, face), sorted by undirected key.
  struct Half {
    uint32_t lo, hi, face;
    bool forward;
  };
  std::vector<Half> halves;
  halves.reserve(size_t(nf) * 3);
  for (uint32_t f = 0; f < nf; ++f) {
    const auto& t = m.faces[f];
    if (UsesAVertexTwice(t)) {
      ++r.degenerateFaces;
      continue;
    }
    if (areas[f] == 0) ++r.degenerateFaces;
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[size_t(k)], b = t[size_t((k + 1) % 3)];
      halves.push_back(Half{std::min(a, b), std::max(a, b), f, a < b});
    }
  }
  std::sort(halves.begin(), halves.end(), [](const Half& x, const Half& y) {
    return x.lo != y.lo ? x.lo < y.lo : (x.hi != y.hi ? x.hi < y.hi : x.face < y.face);
  });
  // Fans: around each vertex, faces joined through the manifold edges at that vertex must form
  // one set. Union-find over (vertex, face) corners.
  std::vector<uint32_t> cornerStart(m.positions.size() + 1, 0);
  for (const auto& t : m.faces)
    if (!UsesAVertexTwice(t))
      for (uint32_t v : t) ++cornerStart[v + 1];
  for (size_t v = 0; v < m.positions.size(); ++v) cornerStart[v + 1] += cornerStart[v];
  std::vector<uint32_t> cornerFace(cornerStart.back());
  {
    std::vector<uint32_t> fill(cornerStart.begin(), cornerStart.end() - 1);
    for (uint32_t f = 0; f < nf; ++f) {
      const auto& t = m.faces[f];
      if (UsesAVertexTwice(t)) continue;
      for (uint32_t v : t) cornerFace[fill[v]++] = f;
    }
  }
  auto corner = [&](uint32_t v, uint32_t f) {
    for (uint32_t i = cornerStart[v]; i < cornerStart[v + 1]; ++i)
      if (cornerFace[i] == f) return i;
    return cornerStart[v];
  };
  std::vector<uint32_t> parent(cornerFace.size());
  std::iota(parent.begin(), parent.end(), 0u);
  std::vector<char> onBadEdge(m.positions.size(), 0);
  for (size_t i = 0; i < halves.size();) {
    size_t j = i;
    while (j < halves.size() && halves[j].lo == halves[i].lo && halves[j].hi == halves[i].hi) ++j;
    const size_t count = j - i;
    if (count == 1)
      ++r.borderEdges;
    else if (count > 2) {
      ++r.nonManifoldEdges;
      onBadEdge[halves[i].lo] = onBadEdge[halves[i].hi] = 1;
    } else {
      if (halves[i].forward == halves[i + 1].forward) ++r.misorientedEdges;
      for (uint32_t v : {halves[i].lo, halves[i].hi}) {
        const uint32_t a = FindRoot(parent, corner(v, halves[i].face)),
                       b = FindRoot(parent, corner(v, halves[i + 1].face));
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
    }
    i = j;
  }
  for (size_t v = 0; v < m.positions.size(); ++v) {
    if (onBadEdge[v]) continue;
    bool one = true;
    for (uint32_t i = cornerStart[v]; i < cornerStart[v + 1]; ++i)
      if (FindRoot(parent, i) != FindRoot(parent, cornerStart[v])) one = false;
    if (!one) ++r.nonManifoldVertices;
  }
  return r;
}

}  // namespace conelod
