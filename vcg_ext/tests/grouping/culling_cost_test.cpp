// Tests of culling_cost.h: exact costs on a cube, invariants on a sphere and a real scan.
#include "conelod/grouping/culling_cost.h"

#include <gtest/gtest.h>

#include "conelod/grouping/cone_grouping.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"
#include "test_util.h"

namespace conelod {
namespace {

GroupHierarchy Group(const IndexedMesh& m, ConeGroupingParams p = ConeGroupingParams()) {
  GroupHierarchy h;
  EXPECT_TRUE(BuildConeHierarchy(m, p, h).ok());
  return h;
}

TEST(ViewDirections, UnitAndBalanced) {
  const auto dirs = ViewDirections(1000);
  ASSERT_EQ(dirs.size(), 1000u);
  vcg::Point3d sum(0, 0, 0);
  for (const auto& d : dirs) {
    EXPECT_NEAR(d.Norm(), 1, 1e-12);
    sum += d;
  }
  EXPECT_LT(sum.Norm() / 1000, 1e-3);
}

TEST(CullingCost, CubeWithOneLevelOfSides) {
  // Six single-normal groups of two faces. From any direction not parallel to a face plane, the
  // three sides facing away are rejected with one test each (6 faces of 12 = ideal), the three
  // sides facing the eye are fully front-facing: two-state = (6 group tests + 6 face tests) / 12,
  // three-state = 6 / 12.
  ConeGroupingParams p;
  p.coneThresholdDeg = 10;
  p.thresholdGrowth = 1;
  p.minTopGroups = 1;
  const IndexedMesh cube = test::Cube();
  const GroupHierarchy h = Group(cube, p);
  ASSERT_EQ(h.level(1).groups.size(), 6u);
  CullingCostParams cp;
  cp.views = 1000;  // an even count: no direction of the lattice lies in a face plane
  CullingCostResult r;
  ASSERT_TRUE(EvaluateCullingCost(cube, h, cp, r).ok());
  EXPECT_NEAR(r.twoState.mean, 1.0, 1e-12);
  EXPECT_NEAR(r.threeState.mean, 0.5, 1e-12);
  EXPECT_NEAR(r.rejectedFraction, 0.5, 1e-12);
  EXPECT_NEAR(r.idealFraction, 0.5, 1e-12);
  EXPECT_NEAR(r.frontAcceptedFraction, 0.5, 1e-12);
}

TEST(CullingCost, InvariantsOnASphere) {
  const IndexedMesh sphere = test::Sphere(5);
  const GroupHierarchy h = Group(sphere);
  for (double distance : {0.0, 3.0}) {
    CullingCostParams cp;
    cp.views = 200;
    cp.cameraDistance = distance;
    CullingCostResult r;
    ASSERT_TRUE(EvaluateCullingCost(sphere, h, cp, r).ok());
    EXPECT_LE(r.rejectedFraction, r.idealFraction + 1e-12);  // never culls a visible face
    EXPECT_LE(r.threeState.mean, r.twoState.mean);           // the third state only saves tests
    EXPECT_LE(r.twoState.min, r.twoState.mean);
    EXPECT_GE(r.twoState.max, r.twoState.mean);
    EXPECT_GT(r.rejectedFraction, 0.6 * r.idealFraction);  // groups do cull most of it
    if (distance == 0)
      EXPECT_NEAR(r.idealFraction, 0.5, 0.01);  // half a sphere faces away
    else
      EXPECT_GT(r.idealFraction, 0.5);  // a near eye sees less than half
  }
}

TEST(CullingCost, SingletonGroupsCostMoreThanPerFaceCulling) {
  // Level 1 of single faces (a threshold no pair can meet): every face costs its group test,
  // and the face test of every visible face: cost = 1 + visible fraction.
  const IndexedMesh sphere = test::Sphere(3);
  ConeGroupingParams p;
  p.coneThresholdDeg = 1e-6;
  p.maxLevels = 1;
  const GroupHierarchy h = Group(sphere, p);
  ASSERT_EQ(h.level(1).groups.size(), sphere.faces.size());
  CullingCostParams cp;
  cp.views = 100;
  CullingCostResult r;
  ASSERT_TRUE(EvaluateCullingCost(sphere, h, cp, r).ok());
  EXPECT_NEAR(r.twoState.mean, 1 + (1 - r.idealFraction), 1e-9);
  EXPECT_NEAR(r.rejectedFraction, r.idealFraction, 1e-9);
}

TEST(CullingCost, BunnyTwoStateNearIdealThreeStateFarBelow) {
  CMesh m;
  ASSERT_EQ(LoadPly(m, test::MeshPath("stanford_bunny_bun_zipper.ply")), "");
  const IndexedMesh bunny = ToIndexedMesh(m);
  const GroupHierarchy h = Group(bunny);
  CullingCostParams cp;
  cp.views = 300;
  CullingCostResult r;
  ASSERT_TRUE(EvaluateCullingCost(bunny, h, cp, r).ok());
  // Drawing needs about 1 - ideal of the faces; the two-state cost stays close to it and the
  // three-state cost is far below per-face culling.
  EXPECT_LT(r.twoState.mean, 1.0);
  EXPECT_LT(r.twoState.mean, (1 - r.idealFraction) + 0.25);
  EXPECT_LT(r.threeState.mean, 0.5 * r.twoState.mean);
  EXPECT_LE(r.rejectedFraction, r.idealFraction);
  EXPECT_GT(r.rejectedFraction, 0.7 * r.idealFraction);
}

TEST(CullingCost, BadArgumentsAreRefused) {
  const IndexedMesh cube = test::Cube();
  const GroupHierarchy h = Group(cube);
  CullingCostResult r;
  CullingCostParams cp;
  cp.views = 0;
  EXPECT_FALSE(EvaluateCullingCost(cube, h, cp, r).ok());
  cp = CullingCostParams();
  cp.cameraDistance = 0.5;  // inside the model
  EXPECT_FALSE(EvaluateCullingCost(cube, h, cp, r).ok());
  EXPECT_FALSE(EvaluateCullingCost(test::Sphere(1), h, CullingCostParams(), r).ok());  // other mesh
}

}  // namespace
}  // namespace conelod
