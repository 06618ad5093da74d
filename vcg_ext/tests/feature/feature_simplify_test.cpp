// Tests of feature_simplify.h: feature edges and vertex classes on hand-built meshes, the
// extension swap, the collapse rules, and simplification of real CAD meshes.
#include "conelod/feature/feature_simplify.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <thread>

#include "conelod/simplify_bridge.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"
#include "test_util.h"

namespace conelod {
namespace {

using P3 = vcg::Point3d;

bool HasEdge(const std::vector<std::array<uint32_t, 2>>& edges, uint32_t a, uint32_t b) {
  const std::array<uint32_t, 2> e = {std::min(a, b), std::max(a, b)};
  return std::find(edges.begin(), edges.end(), e) != edges.end();
}

bool MeshHasEdge(const IndexedMesh& m, uint32_t a, uint32_t b) {
  for (const auto& t : m.faces)
    for (int k = 0; k < 3; ++k)
      if ((t[k] == a && t[(k + 1) % 3] == b) || (t[k] == b && t[(k + 1) % 3] == a)) return true;
  return false;
}

IndexedMesh Load(const std::string& name) {
  CMesh m;
  EXPECT_EQ(LoadPly(m, test::MeshPath(name)), "");
  return ToIndexedMesh(m);
}

// The project's own bad-input meshes (test_meshes/ in the repository).
IndexedMesh LoadOwn(const std::string& name) {
  CMesh m;
  EXPECT_EQ(LoadPly(m, std::string(CONELOD_SOURCE_DIR) + "/test_meshes/" + name), "");
  return ToIndexedMesh(m);
}

// A tent-shaped strip along x: rows T (y = 1), R (the ridge, y = 0), B (y = -1), z = -h |y|, so
// the ridge's dihedral angle is 180 - 2 atan(h) degrees (146.6 for h = 0.3, 90 for h = 1).
// Vertex ids: T_k = k, R_k = n + 1 + k, B_k = 2 (n + 1) + k. With `chipped`, the ridge between
// R_2 and R_3 is cut by a small chamfer, as a mesh generator leaves a feature line with a gap
// (the paper's Fig. 4a): two extra vertices G_t, G_b next to the ridge on either slope, and the
// chamfer faces (R_2, G_b, G_t), (G_b, R_3, G_t) whose shared edge G_b G_t crosses the ridge.
struct Strip {
  IndexedMesh mesh;
  int n;
  uint32_t T(int k) const { return uint32_t(k); }
  uint32_t R(int k) const { return uint32_t(n + 1 + k); }
  uint32_t B(int k) const { return uint32_t(2 * (n + 1) + k); }
  uint32_t Gt() const { return uint32_t(3 * (n + 1)); }
  uint32_t Gb() const { return uint32_t(3 * (n + 1) + 1); }
};

Strip RidgeStrip(int n, double h, bool chipped) {
  Strip s;
  s.n = n;
  for (int row = 0; row < 3; ++row)
    for (int k = 0; k <= n; ++k) {
      const double y = 1.0 - row;
      s.mesh.positions.emplace_back(float(k), float(y), float(-h * std::abs(y)));
    }
  const float delta = 0.1f;
  s.mesh.positions.emplace_back(2.5f, delta, float(-h * delta));   // G_t
  s.mesh.positions.emplace_back(2.5f, -delta, float(-h * delta));  // G_b
  for (int k = 0; k < n; ++k) {
    if (chipped && k == 2) {
      s.mesh.faces.push_back({s.R(2), s.Gt(), s.T(2)});
      s.mesh.faces.push_back({s.Gt(), s.T(3), s.T(2)});
      s.mesh.faces.push_back({s.Gt(), s.R(3), s.T(3)});
      s.mesh.faces.push_back({s.B(2), s.B(3), s.Gb()});
      s.mesh.faces.push_back({s.B(3), s.R(3), s.Gb()});
      s.mesh.faces.push_back({s.B(2), s.Gb(), s.R(2)});
      s.mesh.faces.push_back({s.R(2), s.Gb(), s.Gt()});
      s.mesh.faces.push_back({s.Gb(), s.R(3), s.Gt()});
      continue;
    }
    // Top quad (R_k, R_k+1, T_k+1, T_k) and bottom quad (B_k, B_k+1, R_k+1, R_k), counter-clockwise from +z.
    s.mesh.faces.push_back({s.R(k), s.R(k + 1), s.T(k + 1)});
    s.mesh.faces.push_back({s.R(k), s.T(k + 1), s.T(k)});
    s.mesh.faces.push_back({s.B(k), s.B(k + 1), s.R(k + 1)});
    s.mesh.faces.push_back({s.B(k), s.R(k + 1), s.R(k)});
  }
  return s;
}

TEST(DihedralAngle, FlatCubeEdgeAndKnife) {
  EXPECT_NEAR(DihedralAngleDeg(P3(0, 0, 1), P3(0, 0, 1)), 180.0, 1e-9);  // coplanar faces
  EXPECT_NEAR(DihedralAngleDeg(P3(0, 0, 1), P3(1, 0, 0)), 90.0, 1e-9);   // cube edge
  EXPECT_NEAR(DihedralAngleDeg(P3(0, 0, 1), P3(0, 0, -1)), 0.0, 1e-9);   // folded flat (knife)
  EXPECT_NEAR(DihedralAngleDeg(P3(0, 0, 1), P3(0, std::sin(0.5), std::cos(0.5))), 180.0 - 0.5 * 180 / M_PI, 1e-9);
}

TEST(DetectFeatures, CubeHasTwelveFeatureEdgesAndEightCorners) {
  FeatureSimplifyParams p;  // A_t = 135: the cube's 90-degree edges are features, the diagonals (180) not
  FeatureInfo info;
  ASSERT_TRUE(DetectFeatures(test::Cube(), p, info).ok());
  EXPECT_EQ(info.featureEdges.size(), 12u);
  EXPECT_EQ(info.dihedralEdges, 12u);
  EXPECT_EQ(info.borderEdges, 0u);
  // Every triangle of the cube has two sides of its square as feature edges, its diagonal not:
  // 12 triangles x 2 = 12 edges x 2 triangles.
  for (const auto& t : info.mesh.faces) {
    int featureSides = 0;
    for (int k = 0; k < 3; ++k) featureSides += HasEdge(info.featureEdges, t[k], t[(k + 1) % 3]) ? 1 : 0;
    EXPECT_EQ(featureSides, 2);
  }
  EXPECT_EQ(info.count(VertexClass::Feature), 8u);  // three feature edges meet at each corner
  EXPECT_EQ(info.count(VertexClass::FeatureLine), 0u);
  EXPECT_EQ(info.count(VertexClass::Smooth), 0u);
}

TEST(DetectFeatures, ThresholdBelowTheCubeAngleFindsNothing) {
  FeatureSimplifyParams p;
  p.featureAngleDeg = 89;  // 90-degree edges are not <= 89
  FeatureInfo info;
  ASSERT_TRUE(DetectFeatures(test::Cube(), p, info).ok());
  EXPECT_TRUE(info.featureEdges.empty());
  EXPECT_EQ(info.count(VertexClass::Smooth), 8u);
  // Discrete Gaussian curvature of a cube corner: angle defect pi/2 over a third of the incident area.
  for (size_t v = 0; v < 8; ++v) EXPECT_GT(info.curvatureK[v], 0.0);
}

TEST(DetectFeatures, CurvatureMakesFeatureVertices) {
  // Without feature edges, |K| D^2 >= K_t marks the cube's corners as feature vertices.
  FeatureSimplifyParams p;
  p.featureAngleDeg = 89;
  p.featureCurvature = 1.0;
  FeatureInfo info;
  ASSERT_TRUE(DetectFeatures(test::Cube(), p, info).ok());
  EXPECT_EQ(info.count(VertexClass::Feature), 8u);
}

TEST(DetectFeatures, RidgeStripClasses) {
  const Strip s = RidgeStrip(5, 0.3, false);
  FeatureSimplifyParams p;
  p.featureAngleDeg = 150;  // the ridge is 146.6 degrees
  FeatureInfo info;
  ASSERT_TRUE(DetectFeatures(s.mesh, p, info).ok());
  for (int k = 0; k < 5; ++k) EXPECT_TRUE(HasEdge(info.featureEdges, s.R(k), s.R(k + 1))) << k;
  EXPECT_EQ(info.dihedralEdges, 5u);
  EXPECT_EQ(info.borderEdges, 14u);  // 5 + 5 along the rows, 2 + 2 across the ends
  for (int k = 1; k < 5; ++k) {
    EXPECT_EQ(info.vertexClass[s.R(k)], VertexClass::FeatureLine) << k;
    EXPECT_NEAR(info.curvatureM[s.R(k)], 0.0, 1e-6);                     // a straight line: b = 0
    EXPECT_EQ(info.vertexClass[s.T(k)], VertexClass::FeatureLine) << k;  // on the border
  }
  // Ridge ends meet the border: three feature edges.
  EXPECT_EQ(info.vertexClass[s.R(0)], VertexClass::Feature);
  EXPECT_EQ(info.vertexClass[s.R(5)], VertexClass::Feature);
}

TEST(ExtendFeatureLines, SwapClosesTheGap) {
  // Ridge 90 degrees, A_t = 100; the chamfer edges are 134 and 157 degrees: not features, so the
  // line R0..R2 ends at R2 and R3..R5 at R3. Swapping G_b G_t (opposite R2) gives R2 R3, whose
  // faces lie on the two slopes again: 90 degrees, a feature edge, and the line is whole.
  const Strip s = RidgeStrip(5, 1.0, true);
  ASSERT_FALSE(MeshHasEdge(s.mesh, s.R(2), s.R(3)));
  FeatureSimplifyParams p;
  p.featureAngleDeg = 100;
  p.extendFeatureLines = false;
  FeatureInfo plain;
  ASSERT_TRUE(DetectFeatures(s.mesh, p, plain).ok());
  EXPECT_EQ(plain.vertexClass[s.R(2)], VertexClass::Feature);  // line ends: one feature edge
  EXPECT_EQ(plain.vertexClass[s.R(3)], VertexClass::Feature);
  EXPECT_EQ(plain.dihedralEdges, 4u);

  p.extendFeatureLines = true;
  FeatureInfo info;
  ASSERT_TRUE(DetectFeatures(s.mesh, p, info).ok());
  EXPECT_EQ(info.swapEdges, 1u);
  EXPECT_EQ(info.removedBySwaps, 0u);
  EXPECT_TRUE(MeshHasEdge(info.mesh, s.R(2), s.R(3)));
  EXPECT_FALSE(MeshHasEdge(info.mesh, s.Gt(), s.Gb()));
  for (int k = 0; k < 5; ++k) EXPECT_TRUE(HasEdge(info.featureEdges, s.R(k), s.R(k + 1))) << k;
  EXPECT_EQ(info.vertexClass[s.R(2)], VertexClass::FeatureLine);
  EXPECT_EQ(info.vertexClass[s.R(3)], VertexClass::FeatureLine);
  EXPECT_EQ(info.mesh.faces.size(), s.mesh.faces.size());
  // The swapped faces are on the slopes: their normals are those of the two planes z = -|y|.
  std::vector<P3> normals;
  std::vector<double> areas;
  ComputeFaceNormalsAndAreas(info.mesh, normals, areas);
  for (size_t f = 0; f < info.mesh.faces.size(); ++f) {
    const auto& t = info.mesh.faces[f];
    const bool onRidge =
        (t[0] == s.R(2) || t[1] == s.R(2) || t[2] == s.R(2)) && (t[0] == s.R(3) || t[1] == s.R(3) || t[2] == s.R(3));
    if (onRidge) {
      EXPECT_NEAR(std::abs(normals[f][1]), std::sqrt(0.5), 1e-6);
    }
  }
}

TEST(ExtendFeatureLines, NothingToExtendBelowTheRidgeAngle) {
  const Strip s = RidgeStrip(5, 1.0, true);
  FeatureSimplifyParams p;
  p.featureAngleDeg = 85;  // the ridge (90) is not a feature: no line ends, no swap
  FeatureInfo info;
  ASSERT_TRUE(DetectFeatures(s.mesh, p, info).ok());
  EXPECT_EQ(info.dihedralEdges, 0u);
  EXPECT_EQ(info.swapEdges, 0u);
  EXPECT_FALSE(MeshHasEdge(info.mesh, s.R(2), s.R(3)));
}

TEST(CheckFeatureCollapse, FeatureLineVerticesMoveOnlyAlongTheirLine) {
  const Strip s = RidgeStrip(5, 0.3, false);
  FeatureSimplifyParams p;
  p.featureAngleDeg = 150;
  // R2 is on the ridge: collapsing it into T2 (off the line) would leave the line.
  EXPECT_EQ(CheckFeatureCollapse(s.mesh, p, s.R(2), s.T(2)), CollapseRefusal::OffFeatureLine);
  EXPECT_EQ(CheckFeatureCollapse(s.mesh, p, s.R(2), s.B(2)), CollapseRefusal::OffFeatureLine);
  EXPECT_EQ(CheckFeatureCollapse(s.mesh, p, s.R(2), s.R(3)), CollapseRefusal::None);
  EXPECT_EQ(CheckFeatureCollapse(s.mesh, p, s.R(2), s.R(1)), CollapseRefusal::None);
  // Border vertices move along the border only; corners never move.
  EXPECT_EQ(CheckFeatureCollapse(s.mesh, p, s.T(2), s.R(2)), CollapseRefusal::OffFeatureLine);
  EXPECT_EQ(CheckFeatureCollapse(s.mesh, p, s.T(2), s.T(3)), CollapseRefusal::None);
  EXPECT_EQ(CheckFeatureCollapse(s.mesh, p, s.R(0), s.R(1)), CollapseRefusal::LockedVertex);
  EXPECT_EQ(CheckFeatureCollapse(s.mesh, p, s.R(2), s.R(4)), CollapseRefusal::NotAnEdge);
}

TEST(CheckFeatureCollapse, RefusesFlipsDuplicatesAndFeatureLoops) {
  // A flat fan around c = 0 whose ring is not convex: c may collapse into p3 but not into p2.
  IndexedMesh fan;
  fan.positions = {{0, 0, 0}, {1, 0, 0}, {0.3f, 0.3f, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  for (uint32_t i = 0; i < 5; ++i) fan.faces.push_back({0, 1 + i, 1 + (i + 1) % 5});
  FeatureSimplifyParams p;
  EXPECT_EQ(CheckFeatureCollapse(fan, p, 0, 3), CollapseRefusal::FlipsFace);
  EXPECT_EQ(CheckFeatureCollapse(fan, p, 0, 1), CollapseRefusal::FlipsFace);
  EXPECT_EQ(CheckFeatureCollapse(fan, p, 0, 4), CollapseRefusal::None);

  // A tetrahedron without feature edges (A_t below its 70.5 degrees): any collapse would fold it.
  IndexedMesh tet;
  tet.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tet.faces = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
  p.featureAngleDeg = 10;
  EXPECT_EQ(CheckFeatureCollapse(tet, p, 0, 1), CollapseRefusal::Topology);

  // A lone triangle: its border is a loop of three feature edges; a collapse would merge two.
  IndexedMesh tri;
  tri.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  tri.faces = {{0, 1, 2}};
  EXPECT_EQ(CheckFeatureCollapse(tri, p, 0, 1), CollapseRefusal::MergesFeatures);
}

TEST(FeatureSimplify, CubeCannotBeSimplified) {
  FeatureSimplifyParams p;
  p.targetFaceCount = 1;
  FeatureSimplifyResult r;
  ASSERT_TRUE(FeatureSimplify(test::Cube(), p, r).ok());
  EXPECT_EQ(r.facesOut, 12u);
  EXPECT_FALSE(r.targetReached);
  EXPECT_EQ(r.featureEdges.size(), 12u);
}

TEST(FeatureSimplify, FlatGridKeepsItsOutline) {
  // A flat 8x8 grid: every interior vertex can go (d = 0); the border is a straight feature line
  // whose corners stay. The result is the square, still covering exactly the same area.
  const IndexedMesh grid = test::Grid(8);
  FeatureSimplifyParams p;
  p.targetFaceCount = 2;
  FeatureSimplifyResult r;
  ASSERT_TRUE(FeatureSimplify(grid, p, r).ok());
  EXPECT_EQ(r.facesOut, 2u);
  EXPECT_TRUE(r.targetReached);
  ASSERT_EQ(r.mesh.positions.size(), 4u);
  std::vector<P3> normals;
  std::vector<double> areas;
  ComputeFaceNormalsAndAreas(r.mesh, normals, areas);
  EXPECT_NEAR(areas[0] + areas[1], 64.0, 1e-9);
  for (const auto& n : normals) EXPECT_NEAR(n[2], 1.0, 1e-12);
  // The four corners: on the border line (two feature edges each), never cut off.
  for (size_t v = 0; v < 4; ++v) {
    EXPECT_EQ(r.vertexClass[v], VertexClass::FeatureLine);
    EXPECT_TRUE(r.mesh.positions[v][0] == 0 || r.mesh.positions[v][0] == 8);
    EXPECT_TRUE(r.mesh.positions[v][1] == 0 || r.mesh.positions[v][1] == 8);
  }
}

TEST(FeatureSimplify, SphereStaysAClosedManifold) {
  const IndexedMesh sphere = test::Sphere(4);  // 2048 faces
  for (bool grow : {true, false}) {
    FeatureSimplifyParams p;
    p.targetFaceCount = 200;
    p.growErrorBound = grow;
    FeatureSimplifyResult r;
    ASSERT_TRUE(FeatureSimplify(sphere, p, r).ok());
    EXPECT_TRUE(r.targetReached);
    EXPECT_LE(r.facesOut, 200u);
    EXPECT_GE(r.facesOut, 198u);
    // Closed 2-manifold of genus 0: every edge has two faces, V - E + F = 2.
    std::map<std::pair<uint32_t, uint32_t>, int> edges;
    for (const auto& t : r.mesh.faces)
      for (int k = 0; k < 3; ++k) ++edges[{std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}];
    for (const auto& e : edges) EXPECT_EQ(e.second, 2);
    EXPECT_EQ(int(r.mesh.positions.size()) - int(edges.size()) + int(r.mesh.faces.size()), 2);
    // Vertices never move: every output vertex is an input vertex.
    for (size_t v = 0; v < r.mesh.positions.size(); ++v)
      EXPECT_EQ(r.mesh.positions[v], sphere.positions[r.inputVertex[v]]);
  }
}

// Brute force: the largest distance of an input vertex to the output surface, through the
// point-triangle distance of vcg (independent of the core's code).
double WorstInputToOutput(const IndexedMesh& in, const IndexedMesh& out) {
  double worst = 0;
  for (const auto& q : in.positions) {
    const P3 x = P3::Construct(q);
    double best = 1e300;
    for (const auto& t : out.faces) {
      const P3 a = P3::Construct(out.positions[t[0]]), b = P3::Construct(out.positions[t[1]]),
               c = P3::Construct(out.positions[t[2]]);
      vcg::Point3d closest;
      double dist = 0;
      vcg::Triangle3<double> tri(a, b, c);
      vcg::TrianglePointDistance(tri, x, dist, closest);
      best = std::min(best, dist);
    }
    worst = std::max(worst, best);
  }
  return worst;
}

TEST(FeatureSimplify, ErrorBoundHoldsForEveryInputVertex) {
  const IndexedMesh fandisk = Load("fandisk.ply");
  const double diag = BoundingBoxDiagonal(fandisk);
  FeatureSimplifyParams p;
  p.maxErrorDistance = 0.002 * diag;
  FeatureSimplifyResult r;
  ASSERT_TRUE(FeatureSimplify(fandisk, p, r).ok());
  EXPECT_LT(r.facesOut, fandisk.faceCount() / 3);
  const double worst = WorstInputToOutput(fandisk, r.mesh);
  EXPECT_LE(worst, p.maxErrorDistance * (1 + 1e-6));
  EXPECT_GT(worst, 0.0);
}

// The default mode (a target under a growing bound): every input vertex ends within the final
// bound, whatever order the vertices waiting for a larger bound were admitted in (a vertex that
// absorbed a collapse while waiting keeps waiting with its old error and is measured again when
// the bound reaches it).
TEST(FeatureSimplify, GrowingBoundHoldsForEveryInputVertex) {
  for (const char* name : {"fandisk.ply", "mech_holes_shark.ply"}) {
    const IndexedMesh in = Load(name);
    FeatureSimplifyParams p;
    p.targetFaceCount = in.faceCount() / 10;
    FeatureSimplifyResult r;
    ASSERT_TRUE(FeatureSimplify(in, p, r).ok()) << name;
    EXPECT_TRUE(r.targetReached) << name;
    EXPECT_GT(r.finalErrorBound, 0.0) << name;
    EXPECT_LE(r.maxTrackedError, r.finalErrorBound) << name;
    const double worst = WorstInputToOutput(in, r.mesh);
    EXPECT_LE(worst, r.finalErrorBound * (1 + 1e-6)) << name;
    EXPECT_GT(worst, 0.25 * r.finalErrorBound) << name;  // the bound is not loose either
  }
}

// r is ref to the last bit: the same collapses, vertices, faces, final bound and tracked error.
void ExpectSameOutput(const FeatureSimplifyResult& r, const FeatureSimplifyResult& ref, const std::string& what) {
  EXPECT_EQ(r.collapses, ref.collapses) << what;
  EXPECT_EQ(r.inputVertex, ref.inputVertex) << what;
  EXPECT_EQ(r.mesh.faces, ref.mesh.faces) << what;
  EXPECT_EQ(r.finalErrorBound, ref.finalErrorBound) << what;
  EXPECT_EQ(r.maxTrackedError, ref.maxTrackedError) << what;
}

// The first pass evaluated ahead (in memory order, on any number of threads) gives the output of
// evaluating every vertex in the queue's order: an evaluation made ahead is used only while no
// collapse has come near its vertex. Fandisk's flat parts and the whole grid collapse during the
// first pass (d = 0), so the invalidation is exercised; the sphere has no feature lines at all.
TEST(FeatureSimplify, FirstPassAheadChangesNothing) {
  std::vector<std::pair<std::string, IndexedMesh>> meshes = {{"fandisk.ply", Load("fandisk.ply")},
                                                             {"mech_holes_shark.ply", Load("mech_holes_shark.ply")},
                                                             {"sphere", test::Sphere(4)},
                                                             {"grid", test::Grid(40)}};
  for (const auto& named : meshes) {
    const std::string& name = named.first;
    const IndexedMesh& in = named.second;
    FeatureSimplifyParams p;
    p.targetFaceCount = in.faceCount() / 8;
    p.firstPassAhead = false;
    FeatureSimplifyResult ref;
    ASSERT_TRUE(FeatureSimplify(in, p, ref).ok()) << name;
    ASSERT_GT(ref.collapses, 0u) << name;
    p.firstPassAhead = true;
    for (unsigned threads : {1u, 2u, 3u}) {
      p.threads = threads;
      FeatureSimplifyResult r;
      ASSERT_TRUE(FeatureSimplify(in, p, r).ok()) << name;
      ExpectSameOutput(r, ref, name + " threads " + std::to_string(threads));
    }
  }
}

// Simplified in parts (2 or 8 here, forced by a small facesPerPart): the parts' lanes run on any
// number of threads and give the same output (they share nothing but what none of them changes),
// with the first pass ahead or without; every input vertex still ends within the final bound, the
// target is reached, and the result is about as good as in one piece.
TEST(FeatureSimplify, InPartsTheSameForAnyThreadCount) {
  std::vector<std::pair<std::string, IndexedMesh>> meshes = {{"fandisk.ply", Load("fandisk.ply")},
                                                             {"mech_holes_shark.ply", Load("mech_holes_shark.ply")},
                                                             {"sphere", test::Sphere(5)}};
  for (const auto& named : meshes) {
    const std::string& name = named.first;
    const IndexedMesh& in = named.second;
    FeatureSimplifyParams p;
    p.targetFaceCount = in.faceCount() / 10;
    FeatureSimplifyResult whole;
    ASSERT_TRUE(FeatureSimplify(in, p, whole).ok()) << name;
    ASSERT_EQ(whole.parts, 1u) << name;
    for (size_t perPart : {in.faceCount() / 3, in.faceCount() / 16}) {
      p.facesPerPart = perPart;
      p.threads = 1;
      p.firstPassAhead = false;
      FeatureSimplifyResult ref;
      ASSERT_TRUE(FeatureSimplify(in, p, ref).ok()) << name;
      EXPECT_EQ(ref.parts, perPart == in.faceCount() / 3 ? 2u : 8u) << name;
      EXPECT_TRUE(ref.targetReached) << name;
      EXPECT_GE(ref.facesOut + ref.parts, p.targetFaceCount) << name;  // each lane stops within a collapse
      const double worst = WorstInputToOutput(in, ref.mesh);
      EXPECT_LE(ref.maxTrackedError, ref.finalErrorBound) << name;
      EXPECT_LE(worst, ref.finalErrorBound * (1 + 1e-6)) << name;
      EXPECT_LE(ref.finalErrorBound, whole.finalErrorBound * 1.25 * (1 + 1e-9)) << name;
      p.firstPassAhead = true;
      for (unsigned threads : {2u, 3u}) {
        p.threads = threads;
        FeatureSimplifyResult r;
        ASSERT_TRUE(FeatureSimplify(in, p, r).ok()) << name;
        ExpectSameOutput(r, ref, name + " threads " + std::to_string(threads) + " parts " + std::to_string(r.parts));
      }
    }
  }
}

TEST(FeatureSimplify, FandiskKeepsItsFeatureLines) {
  const IndexedMesh fandisk = Load("fandisk.ply");
  FeatureSimplifyParams p;
  p.targetFaceCount = fandisk.faceCount() / 10;
  FeatureInfo in;
  ASSERT_TRUE(DetectFeatures(fandisk, p, in).ok());
  FeatureSimplifyResult r;
  ASSERT_TRUE(FeatureSimplify(fandisk, p, r).ok());
  EXPECT_TRUE(r.targetReached);
  // Feature vertices are never removed.
  std::set<uint32_t> kept(r.inputVertex.begin(), r.inputVertex.end());
  size_t corners = 0;
  for (uint32_t v = 0; v < in.vertexClass.size(); ++v)
    if (in.vertexClass[v] == VertexClass::Feature) {
      ++corners;
      EXPECT_TRUE(kept.count(v)) << v;
    }
  EXPECT_EQ(corners, r.featureVertices);
  // Every output feature edge joins two vertices of the input's feature lines.
  for (const auto& e : r.featureEdges)
    for (uint32_t v : e) EXPECT_NE(in.vertexClass[r.inputVertex[v]], VertexClass::Smooth);
  // Detected afresh on the output, the feature lines cover the input's.
  FeatureLineAgreement agree;
  ASSERT_TRUE(
      CompareFeatureLines(fandisk, r.mesh, p.featureAngleDeg, 0.005 * BoundingBoxDiagonal(fandisk), agree).ok());
  EXPECT_GT(agree.referenceLengthCovered, 0.97 * agree.referenceLength);
  EXPECT_GT(agree.simplifiedOnReference, 0.95 * agree.simplifiedEdges);
}

TEST(CompareFeatureLines, MeshAgainstItself) {
  const IndexedMesh fandisk = Load("fandisk.ply");
  FeatureLineAgreement a;
  ASSERT_TRUE(CompareFeatureLines(fandisk, fandisk, 135, 1e-6, a).ok());
  EXPECT_EQ(a.simplifiedOnReference, a.simplifiedEdges);
  EXPECT_EQ(a.referenceEdges, a.simplifiedEdges);
  EXPECT_NEAR(a.referenceLengthCovered, a.referenceLength, 1e-9);
  EXPECT_GT(a.referenceEdges, 500u);
}

TEST(FeatureSimplify, BadInputAndParameters) {
  FeatureSimplifyParams p;
  p.targetFaceCount = 10;
  FeatureSimplifyResult r;
  IndexedMesh empty;
  empty.positions = {{0, 0, 0}};
  Status s = FeatureSimplify(empty, p, r);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message.find("no faces"), std::string::npos);

  IndexedMesh nan = test::Cube();
  nan.positions[3][1] = std::nanf("");
  s = FeatureSimplify(nan, p, r);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message.find("NaN"), std::string::npos);
  EXPECT_TRUE(r.mesh.faces.empty());

  FeatureSimplifyParams none;  // no stop criterion
  s = FeatureSimplify(test::Cube(), none, r);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message.find("TargetFaceNum"), std::string::npos);

  FeatureSimplifyParams badAngle = p;
  badAngle.featureAngleDeg = 200;
  EXPECT_FALSE(FeatureSimplify(test::Cube(), badAngle, r).ok());
}

TEST(FeatureSimplify, AwkwardInputsWork) {
  // Zero-area faces (one with a repeated vertex) and an unreferenced vertex.
  const IndexedMesh zero = LoadOwn("zero_area_faces.ply");
  FeatureSimplifyParams p;
  p.targetFaceCount = 1;
  FeatureSimplifyResult r;
  ASSERT_TRUE(FeatureSimplify(zero, p, r).ok());
  EXPECT_LE(r.facesOut, zero.faceCount());
  // 70 non-manifold edges and duplicate faces: their vertices are locked, the rest simplifies.
  const IndexedMesh res4 = Load("stanford_bunny_bun_zipper_res4.ply");
  p.targetFaceCount = res4.faceCount() / 2;
  ASSERT_TRUE(FeatureSimplify(res4, p, r).ok());
  EXPECT_LT(r.facesOut, res4.faceCount());
  // 122 components.
  const IndexedMesh boeing = Load("boeing.ply");
  p.targetFaceCount = boeing.faceCount() / 2;
  ASSERT_TRUE(FeatureSimplify(boeing, p, r).ok());
  EXPECT_LT(r.facesOut, boeing.faceCount());
}

TEST(FeatureSimplify, CancelLeavesNoResult) {
  const IndexedMesh sphere = test::Sphere(5);
  FeatureSimplifyParams p;
  p.targetFaceCount = 100;
  FeatureSimplifyResult r;
  int calls = 0;
  const Status s = FeatureSimplify(sphere, p, r, [&](int, const char*) { return ++calls < 3; });
  EXPECT_EQ(s.code, Status::Code::Cancelled);
  EXPECT_TRUE(r.mesh.faces.empty());
  EXPECT_EQ(r.facesOut, 0u);
}

// The first pass runs on several threads: progress is reported from the calling thread only, and
// cancelling there (at its first report) stops it with no result.
// So do the parts (here 8, on 3 threads); cancelling at a report in the middle stops them too.
TEST(FeatureSimplify, FirstPassAheadReportsOnTheCallingThread) {
  const IndexedMesh sphere = test::Sphere(5);  // 4098 vertices: several chunks per thread
  for (size_t perPart : {size_t(0), size_t(1000)}) {
    FeatureSimplifyParams p;
    p.targetFaceCount = 100;
    p.threads = 3;
    p.facesPerPart = perPart;
    const std::thread::id caller = std::this_thread::get_id();
    int calls = 0, elsewhere = 0;
    FeatureSimplifyResult r;
    ASSERT_TRUE(FeatureSimplify(sphere, p, r, [&](int, const char*) {
                  ++calls;
                  if (std::this_thread::get_id() != caller) ++elsewhere;
                  return true;
                }).ok());
    EXPECT_EQ(r.parts, perPart ? 8u : 1u);
    EXPECT_GT(calls, 1);
    EXPECT_EQ(elsewhere, 0);
    // How many reports a run makes depends on how the threads share the chunks (the calling
    // thread reports after each of its own): a run cancelled at report k is cancelled if it made
    // k reports, and complete if it made fewer. Reports 1 and 2 (feature detection, then the
    // simplification's first or last) come in every run.
    for (int stopAt : {1, 2, calls / 2}) {
      FeatureSimplifyResult cancelled;
      int seen = 0;
      const Status s = FeatureSimplify(sphere, p, cancelled, [&](int, const char*) { return ++seen < stopAt; });
      if (seen >= stopAt) {
        EXPECT_EQ(s.code, Status::Code::Cancelled) << "parts " << r.parts << " stop at report " << stopAt;
        EXPECT_TRUE(cancelled.mesh.faces.empty());
        EXPECT_EQ(seen, stopAt) << "no report after the cancel";
      } else {
        EXPECT_TRUE(s.ok()) << "parts " << r.parts << ": " << seen << " reports, none cancelled";
        EXPECT_GT(stopAt, 2);
      }
    }
  }
}

// Issue 26: each input vertex ends in one output vertex (FeatureSimplifyResult::survivor), and
// MeanSurvivorColours gives each output vertex the colour of the extended quadric of the input
// vertices that ended in it, at its position: the area-weighted squared colour difference between
// each input vertex and its survivor drops against the survivors' own colours; a colour linear in
// position on a flat grid, and a constant colour, stay exact.
TEST(FeatureSimplify, SurvivorsTakeTheMeanColourOfWhatTheyReplaced) {
  const IndexedMesh sphere = test::Sphere(4);
  FeatureSimplifyParams p;
  p.targetFaceCount = sphere.faces.size() / 10;
  FeatureSimplifyResult r;
  ASSERT_TRUE(FeatureSimplify(sphere, p, r).ok());
  ASSERT_TRUE(r.targetReached);
  ASSERT_EQ(r.survivor.size(), sphere.positions.size());
  std::vector<size_t> members(r.inputVertex.size(), 0);
  for (uint32_t s : r.survivor) {
    ASSERT_LT(s, r.inputVertex.size());
    ++members[s];
  }
  for (size_t o = 0; o < r.inputVertex.size(); ++o) EXPECT_EQ(r.survivor[r.inputVertex[o]], o);
  EXPECT_GT(*std::max_element(members.begin(), members.end()), 1u);

  // Input vertex areas (a third of their faces') and a colour that varies from vertex to vertex.
  std::vector<double> area(sphere.positions.size(), 0.0);
  for (const auto& t : sphere.faces) {
    const auto& a = sphere.positions[t[0]];
    const double third = double(((sphere.positions[t[1]] - a) ^ (sphere.positions[t[2]] - a)).Norm()) / 6.0;
    for (uint32_t v : t) area[v] += third;
  }
  auto colour = [&](size_t v) {
    const auto& q = sphere.positions[v];
    return vcg::Color4b((unsigned char)(128 + 120 * q[0]), (unsigned char)((v * 37) % 256),
                        (unsigned char)(128 + 100 * std::sin(9 * q[2])), 255);
  };
  CMesh m;
  AppendIndexedMesh(m, sphere);
  vcg::tri::UpdateBounding<CMesh>::Box(m);
  for (size_t v = 0; v < m.vert.size(); ++v) m.vert[v].C() = colour(v);
  MeanSurvivorColours(m, r);
  double before = 0, after = 0;
  size_t changed = 0;
  for (size_t o = 0; o < r.inputVertex.size(); ++o) {
    changed += m.vert[r.inputVertex[o]].C() != colour(r.inputVertex[o]);
    EXPECT_EQ(m.vert[r.inputVertex[o]].C()[3], 255);
  }
  EXPECT_GT(changed, r.inputVertex.size() / 2);
  for (size_t v = 0; v < r.survivor.size(); ++v) {
    const vcg::Color4b own = colour(r.inputVertex[r.survivor[v]]), mean = m.vert[r.inputVertex[r.survivor[v]]].C();
    for (int k = 0; k < 3; ++k) {
      before += area[v] * std::pow(double(colour(v)[k]) - own[k], 2);
      after += area[v] * std::pow(double(colour(v)[k]) - mean[k], 2);
    }
  }
  EXPECT_LT(after, 0.8 * before) << "area-weighted squared colour difference to the survivor";

  // A constant colour stays exactly that colour; WriteSimplifiedMesh keeps the survivors' colours.
  for (auto& v : m.vert) v.C() = vcg::Color4b(10, 200, 77, 128);
  MeanSurvivorColours(m, r);
  std::vector<size_t> faceOf;
  ToIndexedMesh(m, &faceOf);
  WriteSimplifiedMesh(m, faceOf, r, false);
  ASSERT_EQ(size_t(m.vn), r.inputVertex.size());
  for (const auto& v : m.vert) EXPECT_EQ(v.C(), vcg::Color4b(10, 200, 77, 128));

  // A flat grid whose colour is linear in position: every kept vertex keeps the exact value.
  const IndexedMesh grid = test::Grid(20);
  FeatureSimplifyParams gp;
  gp.targetFaceCount = grid.faces.size() / 8;
  FeatureSimplifyResult gr;
  ASSERT_TRUE(FeatureSimplify(grid, gp, gr).ok());
  CMesh g;
  AppendIndexedMesh(g, grid);
  auto linear = [](const vcg::Point3f& q) {
    return vcg::Color4b((unsigned char)(10 + 3 * q[0] + 5 * q[1]), (unsigned char)(200 - 4 * q[0]),
                        (unsigned char)(30 + 7 * q[1]), 255);
  };
  for (auto& v : g.vert) v.C() = linear(v.P());
  MeanSurvivorColours(g, gr);
  size_t tookOver = 0;
  for (size_t o = 0; o < gr.inputVertex.size(); ++o) {
    const auto& v = g.vert[gr.inputVertex[o]];
    EXPECT_EQ(v.C(), linear(v.P())) << "output vertex " << o;
  }
  for (size_t v = 0; v < gr.survivor.size(); ++v) tookOver += gr.inputVertex[gr.survivor[v]] != v;
  EXPECT_GT(tookOver, grid.positions.size() / 2);
}

// Issue 26: the normals and texture coordinates as the colour above. On a flat grid whose normals
// tilt by +-0.3 from vertex to vertex (a noisy scan's), every kept vertex that took others over gets
// a unit normal tilted less than its own, and texture coordinates linear in position stay exact
// (a kept vertex's own coordinates are right for its unchanged position; the mean gives them back).
// With noise on the coordinates the kept vertices' move towards the linear ones. The grid cut in
// two by a seam (the right half's vertices on x = 0.5 repeated, as the CLI reads a texture seam):
// the seam's kept vertices keep their own coordinates, noise included.
TEST(FeatureSimplify, SurvivorsTakeTheMeanNormalAndTexCoordsAwayFromSeams) {
  const IndexedMesh grid = test::Grid(20);
  FeatureSimplifyParams gp;
  gp.targetFaceCount = grid.faces.size() / 8;
  FeatureSimplifyResult gr;
  ASSERT_TRUE(FeatureSimplify(grid, gp, gr).ok());
  CMesh g;
  AppendIndexedMesh(g, grid);
  vcg::tri::UpdateBounding<CMesh>::Box(g);
  const float step = g.bbox.DimX() / 20;
  auto sign = [&](const vcg::Point3f& q) { return (int(std::lround(q[0] / step + q[1] / step)) % 2) ? 1.0f : -1.0f; };
  auto linearU = [&](const vcg::Point3f& q) { return 0.1f + 0.04f * q[0] / step; };
  auto linearV = [&](const vcg::Point3f& q) { return 0.9f - 0.03f * q[1] / step; };
  for (auto& v : g.vert) {
    v.N() = vcg::Point3f(0.3f * sign(v.P()), 0, 1).Normalize();
    v.T().U() = linearU(v.P());
    v.T().V() = linearV(v.P());
  }
  EXPECT_EQ(MeanSurvivorNormalsAndTexCoords(g, gr, true, true), 0u);
  std::vector<size_t> members(gr.inputVertex.size(), 0);
  for (uint32_t s : gr.survivor) ++members[s];
  size_t tilted = 0, grouped = 0;
  for (size_t o = 0; o < gr.inputVertex.size(); ++o) {
    const auto& v = g.vert[gr.inputVertex[o]];
    EXPECT_NEAR(v.cN().Norm(), 1.0, 1e-5);
    EXPECT_NEAR(v.cT().U(), linearU(v.cP()), 1e-5) << o;
    EXPECT_NEAR(v.cT().V(), linearV(v.cP()), 1e-5) << o;
    if (members[o] < 3) continue;
    ++grouped;
    tilted += std::fabs(v.cN()[0]) < 0.25 * std::fabs(0.3 / std::sqrt(1.09));
  }
  EXPECT_GT(grouped, gr.inputVertex.size() / 4);
  EXPECT_GT(tilted, grouped / 2) << "kept vertices whose normal is nearer the mean (0, 0, 1) than their own";

  // Noise on the coordinates: the kept vertices' come nearer the linear ones; on a seam they stay.
  auto noisy = [&](const vcg::Point3f& q) { return linearU(q) + 0.01f * sign(q); };
  for (auto& v : g.vert) v.T().U() = noisy(v.P());
  MeanSurvivorNormalsAndTexCoords(g, gr, false, true);
  double before = 0, after = 0;
  for (size_t o = 0; o < gr.inputVertex.size(); ++o) {
    if (members[o] < 3) continue;
    const auto& v = g.vert[gr.inputVertex[o]];
    before += std::pow(noisy(v.cP()) - linearU(v.cP()), 2);
    after += std::pow(v.cT().U() - linearU(v.cP()), 2);
  }
  EXPECT_LT(after, 0.25 * before);

  // The seam: the faces right of x = 0.5 take copies of the vertices on it.
  IndexedMesh cut = grid;
  const float mid = 0.5f * (g.bbox.min[0] + g.bbox.max[0]);
  std::vector<uint32_t> copy(cut.positions.size(), UINT32_MAX);
  for (auto& t : cut.faces) {
    const vcg::Point3f c = (cut.positions[t[0]] + cut.positions[t[1]] + cut.positions[t[2]]) / 3.0f;
    if (c[0] < mid) continue;
    for (auto& v : t)
      if (std::fabs(cut.positions[v][0] - mid) < 1e-6f) {
        if (copy[v] == UINT32_MAX) {
          copy[v] = uint32_t(cut.positions.size());
          cut.positions.push_back(cut.positions[v]);
        }
        v = copy[v];
      }
  }
  FeatureSimplifyResult cr;
  ASSERT_TRUE(FeatureSimplify(cut, gp, cr).ok());
  CMesh c;
  AppendIndexedMesh(c, cut);
  for (auto& v : c.vert) {
    v.T().U() = noisy(v.P());
    v.T().V() = linearV(v.P());
  }
  size_t onSeam = 0;
  for (size_t o = 0; o < cr.inputVertex.size(); ++o)
    onSeam += std::fabs(c.vert[cr.inputVertex[o]].cP()[0] - mid) < 1e-6f;
  EXPECT_GT(onSeam, 2u);
  EXPECT_EQ(MeanSurvivorNormalsAndTexCoords(c, cr, false, true), onSeam);
  for (size_t o = 0; o < cr.inputVertex.size(); ++o) {
    const auto& v = c.vert[cr.inputVertex[o]];
    if (std::fabs(v.cP()[0] - mid) < 1e-6f) {
      EXPECT_EQ(v.cT().U(), noisy(v.cP())) << "seam vertex " << o;
    }
  }
}

}  // namespace
}  // namespace conelod
