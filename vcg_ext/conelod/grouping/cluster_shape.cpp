// ConeLOD — cluster shape figures (see cluster_shape.h).
#include "conelod/common.h"
#include "conelod/grouping/cluster_shape.h"

#include <algorithm>
#include <cmath>

namespace conelod {

ClusterShape MeasureClusterShape(const IndexedMesh& m, const std::vector<int>& faceCluster) {
  ClusterShape out;
  int maxId = -1;
  for (int c : faceCluster) maxId = std::max(maxId, c);
  if (maxId < 0) return out;
  std::vector<vcg::Point3d> normals;
  std::vector<double> areas;
  ComputeFaceNormalsAndAreas(m, normals, areas);
  std::vector<double> area(size_t(maxId) + 1, 0), perimeter(size_t(maxId) + 1, 0);
  std::vector<char> present(size_t(maxId) + 1, 0);
  double totalArea = 0;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const int c = faceCluster[f];
    if (c < 0) continue;
    area[size_t(c)] += areas[f];
    present[size_t(c)] = 1;
    totalArea += areas[f];
  }
  // Undirected edges with their faces, sorted: each edge is seen once with all its faces.
  struct Half {
    uint32_t lo, hi;
    int cluster;
  };
  std::vector<Half> halves;
  halves.reserve(m.faces.size() * 3);
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (faceCluster[f] < 0) continue;
    const auto& t = m.faces[f];
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[size_t(k)], b = t[size_t((k + 1) % 3)];
      if (a != b) halves.push_back(Half{std::min(a, b), std::max(a, b), faceCluster[f]});
    }
  }
  std::sort(halves.begin(), halves.end(), [](const Half& x, const Half& y) {
    return x.lo != y.lo ? x.lo < y.lo : (x.hi != y.hi ? x.hi < y.hi : x.cluster < y.cluster);
  });
  for (size_t i = 0; i < halves.size();) {
    size_t j = i;
    while (j < halves.size() && halves[j].lo == halves[i].lo && halves[j].hi == halves[i].hi) ++j;
    const double len = vcg::Distance(vcg::Point3d::Construct(m.positions[halves[i].lo]),
                                     vcg::Point3d::Construct(m.positions[halves[i].hi]));
    const bool border = j - i == 1;
    const bool between = halves[i].cluster != halves[j - 1].cluster;  // sorted: first != last
    if (between) out.boundaryLength += len;
    if (border || between)
      for (size_t k = i; k < j; ++k)
        if (k == i || halves[k].cluster != halves[k - 1].cluster) perimeter[size_t(halves[k].cluster)] += len;
    i = j;
  }
  double weighted = 0, weight = 0;
  for (size_t c = 0; c < area.size(); ++c) {
    if (!present[c]) continue;
    ++out.clusters;
    if (perimeter[c] <= 0) continue;  // a closed surface: no boundary to measure
    weighted += area[c] * std::min(1.0, 4 * kPi * area[c] / (perimeter[c] * perimeter[c]));
    weight += area[c];
  }
  out.meanCompactness = weight > 0 ? weighted / weight : 0;
  out.boundaryRatio = totalArea > 0 ? out.boundaryLength / std::sqrt(kPi * totalArea * out.clusters) : 0;
  return out;
}

}  // namespace conelod
