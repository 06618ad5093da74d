// ConeLOD — how round and smooth the clusters of a face partition are.
//
// Tsuji, Zha, Kurazume, Hasegawa (§5.1, figs. 4-5) compare recursive PCA partitioning with
// bottom-up cluster merging by eye: the splitting planes give "smoother, straighter" boundaries.
// These figures put numbers on it, for any partition (PCA clusters, normal-cone groups, a user's
// per-face quality):
//  - boundaryRatio: the total length of the edges between different clusters, over the length K
//    round clusters of the same total area A would need, sqrt(pi A K) (each of K discs of area
//    A/K has perimeter 2 sqrt(pi A / K), every boundary shared by two): about 1 for round
//    clusters with straight boundaries (hexagons give 1.05), more for ragged ones;
//  - meanCompactness: the area-weighted mean over clusters of 4 pi area / perimeter² (1 for a
//    flat disc, smaller for elongated or ragged clusters; the mesh border counts as perimeter).
#pragma once

#include <vector>

#include "conelod/mesh/indexed_mesh.h"

namespace conelod {

struct ClusterShape {
  int clusters = 0;
  double boundaryLength = 0;   // model units
  double boundaryRatio = 0;    // boundaryLength / sqrt(pi A K)
  double meanCompactness = 0;  // area-weighted, in (0, 1]
};

// faceCluster: per face, its cluster id (>= 0; -1 faces are ignored).
ClusterShape MeasureClusterShape(const IndexedMesh& m, const std::vector<int>& faceCluster);

}  // namespace conelod
