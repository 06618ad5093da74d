// ConeLOD — the progressive cluster mesh: a coarse mesh whose vertices are the corners of the
// clusters of a PCA partition tree.
//
// Tsuji, Zha, Kurazume, Hasegawa, "Face clusters partitioning for hierarchical data structure and
// high speed rendering" (§4): the cluster error is λ_min of the cluster's face-based covariance.
// Starting from the finest clusters, the splits of the tree are undone in order of increasing
// error (the reverse of the largest-error-first split order of pca_partition.h); after each merge
// the vertices that touch fewer than 3 clusters are removed by moving them along the cluster
// boundary onto the nearest neighbouring vertex (a half-edge collapse). The mesh border counts as
// one more cluster, so the border keeps its corners and is simplified along itself.
//
// Which collapse u -> v is allowed (u removed, v kept), in the order tried (nearest v first):
//  - u touches 1 cluster and is not on the border: v is any neighbour;
//  - u touches 2 clusters: v is one of the two neighbours along the boundary between them (u's
//    faces must form one arc per cluster, else u is left alone);
//  - u is on the border and touches 1 cluster: v is one of its two border neighbours.
// A collapse is refused when it would
//  - break the 2-manifold: the link condition Lk(u) ∩ Lk(v) = Lk(uv), with a virtual vertex
//    joined to every border vertex (so that no interior edge between two border vertices
//    collapses and pinches the surface);
//  - flip a face or make it degenerate: every face that moves keeps its normal within
//    `maxNormalTurnDeg` of the normal it had before the collapse;
//  - remove a cluster's last face (clusters stay non-empty; they also stay edge-connected: the
//    two faces that vanish have their wing faces glued together, and u's remaining faces stay a
//    connected fan).
// Vertices of non-manifold edges or with non-manifold fans in the input never move: the output is
// a 2-manifold wherever the input is one. A vertex whose every collapse is refused stays (counted
// in blockedVertices).
#pragma once

#include <vector>

#include "conelod/mesh/indexed_mesh.h"
#include "conelod/pca/pca_partition.h"
#include "conelod/status.h"

namespace conelod {

struct ProgressiveMeshParams {
  int targetClusters = 1000;       // merge down to this many clusters (never fewer than the components)
  double maxNormalTurnDeg = 45.0;  // in (0, 180): a collapse may turn a face's normal by less than this
};

Status ValidateParams(const ProgressiveMeshParams& p);

struct ProgressiveMeshResult {
  IndexedMesh mesh;                    // the coarse mesh: kept vertices (input order) and faces
  std::vector<int> faceCluster;        // per coarse face: index into CutByCount(tree, clusters)
  std::vector<uint32_t> vertexOrigin;  // per coarse vertex: its index in the input mesh
  std::vector<uint32_t> faceOrigin;    // per coarse face: the input face it descends from
  // Per input vertex: the coarse vertex its collapses ended in (a kept vertex: its own);
  // UINT32_MAX where no face used it. Issue 26: the attributes the coarse vertex stands for.
  std::vector<uint32_t> survivor;
  int clusters = 0;            // clusters at the end (the target, unless the tree has fewer)
  size_t collapses = 0;        // half-edge collapses done
  size_t blockedVertices = 0;  // vertices touching < 3 clusters that no allowed collapse removed
  size_t lockedVertices = 0;   // vertices never moved (non-manifold in the input)
};

// The coarse mesh at params.targetClusters clusters of `tree` (built on `mesh`, to single faces or
// not). The input is not changed; on failure or cancellation `out` is left empty.
Status BuildProgressiveClusterMesh(const IndexedMesh& mesh, const PcaTree& tree, const ProgressiveMeshParams& params,
                                   ProgressiveMeshResult& out, const Progress& progress = Progress());

// The same from the mesh alone: its PCA tree (PcaPartitionParams() defaults) and the coarse mesh,
// both computed on the mesh times NormalizingScale(mesh) (a power of two, so exact) and the
// result's positions scaled back. The tree keeps its errors and areas in single precision in the
// model's units, where a model 2^-60 times too small has them all zero (the merge order lost) and
// the PCA's sums in denormal numbers (a hundred times slower); scaled, the result of a mesh times
// 2^k is that of the mesh times 2^k, bit for bit. `treeSeconds` (optional): the tree's time.
Status BuildProgressiveClusterMeshOf(const IndexedMesh& mesh, const ProgressiveMeshParams& params,
                                     ProgressiveMeshResult& out, const Progress& progress = Progress(),
                                     double* treeSeconds = nullptr);

}  // namespace conelod
