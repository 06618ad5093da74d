// Tests of pca_partition.h: the face-based second moments against numerical integration, face-
// against vertex-based PCA on uneven density, exact splits on tiny meshes, the tree's invariants
// (every node edge-connected, ranges tiling the faces) on real scans, cuts, stop criteria,
// progress and cancellation, bad input.
#include "conelod/pca/pca_partition.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>

#include "conelod/grouping/culling_cost.h"
#include "conelod/mesh/mesh_check.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"
#include "test_util.h"

namespace conelod {
namespace {

IndexedMesh LoadReal(const std::string& name) {
  CMesh m;
  const std::string err = LoadPly(m, test::MeshPath(name));
  EXPECT_EQ(err, "") << "the real test meshes live in ../shared/test_meshes (set CONELOD_TEST_MESHES)";
  return ToIndexedMesh(m);
}

Eigen::Vector3d V(double x, double y, double z) { return Eigen::Vector3d(x, y, z); }

// ∫ r rᵀ dS over the triangle by the centroid rule on n² congruent sub-triangles (error O(1/n²)).
Eigen::Matrix3d IntegrateSecondMoment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                      int n) {
  const double area = 0.5 * (b - a).cross(c - a).norm();
  const double sub = area / (double(n) * n);
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  const Eigen::Vector3d u = (b - a) / n, v = (c - a) / n;
  for (int i = 0; i < n; ++i)
    for (int j = 0; i + j < n; ++j) {
      const Eigen::Vector3d p = a + u * i + v * j;
      const Eigen::Vector3d up = p + (u + v) / 3;  // "upright" sub-triangle
      m += sub * up * up.transpose();
      if (i + j + 1 < n) {
        const Eigen::Vector3d down = p + (u + v) * (2.0 / 3);  // the inverted one
        m += sub * down * down.transpose();
      }
    }
  return m;
}

TEST(FacePca, SecondMomentMatchesNumericalIntegration) {
  // A scalene triangle away from the origin: every entry of M_i is non-trivial.
  const Eigen::Vector3d a = V(1.0, 2.0, -0.5), b = V(3.5, 2.5, 0.7), c = V(1.7, 4.2, 1.9);
  const double area = 0.5 * (b - a).cross(c - a).norm();
  const Eigen::Matrix3d exact = TriangleSecondMoment(a, b, c, area);
  // The paper's eq. (6), literally: weights 1/6 on v_i v_iᵀ and 1/12 on the six cross terms.
  const Eigen::Matrix3d paper = area * ((a * a.transpose() + b * b.transpose() + c * c.transpose()) / 6 +
                                        (a * b.transpose() + b * c.transpose() + c * a.transpose() + b * a.transpose() +
                                         c * b.transpose() + a * c.transpose()) /
                                            12);
  EXPECT_LT((exact - paper).norm(), 1e-12 * paper.norm());
  // The midpoint rule converges to it, and its error shrinks as 1/n².
  const double e64 = (IntegrateSecondMoment(a, b, c, 64) - exact).norm() / exact.norm();
  const double e256 = (IntegrateSecondMoment(a, b, c, 256) - exact).norm() / exact.norm();
  EXPECT_LT(e256, 1e-5);
  EXPECT_NEAR(e64 / e256, 16.0, 1.0);
  // Wrong weights (1/3 and 1/6, say) would be far off.
  const Eigen::Matrix3d wrong = area * ((a * a.transpose() + b * b.transpose() + c * c.transpose()) / 3);
  EXPECT_GT((wrong - exact).norm(), 0.1 * exact.norm());
}

TEST(FacePca, RectangleHasTheExactCovariance) {
  // [0,4] x [0,2] in the plane z = 1, two triangles: Z = diag(4²/12, 2²/12, 0).
  IndexedMesh m;
  m.positions = {{0, 0, 1}, {4, 0, 1}, {4, 2, 1}, {0, 2, 1}};
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  const PcaFrame fr = FaceBasedPca(m);
  EXPECT_NEAR(fr.area, 8.0, 1e-12);
  EXPECT_NEAR((fr.centroid - V(2, 1, 1)).norm(), 0, 1e-12);
  EXPECT_NEAR(fr.eigenvalues[0], 0, 1e-12);
  EXPECT_NEAR(fr.eigenvalues[1], 4.0 / 12, 1e-12);
  EXPECT_NEAR(fr.eigenvalues[2], 16.0 / 12, 1e-12);
  EXPECT_NEAR(std::abs(fr.axisMax()[0]), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(fr.axisMin()[2]), 1.0, 1e-12);
}

// A rectangle [0, w] x [0, 1] whose triangulation is dense where `dense(x, y)` says so.
IndexedMesh UnevenRectangle(double w, int coarse, int fine, bool (*dense)(double, double)) {
  IndexedMesh m;
  const int n = coarse * fine;  // vertex lattice at the fine spacing
  std::map<std::pair<int, int>, uint32_t> id;
  auto vertex = [&](int i, int j) {
    auto it = id.find({i, j});
    if (it != id.end()) return it->second;
    m.positions.emplace_back(float(w * i / n), float(double(j) / n), 0.f);
    return id[{i, j}] = uint32_t(m.positions.size() - 1);
  };
  auto quad = [&](int i, int j, int s) {  // lattice square of side s at (i, j)
    const uint32_t a = vertex(i, j), b = vertex(i + s, j), c = vertex(i + s, j + s), d = vertex(i, j + s);
    m.faces.push_back({a, b, c});
    m.faces.push_back({a, c, d});
  };
  // Coarse cells are split into fine cells where dense; hanging vertices do not matter here
  // (the surface is flat), only the density of vertices and faces does.
  for (int ci = 0; ci < coarse; ++ci)
    for (int cj = 0; cj < coarse; ++cj) {
      const double x = w * (ci + 0.5) / coarse, y = (cj + 0.5) / coarse;
      if (dense(x / w, y))
        for (int fi = 0; fi < fine; ++fi)
          for (int fj = 0; fj < fine; ++fj) quad(ci * fine + fi, cj * fine + fj, 1);
      else
        quad(ci * fine, cj * fine, fine);
    }
  return m;
}

TEST(FacePca, FaceBasedIgnoresVertexDensityVertexBasedDoesNot) {
  // The paper's point (§3.2): where vertices are denser, vertex-based PCA leans that way.
  // (1) Dense left half of [0,2] x [0,1]: the surface centroid stays at x = 1.
  const IndexedMesh left = UnevenRectangle(2.0, 8, 6, [](double x, double) { return x < 0.5; });
  const PcaFrame fl = FaceBasedPca(left), vl = VertexBasedPca(left);
  EXPECT_NEAR(fl.centroid[0], 1.0, 1e-6);
  EXPECT_NEAR(fl.eigenvalues[2], 4.0 / 12, 1e-6);  // exact for the rectangle
  EXPECT_LT(vl.centroid[0], 0.8);                  // pulled to the dense side
  // (2) Dense strips along y = 0 and y = 1 of a 1.2 x 1 rectangle: the true principal axis is x
  // (1.2 > 1), but the vertices' spread is larger along y.
  const IndexedMesh strips = UnevenRectangle(1.2, 10, 6, [](double, double y) { return y < 0.15 || y > 0.85; });
  const PcaFrame fs = FaceBasedPca(strips), vs = VertexBasedPca(strips);
  EXPECT_GT(std::abs(fs.axisMax()[0]), 0.999);
  EXPECT_NEAR(fs.eigenvalues[2], 1.44 / 12, 1e-6);
  EXPECT_NEAR(fs.eigenvalues[1], 1.0 / 12, 1e-6);
  EXPECT_GT(std::abs(vs.axisMax()[1]), 0.999);  // vertex-based picks y: the split would be wrong
}

TEST(FacePca, FarFromTheOriginKeepsPrecision) {
  IndexedMesh m;
  m.positions = {{1e5f, 1e5f, 0}, {1e5f + 4, 1e5f, 0}, {1e5f + 4, 1e5f + 2, 0}, {1e5f, 1e5f + 2, 0}};
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  const PcaFrame fr = FaceBasedPca(m);
  EXPECT_NEAR(fr.eigenvalues[2], 16.0 / 12, 1e-9);
  EXPECT_NEAR(fr.eigenvalues[1], 4.0 / 12, 1e-9);
}

// ---------------------------------------------------------------------------------------------

void ExpectSoundTree(const IndexedMesh& mesh, const PcaTree& tree) {
  const FaceAdjacency adj = BuildFaceAdjacency(mesh);
  EXPECT_EQ(VerifyPcaTree(mesh, adj, tree), "");
}

TEST(PcaTree, ElongatedStripSplitsInTheMiddleAcrossItsLength) {
  // 16 x 4 quads (128 faces) along x: the first split is the plane x = 8, cutting no triangle.
  IndexedMesh m;
  for (int y = 0; y <= 4; ++y)
    for (int x = 0; x <= 16; ++x) m.positions.emplace_back(float(x), float(y), 0.f);
  auto id = [](int x, int y) { return uint32_t(y * 17 + x); };
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 16; ++x) {
      m.faces.push_back({id(x, y), id(x + 1, y), id(x + 1, y + 1)});
      m.faces.push_back({id(x, y), id(x + 1, y + 1), id(x, y + 1)});
    }
  PcaTree tree;
  ASSERT_TRUE(BuildPcaTree(m, PcaPartitionParams(), tree).ok());
  ExpectSoundTree(m, tree);
  const PcaNode& root = tree.nodes[0];
  EXPECT_NEAR(root.centroid[0], 8.0, 1e-5);
  EXPECT_NEAR(std::abs(root.axis[0]), 1.0, 1e-6);
  EXPECT_NEAR(root.eigenvalues[2], 256.0 / 12, 1e-3);  // length 16: 16²/12
  EXPECT_NEAR(root.eigenvalues[1], 16.0 / 12, 1e-4);   // width 4
  EXPECT_NEAR(root.eigenvalues[0], 0.0, 1e-9);
  ASSERT_EQ(tree.children(0).count, 2);
  for (PcaItem c : tree.children(0)) {
    ASSERT_FALSE(IsFaceItem(c));
    const PcaNode& half = tree.nodes[size_t(c)];
    EXPECT_EQ(half.faceCount, 64u);
    for (uint32_t k = 0; k < half.faceCount; ++k) {
      const auto& t = m.faces[tree.faceOrder[half.firstFace + k]];
      const bool low = m.positions[t[0]][0] + m.positions[t[1]][0] + m.positions[t[2]][0] < 24;
      EXPECT_EQ(low, half.centroid[0] < 8) << "a face on the wrong side of the plane x = 8";
    }
  }
  // Down to single triangles: 127 nodes, 128 single-face leaves.
  EXPECT_EQ(tree.nodes.size(), 127u);
  EXPECT_EQ(tree.leafClusterCount(), 128);
}

TEST(PcaTree, FullTreeOnSmallMeshes) {
  for (const IndexedMesh& m : {test::Cube(), test::Sphere(3), test::Grid(9)}) {
    PcaTree tree;
    ASSERT_TRUE(BuildPcaTree(m, PcaPartitionParams(), tree).ok());
    ExpectSoundTree(m, tree);
    EXPECT_EQ(tree.nodes.size(), m.faces.size() - 1);
    EXPECT_EQ(tree.leafClusterCount(), int(m.faces.size()));
    EXPECT_EQ(tree.componentCount, 1);
    // Bounds: boxes hold the faces' vertices, cones hold the faces' normals.
    std::vector<vcg::Point3d> normals;
    std::vector<double> areas;
    ComputeFaceNormalsAndAreas(m, normals, areas);
    for (size_t i = 0; i < tree.nodes.size(); ++i) {
      const PcaNode& node = tree.nodes[i];
      const NormalCone cone = tree.bounds[i].cone();
      for (uint32_t k = 0; k < node.faceCount; ++k) {
        const uint32_t f = tree.faceOrder[node.firstFace + k];
        for (uint32_t v : m.faces[f]) EXPECT_TRUE(tree.bounds[i].box.IsIn(m.positions[v]));
        if (cone.cullable()) {
          EXPECT_TRUE(cone.contains(normals[f], 1e-6));
        }
      }
    }
  }
}

TEST(PcaTree, NodesCarryTheFaceBasedPcaOfTheirFaces) {
  const IndexedMesh bunny = LoadReal("stanford_bunny_bun_zipper.ply");
  PcaTree tree;
  ASSERT_TRUE(BuildPcaTree(bunny, PcaPartitionParams(), tree).ok());
  // Nodes are computed from sums (the larger child as parent minus the smaller): check some
  // against a direct face-based PCA of their faces.
  int checked = 0;
  for (size_t i = 0; i < tree.nodes.size(); i += 997) {
    const PcaNode& node = tree.nodes[i];
    std::vector<uint32_t> faces(tree.faceOrder.begin() + node.firstFace,
                                tree.faceOrder.begin() + node.firstFace + node.faceCount);
    const PcaFrame fr = FaceBasedPca(bunny, &faces);
    const double scale = fr.eigenvalues[2];
    EXPECT_NEAR(node.area, fr.area, 1e-5 * fr.area);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(node.centroid[k], fr.centroid[k], 1e-6 + 1e-4 * std::sqrt(scale));
      EXPECT_NEAR(node.eigenvalues[k], fr.eigenvalues[k], 1e-4 * scale + 1e-12);
    }
    if (fr.eigenvalues[2] > 1.01 * fr.eigenvalues[1]) {
      EXPECT_GT(std::abs(Eigen::Vector3d(node.axis[0], node.axis[1], node.axis[2]).dot(fr.axisMax())), 0.999);
    }
    ++checked;
  }
  EXPECT_GT(checked, 60);
}

TEST(PcaTree, RealScansEveryNodeConnectedAndExact) {
  // The bunny (one component), boeing (122 components), the non-manifold res4 bunny, blobby (3).
  for (const char* name :
       {"stanford_bunny_bun_zipper.ply", "boeing.ply", "stanford_bunny_bun_zipper_res4.ply", "blobby_3cc.ply"}) {
    SCOPED_TRACE(name);
    const IndexedMesh m = LoadReal(name);
    PcaTree tree;
    ASSERT_TRUE(BuildPcaTree(m, PcaPartitionParams(), tree).ok());
    ExpectSoundTree(m, tree);
    EXPECT_EQ(tree.leafClusterCount(), int(m.faces.size()));
    const MeshReport r = CheckMesh(m);
    EXPECT_EQ(tree.componentCount, r.components);
    if (r.components > 1) {
      EXPECT_EQ(tree.children(0).count, r.components);
    }
  }
}

TEST(PcaTree, ComponentsAreTheFirstSplit) {
  // Two cubes apart: the root's children are the cubes; no cut has fewer than two clusters.
  IndexedMesh m = test::Cube();
  const IndexedMesh other = test::Cube();
  for (const auto& p : other.positions) m.positions.push_back(p + vcg::Point3f(3, 0, 0));
  for (const auto& t : other.faces) m.faces.push_back({t[0] + 8, t[1] + 8, t[2] + 8});
  PcaTree tree;
  ASSERT_TRUE(BuildPcaTree(m, PcaPartitionParams(), tree).ok());
  ExpectSoundTree(m, tree);
  EXPECT_EQ(tree.componentCount, 2);
  ASSERT_EQ(tree.children(0).count, 2);
  std::vector<int> fc;
  FaceClustersOfCut(tree, CutByCount(tree, 1), fc);
  EXPECT_EQ(std::set<int>(fc.begin(), fc.end()).size(), 2u);
  for (int f = 0; f < 24; ++f) EXPECT_EQ(fc[size_t(f)], f < 12 ? fc[0] : fc[12]);
  EXPECT_NE(fc[0], fc[12]);
}

TEST(PcaCut, CutsPartitionNestAndMatchTheBestFirstBuild) {
  const IndexedMesh bunny = LoadReal("stanford_bunny_bun_zipper.ply");
  const FaceAdjacency adj = BuildFaceAdjacency(bunny);
  PcaTree full;
  ASSERT_TRUE(BuildPcaTree(bunny, PcaPartitionParams(), full).ok());
  std::vector<int> previous;
  for (int k : {1, 2, 7, 100, 1000}) {
    SCOPED_TRACE(k);
    const std::vector<PcaItem> cut = CutByCount(full, k);
    ASSERT_EQ(int(cut.size()), k);
    std::vector<int> fc;
    FaceClustersOfCut(full, cut, fc);
    std::vector<int> size(cut.size(), 0);
    for (int c : fc) {
      ASSERT_GE(c, 0);
      ++size[size_t(c)];
    }
    for (size_t c = 0; c < cut.size(); ++c) EXPECT_EQ(uint32_t(size[c]), full.itemFaceCount(cut[c]));
    EXPECT_TRUE(GroupsAreEdgeConnected(adj, fc));
    // Nested: every cluster of this cut lies in one cluster of the coarser one.
    if (!previous.empty()) {
      std::vector<int> parentOf(cut.size(), -1);
      for (size_t f = 0; f < fc.size(); ++f) {
        int& p = parentOf[size_t(fc[f])];
        if (p < 0) p = previous[f];
        EXPECT_EQ(p, previous[f]);
      }
    }
    previous = fc;
    // Built best-first to k clusters: the very same clusters.
    PcaPartitionParams params;
    params.targetClusters = k;
    PcaTree partial;
    ASSERT_TRUE(BuildPcaTree(bunny, params, partial).ok());
    ExpectSoundTree(bunny, partial);
    std::vector<int> fp;
    FaceClustersOfCut(partial, CutByCount(partial, k), fp);
    EXPECT_EQ(fp, fc);
    EXPECT_EQ(partial.leafClusterCount(), k);
  }
  // The split sequence reproduces the cuts.
  const std::vector<int32_t> seq = SplitSequence(full);
  EXPECT_EQ(seq.size(), full.nodes.size());
  EXPECT_EQ(seq[0], 0);
  // Largest error first among what is available: the first splits have non-increasing errors
  // unless a child's error exceeds its parent's.
  const std::vector<PcaItem> c3 = CutByCount(full, 3);
  std::set<PcaItem> expected(c3.begin(), c3.end()), got;
  for (PcaItem c : full.children(seq[0])) got.insert(c);
  got.erase(seq[1]);
  for (PcaItem c : full.children(seq[1])) got.insert(c);
  EXPECT_EQ(got, expected);
}

TEST(PcaCut, ByErrorSplitsEveryClusterAboveTheThreshold) {
  const IndexedMesh m = test::Sphere(4);
  PcaTree tree;
  ASSERT_TRUE(BuildPcaTree(m, PcaPartitionParams(), tree).ok());
  const double threshold = 0.01;  // RMS distance to the cluster plane, sphere of radius 1
  const std::vector<PcaItem> cut = CutByError(tree, threshold);
  EXPECT_GT(cut.size(), 8u);
  for (PcaItem c : cut)
    if (!IsFaceItem(c)) {
      EXPECT_LE(std::sqrt(tree.nodes[size_t(c)].eigenvalues[0]), threshold);
    }
  // ... and only those: every parent of a cut cluster was above it.
  for (PcaItem c : cut) {
    const int32_t parent = IsFaceItem(c) ? -1 : tree.nodes[size_t(c)].parent;
    if (parent >= 0) {
      EXPECT_GT(std::sqrt(tree.nodes[size_t(parent)].eigenvalues[0]), threshold);
    }
  }
}

TEST(PcaTree, StopCriteria) {
  const IndexedMesh m = test::Sphere(4);  // 2048 faces
  {
    PcaPartitionParams p;
    p.minFaces = 20;
    PcaTree tree;
    ASSERT_TRUE(BuildPcaTree(m, p, tree).ok());
    ExpectSoundTree(m, tree);
    for (int32_t i = 0; i < int32_t(tree.nodes.size()); ++i) {
      if (tree.isLeaf(i)) {
        EXPECT_LE(tree.nodes[size_t(i)].faceCount, 20u);
      } else {
        EXPECT_GT(tree.nodes[size_t(i)].faceCount, 20u);
      }
    }
  }
  {
    PcaPartitionParams p;
    p.maxDepth = 4;
    PcaTree tree;
    ASSERT_TRUE(BuildPcaTree(m, p, tree).ok());
    EXPECT_EQ(tree.maxDepth, 4);
    EXPECT_EQ(tree.leafClusterCount(), 16);
  }
  {
    PcaPartitionParams p;
    p.maxErrorRms = 0.02;
    PcaTree tree;
    ASSERT_TRUE(BuildPcaTree(m, p, tree).ok());
    for (int32_t i = 0; i < int32_t(tree.nodes.size()); ++i)
      if (!tree.isLeaf(i)) {
        EXPECT_GT(std::sqrt(tree.nodes[size_t(i)].eigenvalues[0]), 0.02);
      }
    // Leaf clusters have their exact cone: it holds every normal.
  }
  {
    PcaPartitionParams p;
    p.targetClusters = 50;
    PcaTree tree;
    ASSERT_TRUE(BuildPcaTree(m, p, tree).ok());
    EXPECT_EQ(tree.leafClusterCount(), 50);
    EXPECT_EQ(CutByCount(tree, 1000).size(), 50u);  // no more splits than were built
  }
}

TEST(PcaTree, DegenerateAndAwkwardInput) {
  // Duplicate faces and zero-area faces have no split plane: they still split into connected
  // halves, down to single faces.
  IndexedMesh m = test::Grid(3);
  m.faces.push_back(m.faces[0]);             // a duplicate (non-manifold edges)
  m.positions.emplace_back(0.5f, 0.f, 0.f);  // a zero-area sliver on the border
  m.faces.push_back({0, 1, uint32_t(m.positions.size() - 1)});
  PcaTree tree;
  ASSERT_TRUE(BuildPcaTree(m, PcaPartitionParams(), tree).ok());
  ExpectSoundTree(m, tree);
  EXPECT_EQ(tree.leafClusterCount(), int(m.faces.size()));
  // A one-face mesh: the root alone.
  IndexedMesh one;
  one.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  one.faces = {{0, 1, 2}};
  ASSERT_TRUE(BuildPcaTree(one, PcaPartitionParams(), tree).ok());
  EXPECT_EQ(tree.nodes.size(), 1u);
  EXPECT_EQ(CutByCount(tree, 5).size(), 1u);
  // The repository's zero-area mesh.
  CMesh z;
  ASSERT_EQ(LoadPly(z, std::string(CONELOD_SOURCE_DIR) + "/test_meshes/zero_area_faces.ply"), "");
  const IndexedMesh zm = ToIndexedMesh(z);
  ASSERT_TRUE(BuildPcaTree(zm, PcaPartitionParams(), tree).ok());
  ExpectSoundTree(zm, tree);
}

TEST(PcaTree, BadInputAndBadParameters) {
  PcaTree tree;
  IndexedMesh empty;
  empty.positions = {{0, 0, 0}};
  Status s = BuildPcaTree(empty, PcaPartitionParams(), tree);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message.find("no faces"), std::string::npos);
  IndexedMesh nan = test::Cube();
  nan.positions[3][1] = std::numeric_limits<float>::quiet_NaN();
  s = BuildPcaTree(nan, PcaPartitionParams(), tree);
  EXPECT_NE(s.message.find("NaN"), std::string::npos);
  EXPECT_TRUE(tree.empty());
  IndexedMesh flat;
  flat.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  flat.faces = {{0, 1, 2}};
  EXPECT_FALSE(BuildPcaTree(flat, PcaPartitionParams(), tree).ok());
  PcaPartitionParams p;
  p.minFaces = 0;
  EXPECT_NE(BuildPcaTree(test::Cube(), p, tree).message.find("MinFaces"), std::string::npos);
  p = PcaPartitionParams();
  p.targetClusters = -1;
  EXPECT_FALSE(BuildPcaTree(test::Cube(), p, tree).ok());
  p = PcaPartitionParams();
  p.maxErrorRms = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(BuildPcaTree(test::Cube(), p, tree).ok());
}

TEST(PcaTree, ProgressRisesAndCancellationLeavesNothing) {
  const IndexedMesh bunny = LoadReal("stanford_bunny_bun_zipper.ply");
  std::vector<int> seen;
  PcaTree tree;
  ASSERT_TRUE(BuildPcaTree(bunny, PcaPartitionParams(), tree, [&](int p, const char*) {
                seen.push_back(p);
                return true;
              }).ok());
  ASSERT_GE(seen.size(), 4u);
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
  EXPECT_EQ(seen.back(), 100);
  int calls = 0;
  const Status s = BuildPcaTree(bunny, PcaPartitionParams(), tree, [&](int, const char*) { return ++calls < 3; });
  EXPECT_EQ(s.code, Status::Code::Cancelled);
  EXPECT_TRUE(tree.empty());
}

TEST(PcaTree, Deterministic) {
  const IndexedMesh m = LoadReal("blobby_3cc.ply");
  PcaTree a, b;
  ASSERT_TRUE(BuildPcaTree(m, PcaPartitionParams(), a).ok());
  ASSERT_TRUE(BuildPcaTree(m, PcaPartitionParams(), b).ok());
  EXPECT_EQ(a.faceOrder, b.faceOrder);
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  for (size_t i = 0; i < a.nodes.size(); ++i) EXPECT_EQ(a.nodes[i].eigenvalues, b.nodes[i].eigenvalues);
}

TEST(PcaTree, TreeDoesNotDependOnTheModelsScale) {
  // Scaling by a power of two changes no ratio of lengths, areas or moments: the tree (every
  // split) must be the same at every scale, and its figures scale exactly.
  const IndexedMesh sphere = test::Sphere(5);  // 8192 faces
  PcaTree ref;
  ASSERT_TRUE(BuildPcaTree(sphere, PcaPartitionParams(), ref).ok());
  for (int k : {-40, -34, -20, 20, 34, 40}) {
    IndexedMesh scaled = sphere;
    for (auto& p : scaled.positions) p *= std::ldexp(1.0f, k);
    PcaTree t;
    ASSERT_TRUE(BuildPcaTree(scaled, PcaPartitionParams(), t).ok()) << "2^" << k;
    EXPECT_EQ(t.faceOrder, ref.faceOrder) << "2^" << k;
    ASSERT_EQ(t.nodes.size(), ref.nodes.size()) << "2^" << k;
    int bad = 0;
    for (size_t i = 0; i < ref.nodes.size(); ++i) {
      const PcaNode& a = ref.nodes[i];
      const PcaNode& b = t.nodes[i];
      const bool same = a.child[0] == b.child[0] && a.child[1] == b.child[1] && a.firstFace == b.firstFace &&
                        a.faceCount == b.faceCount && b.area == std::ldexp(a.area, 2 * k) &&
                        b.eigenvalues[0] == std::ldexp(a.eigenvalues[0], 2 * k) &&
                        b.eigenvalues[2] == std::ldexp(a.eigenvalues[2], 2 * k) && b.axis == a.axis;
      if (!same && ++bad <= 3) ADD_FAILURE() << "2^" << k << ": node " << i << " differs";
    }
    EXPECT_EQ(CutByCount(t, 100), CutByCount(ref, 100)) << "2^" << k;
  }
}

TEST(PcaGroups, HierarchyFromNestedCutsFeedsTheCullingCost) {
  const IndexedMesh m = test::Sphere(4);
  PcaTree tree;
  ASSERT_TRUE(BuildPcaTree(m, PcaPartitionParams(), tree).ok());
  GroupHierarchy h;
  ASSERT_TRUE(PcaGroupHierarchy(m, tree, {64, 16, 4}, h).ok());
  ASSERT_EQ(h.levelCount(), 3);
  EXPECT_EQ(h.level(1).groups.size(), 64u);
  EXPECT_EQ(h.level(3).groups.size(), 4u);
  std::vector<vcg::Point3d> normals;
  std::vector<double> areas;
  ComputeFaceNormalsAndAreas(m, normals, areas);
  const FaceAdjacency adj = BuildFaceAdjacency(m);
  for (int l = 1; l <= 3; ++l) {
    const GroupLevel& lv = h.level(l);
    EXPECT_TRUE(GroupsAreEdgeConnected(adj, lv.faceGroup));
    for (size_t f = 0; f < normals.size(); ++f) {
      const Group& g = lv.groups[size_t(lv.faceGroup[f])];
      if (g.cone.cullable()) {
        EXPECT_TRUE(g.cone.contains(normals[f], 1e-7));
      }
      for (uint32_t v : m.faces[f]) EXPECT_LE(vcg::Distance(m.positions[v], g.center), g.radius);
    }
    if (l > 1)  // children of level l are the level l-1 groups inside them
      for (size_t g = 0; g < lv.groups.size(); ++g)
        for (int i = 0; i < lv.groups[g].childCount; ++i) {
          const int child = lv.children[size_t(lv.groups[g].firstChild + i)];
          EXPECT_EQ(h.level(l - 1).groups[size_t(child)].parent, int(g));
        }
  }
  // 64 clusters of a sphere each fit in a narrow cone: culling beats per-face tests.
  CullingCostParams cp;
  cp.views = 200;
  CullingCostResult r;
  ASSERT_TRUE(EvaluateCullingCost(m, h, cp, r).ok());
  EXPECT_LT(r.twoState.mean, 0.8);
  EXPECT_LE(r.rejectedFraction, r.idealFraction);
  // Counts must decrease.
  EXPECT_FALSE(PcaGroupHierarchy(m, tree, {16, 64}, h).ok());
}

}  // namespace
}  // namespace conelod
