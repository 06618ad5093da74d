// Tests of progressive_cluster_mesh.h: the coarse mesh is a 2-manifold with consistent
// orientation, its vertices are cluster corners, clusters survive and stay connected, the input
// is untouched; exact behaviour on tiny meshes; the bunny at 100 / 1,000 / 10,000 clusters.
#include "conelod/pca/progressive_cluster_mesh.h"

#include <gtest/gtest.h>

#include <set>

#include "conelod/mesh/manifold_check.h"
#include "conelod/mesh/mesh_check.h"
#include "conelod/mesh/sampled_distance.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"
#include "test_util.h"

namespace conelod {
namespace {

IndexedMesh LoadReal(const std::string& name) {
  CMesh m;
  EXPECT_EQ(LoadPly(m, test::MeshPath(name)), "");
  return ToIndexedMesh(m);
}

ProgressiveMeshResult Coarse(const IndexedMesh& m, int clusters, PcaTree* treeOut = nullptr) {
  PcaTree tree;
  EXPECT_TRUE(BuildPcaTree(m, PcaPartitionParams(), tree).ok());
  ProgressiveMeshParams p;
  p.targetClusters = clusters;
  ProgressiveMeshResult r;
  EXPECT_TRUE(BuildProgressiveClusterMesh(m, tree, p, r).ok());
  if (treeOut) *treeOut = std::move(tree);
  return r;
}

// Every property the header promises, on a manifold input.
void ExpectSoundCoarseMesh(const IndexedMesh& in, const ProgressiveMeshResult& r) {
  const ManifoldReport mr = CheckManifold(r.mesh);
  EXPECT_TRUE(mr.valid()) << mr.nonManifoldEdges << " non-manifold edges, " << mr.nonManifoldVertices
                          << " non-manifold vertices, " << mr.misorientedEdges << " misoriented edges";
  EXPECT_EQ(mr.degenerateFaces, 0u);
  ASSERT_EQ(r.faceCluster.size(), r.mesh.faces.size());
  ASSERT_EQ(r.faceOrigin.size(), r.mesh.faces.size());
  ASSERT_EQ(r.vertexOrigin.size(), r.mesh.positions.size());
  // Vertices are input vertices, unmoved (half-edge collapses only).
  for (size_t v = 0; v < r.vertexOrigin.size(); ++v) EXPECT_EQ(r.mesh.positions[v], in.positions[r.vertexOrigin[v]]);
  // Every cluster survives, in one edge-connected piece.
  std::set<int> ids(r.faceCluster.begin(), r.faceCluster.end());
  EXPECT_EQ(int(ids.size()), r.clusters);
  EXPECT_EQ(*ids.begin(), 0);
  EXPECT_EQ(*ids.rbegin(), r.clusters - 1);
  EXPECT_TRUE(GroupsAreEdgeConnected(BuildFaceAdjacency(r.mesh), r.faceCluster));
  // Vertices are cluster corners: three or more clusters (the border counting as one), except
  // the few that no allowed collapse could remove.
  std::vector<std::set<int>> around(r.mesh.positions.size());
  for (size_t f = 0; f < r.mesh.faces.size(); ++f)
    for (uint32_t v : r.mesh.faces[f]) around[v].insert(r.faceCluster[f]);
  std::vector<int> borderEdgesAt(r.mesh.positions.size(), 0);
  {
    std::map<std::pair<uint32_t, uint32_t>, int> edges;
    for (const auto& t : r.mesh.faces)
      for (int k = 0; k < 3; ++k) ++edges[std::minmax(t[size_t(k)], t[size_t((k + 1) % 3)])];
    for (const auto& e : edges)
      if (e.second == 1) {
        ++borderEdgesAt[e.first.first];
        ++borderEdgesAt[e.first.second];
      }
  }
  size_t fewer = 0;
  for (size_t v = 0; v < around.size(); ++v)
    if (around[v].size() + (borderEdgesAt[v] ? 1 : 0) < 3) ++fewer;
  EXPECT_EQ(fewer, r.blockedVertices);
}

TEST(ProgressiveMesh, SphereAtEightClusters) {
  const IndexedMesh m = test::Sphere(4);  // 2048 faces, closed
  const IndexedMesh copy = m;
  const ProgressiveMeshResult r = Coarse(m, 8);
  EXPECT_EQ(m.positions, copy.positions);  // the input is untouched
  EXPECT_EQ(m.faces, copy.faces);
  EXPECT_EQ(r.clusters, 8);
  ExpectSoundCoarseMesh(m, r);
  EXPECT_LT(r.mesh.faces.size(), 60u);
  EXPECT_EQ(r.blockedVertices, 0u);
  // A closed genus-0 surface stays one: V - E + F = 2.
  EXPECT_EQ(CheckManifold(r.mesh).borderEdges, 0u);
  EXPECT_EQ(int(r.mesh.positions.size()) - int(r.mesh.faces.size()) * 3 / 2 + int(r.mesh.faces.size()), 2);
  EXPECT_EQ(CountFacesAgainstSurface(r.mesh, m), 0u);
}

TEST(ProgressiveMesh, AllClustersKeepTheMesh) {
  // At as many clusters as faces nothing is merged: every vertex touches three clusters (or is
  // a border corner of a single face, whose collapse would destroy its cluster).
  const IndexedMesh m = test::Grid(4);
  const ProgressiveMeshResult r = Coarse(m, 1000);
  EXPECT_EQ(r.clusters, 32);
  EXPECT_EQ(r.mesh.faces.size(), m.faces.size());
  EXPECT_EQ(r.collapses, 0u);
}

TEST(ProgressiveMesh, FlatGridStaysFlatAndFacingUp) {
  const IndexedMesh m = test::Grid(12);
  const ProgressiveMeshResult r = Coarse(m, 6);
  ExpectSoundCoarseMesh(m, r);
  std::vector<vcg::Point3d> normals;
  std::vector<double> areas;
  ComputeFaceNormalsAndAreas(r.mesh, normals, areas);
  for (const auto& n : normals) EXPECT_GT(n[2], 0.999);  // no flip
  for (const auto& p : r.mesh.positions) EXPECT_EQ(p[2], 0.f);
  // One border loop: as many border edges as border vertices.
  const ManifoldReport mr = CheckManifold(r.mesh);
  EXPECT_GT(mr.borderEdges, 3u);
  EXPECT_LT(r.mesh.faces.size(), 60u);
}

TEST(ProgressiveMesh, BunnyAtOneHundredThousandAndTenThousandClusters) {
  const IndexedMesh bunny = LoadReal("stanford_bunny_bun_zipper.ply");
  PcaTree tree;
  ASSERT_TRUE(BuildPcaTree(bunny, PcaPartitionParams(), tree).ok());
  size_t previousFaces = 0;
  for (int k : {100, 1000, 10000}) {
    SCOPED_TRACE(k);
    ProgressiveMeshParams p;
    p.targetClusters = k;
    ProgressiveMeshResult r;
    ASSERT_TRUE(BuildProgressiveClusterMesh(bunny, tree, p, r).ok());
    EXPECT_EQ(r.clusters, k);
    ExpectSoundCoarseMesh(bunny, r);
    EXPECT_GT(r.mesh.faces.size(), previousFaces);
    previousFaces = r.mesh.faces.size();
    // Cluster ids are those of the partition at the same count.
    std::vector<int> fc;
    FaceClustersOfCut(tree, CutByCount(tree, k), fc);
    for (size_t f = 0; f < r.faceOrigin.size(); ++f) EXPECT_EQ(r.faceCluster[f], fc[r.faceOrigin[f]]);
    HausdorffResult h;
    ASSERT_TRUE(SampledHausdorff(bunny, r.mesh, 50000, h).ok());
    EXPECT_LT(h.hausdorff, (k == 100 ? 0.06 : 0.025) * h.diagonal);
    EXPECT_LT(r.blockedVertices, r.mesh.positions.size() / 10);  // almost every vertex is a corner
    if (k >= 1000) {
      EXPECT_EQ(CountFacesAgainstSurface(r.mesh, bunny), 0u);
    }
  }
}

TEST(ProgressiveMesh, NonManifoldInputStaysNonManifoldOnlyWhereItWas) {
  const IndexedMesh m = LoadReal("stanford_bunny_bun_zipper_res4.ply");  // 70 non-manifold edges
  const ProgressiveMeshResult r = Coarse(m, 30);
  EXPECT_GT(r.lockedVertices, 0u);
  const ManifoldReport in = CheckManifold(m), out = CheckManifold(r.mesh);
  EXPECT_LE(out.nonManifoldEdges, in.nonManifoldEdges);
  EXPECT_LE(out.misorientedEdges, in.misorientedEdges);
  EXPECT_LT(r.mesh.faces.size(), m.faces.size());
  // Several components: never fewer clusters than components.
  const IndexedMesh boeing = LoadReal("boeing.ply");
  const ProgressiveMeshResult b = Coarse(boeing, 10);
  EXPECT_EQ(b.clusters, 122);
  EXPECT_TRUE(GroupsAreEdgeConnected(BuildFaceAdjacency(b.mesh), b.faceCluster));
}

TEST(ProgressiveMesh, CancellationAndBadParameters) {
  const IndexedMesh m = test::Sphere(4);
  PcaTree tree;
  ASSERT_TRUE(BuildPcaTree(m, PcaPartitionParams(), tree).ok());
  ProgressiveMeshParams p;
  p.targetClusters = 4;
  ProgressiveMeshResult r;
  int calls = 0;
  const Status s = BuildProgressiveClusterMesh(m, tree, p, r, [&](int, const char*) { return ++calls < 2; });
  EXPECT_EQ(s.code, Status::Code::Cancelled);
  EXPECT_TRUE(r.mesh.faces.empty());
  p.targetClusters = 0;
  EXPECT_FALSE(BuildProgressiveClusterMesh(m, tree, p, r).ok());
  p.targetClusters = 4;
  p.maxNormalTurnDeg = 0;
  EXPECT_FALSE(BuildProgressiveClusterMesh(m, tree, p, r).ok());
  p.maxNormalTurnDeg = 45;
  EXPECT_FALSE(BuildProgressiveClusterMesh(test::Cube(), tree, p, r).ok());  // another mesh's tree
}

}  // namespace
}  // namespace conelod
