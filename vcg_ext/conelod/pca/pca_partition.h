// ConeLOD — face-based PCA and the recursive PCA partition of a mesh into a binary tree of
// edge-connected face clusters.
//
// Tsuji, Zha, Kurazume, Hasegawa, "Face clusters partitioning for hierarchical data structure and
// high speed rendering" (§3):
//  - face-based PCA (eq. 3-8): the covariance of the points of the surface, not of its vertices,
//      M_i = A_i { (v1v1ᵀ+v2v2ᵀ+v3v3ᵀ)/6 + (v1v2ᵀ+v2v3ᵀ+v3v1ᵀ+v2v1ᵀ+v3v2ᵀ+v1v3ᵀ)/12 }   (eq. 6)
//      Z_f = (Σ M_i − A r̄ r̄ᵀ) / A,  A = Σ A_i,  r̄ = Σ A_i r_i / A,  r_i = (v1+v2+v3)/3  (eq. 7-8)
//    so that a cluster whose vertices are dense on one side is not pulled towards that side;
//  - split (§3.3): the plane through r̄ perpendicular to x_max (the eigenvector of the largest
//    eigenvalue). R_i = x_max · (r_i − r̄); the seeds are the faces of largest and smallest R_i;
//    cluster 1 grows from its seed over adjacent faces with R_i > 0, cluster 2 over R_i < 0; each
//    connected region of faces reached by neither is attached whole to the cluster it shares more
//    edges with. Both children are therefore edge-connected;
//  - recursion down to single triangles, or until a stop criterion holds.
// BEYOND the paper: a mesh with several edge-connected components gets a root whose children are
// the components (the paper assumes one connected mesh); a cluster whose faces all lie on the
// split plane (duplicate or zero-area faces) is split by growing both halves at once from two of
// its faces, so that every split makes two non-empty connected children.
//
// The cluster error of §4 is λ_min of Z_f (the variance along the cluster's normal, a squared
// length). Cuts of the tree "split the largest-error cluster first"; ties go to the larger area.
//
// Cost: a split touches each face of its cluster a constant number of times (one pass for R_i,
// the region growing, the moment sums of the smaller half only: the larger half is the parent
// minus the smaller, by the parallel-axis theorem), so the full tree costs O(N · depth), depth ≈
// log2 N on real meshes (mean leaf depth 21.7 on the 871k-face dragon). The work arrays are
// allocated once; faces are renumbered in Morton order so that clusters are compact in memory;
// clusters are contiguous ranges of one face permutation (no per-node lists); single faces are
// leaves without a node. Precision: the sums are in double from per-face float data (centroid,
// area, own second moment), i.e. as accurate as the input's float coordinates.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <vcg/space/box3.h>
#include <vcg/space/point3.h>

#include "conelod/grouping/group_hierarchy.h"
#include "conelod/mesh/indexed_mesh.h"
#include "conelod/grouping/normal_cone.h"
#include "conelod/status.h"

namespace conelod {

// ---------------------------------------------------------------------------------------------
// Face-based PCA

// The exact second moment ∫ r rᵀ dS of the triangle (a, b, c) about the origin (eq. 6), with
// `area` its area: area/12 (Σ v vᵀ + (Σ v)(Σ v)ᵀ), the same as the paper's 1/6 and 1/12 weights.
Eigen::Matrix3d TriangleSecondMoment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                     double area);

struct PcaFrame {
  double area = 0;  // A, total area (0 for vertex-based PCA)
  Eigen::Vector3d centroid{0, 0, 0};
  Eigen::Vector3d eigenvalues{0, 0, 0};                // ascending: λ_min, λ_mid, λ_max
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // columns: x_min, x_mid, x_max (unit)
  Eigen::Vector3d axisMax() const { return axes.col(2); }
  Eigen::Vector3d axisMin() const { return axes.col(0); }
};

// Face-based PCA (eq. 8) of the given faces (all faces when `faces` is null). Sums are taken about
// the first vertex so that a mesh far from the origin keeps its precision. A set of zero total
// area gives area 0, the unweighted centroid of the face centroids and zero eigenvalues.
PcaFrame FaceBasedPca(const IndexedMesh& m, const std::vector<uint32_t>* faces = nullptr);

// Vertex-based PCA (eq. 1-2) of the vertices used by the given faces: the covariance of the points
// themselves (the 1/(k-1) sample normalisation), for comparison with FaceBasedPca.
PcaFrame VertexBasedPca(const IndexedMesh& m, const std::vector<uint32_t>* faces = nullptr);

// ---------------------------------------------------------------------------------------------
// The partition tree

// A cluster of the tree is either a node (an item >= 0, the index into PcaTree::nodes) or a single
// face f (the item ~f, < 0): single triangles are leaves without a node, which halves the memory
// of the full tree.
using PcaItem = int32_t;
constexpr PcaItem kNoChild = INT32_MAX;
inline bool IsFaceItem(PcaItem item) { return item < 0; }
inline uint32_t FaceOfItem(PcaItem item) { return uint32_t(~item); }
inline PcaItem ItemOfFace(uint32_t f) { return ~PcaItem(f); }

// What the split pass computes for a node (64 bytes).
struct PcaNode {
  int32_t parent = -1;                      // node index; -1 at the root
  PcaItem child[2] = {kNoChild, kNoChild};  // the two halves; kNoChild for a leaf cluster (a stop
                                            // criterion held) and for the root of a disconnected mesh, whose
                                            // children are PcaTree::components (use PcaTree::children())
  uint32_t firstFace = 0;                   // faces: PcaTree::faceOrder[firstFace .. firstFace + faceCount)
  uint32_t faceCount = 0;
  int32_t depth = 0;  // the root is 0
  float area = 0;
  vcg::Point3f centroid;     // area centroid r̄
  vcg::Point3f eigenvalues;  // of Z_f, ascending (λ_min, λ_mid, λ_max), squared length units
  vcg::Point3f axis;         // x_max, the split direction (unit)

  float error() const { return eigenvalues[0]; }  // λ_min, the §4 cluster error
};

// What a bottom-up pass computes after the split pass has released its work memory (40 bytes).
struct PcaBounds {
  vcg::Point3f coneAxis;     // normal cone: the union of the children's cones (an upper bound of the
  float coneHalfAngle = -1;  // exact minimal cone; exact for leaf clusters); radians, < 0 empty,
                             // >= pi/2 not cullable
  vcg::Box3f box;            // bounding box of the cluster's vertices

  NormalCone cone() const;
};

struct PcaItemRange {  // the children of a node, for range-for
  const PcaItem* first;
  int count;
  const PcaItem* begin() const { return first; }
  const PcaItem* end() const { return first + count; }
};

struct PcaTree {
  std::vector<PcaNode> nodes;       // nodes[0] is the root; a child's index is above its parent's
  std::vector<PcaBounds> bounds;    // per node
  std::vector<PcaItem> components;  // the root's children when the mesh has several components
  std::vector<uint32_t> faceOrder;  // a permutation of the faces: every cluster is a range of it
  int faceCount = 0;
  int componentCount = 0;  // edge-connected components of the mesh
  int maxDepth = 0;        // of the tree, single-face leaves included

  bool empty() const { return nodes.empty(); }
  PcaItemRange children(int32_t node) const {
    if (node == 0 && !components.empty()) return {components.data(), int(components.size())};
    const PcaNode& n = nodes[size_t(node)];
    return {n.child, n.child[0] == kNoChild ? 0 : 2};
  }
  bool isLeaf(int32_t node) const { return children(node).count == 0; }
  int leafClusterCount() const;  // clusters of the finest cut (single faces and leaf nodes)
  uint32_t itemFaceCount(PcaItem item) const { return IsFaceItem(item) ? 1u : nodes[size_t(item)].faceCount; }
  size_t memoryBytes() const;  // capacity of the arrays above
};

struct PcaPartitionParams {
  int targetClusters = 0;  // stop at this many clusters, splitting the largest error first; 0: no limit
  int maxDepth = 0;        // clusters at this depth are not split (the root is 0); 0: no limit
  int minFaces = 1;        // clusters of this many faces or fewer are not split; 1: down to triangles
  double maxErrorRms = 0;  // clusters with sqrt(λ_min) <= this length are not split; 0: no limit
};

Status ValidateParams(const PcaPartitionParams& p);

// Builds the tree. The mesh must pass RequireValidForFaces (checked here). On failure or
// cancellation `out` is left empty. With targetClusters > 0 the tree is built best-first and holds
// exactly the splits of CutByCount(full tree, targetClusters).
Status BuildPcaTree(const IndexedMesh& mesh, const PcaPartitionParams& params, PcaTree& out,
                    const Progress& progress = Progress());

// ---------------------------------------------------------------------------------------------
// Cuts

// The clusters after splitting, largest error first, until there are `clusterCount` of them (or
// the tree has no more splits). A disconnected mesh starts from its components, so a cut never
// has fewer clusters than components.
std::vector<PcaItem> CutByCount(const PcaTree& tree, int clusterCount);
// The clusters after splitting every cluster with sqrt(λ_min) > maxErrorRms (that has children).
std::vector<PcaItem> CutByError(const PcaTree& tree, double maxErrorRms);
// The nodes in the order CutByCount splits them (the root first): CutByCount(tree, K) is the
// result of the first K − (starting clusters) splits. The progressive mesh undoes them backwards.
std::vector<int32_t> SplitSequence(const PcaTree& tree);
// Per face: the index of its cluster in `cut`.
void FaceClustersOfCut(const PcaTree& tree, const std::vector<PcaItem>& cut, std::vector<int>& faceCluster);

// Checks that every node's range is the concatenation of its children's ranges, that faceOrder
// is a permutation, and that every node is edge-connected: so every cut partitions the faces into
// edge-connected clusters. O(N · depth). Returns "" or what is wrong.
std::string VerifyPcaTree(const IndexedMesh& mesh, const FaceAdjacency& adj, const PcaTree& tree);

// A group hierarchy (as cone_grouping.h builds) from nested cuts: level 1 is the cut with
// clusterCounts[0] clusters, level k the cut with clusterCounts[k-1] (decreasing counts; each
// coarser cut is a union of clusters of the finer, since cuts are prefixes of one split order).
// Every group gets its exact minimal normal cone, bounding box and a bounding sphere, so that
// culling_cost.h can evaluate the PCA clusters like normal-cone groups.
Status PcaGroupHierarchy(const IndexedMesh& mesh, const PcaTree& tree, const std::vector<int>& clusterCounts,
                         GroupHierarchy& out);

}  // namespace conelod
