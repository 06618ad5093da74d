// Tests of hierarchical_simplification.h: one level per hierarchy level, each coarser, each
// keeping its own groups (and the coarser ones) intact, sources traced back to the input.
#include "conelod/hierarchical_simplification.h"

#include <gtest/gtest.h>

#include "conelod/cone_grouping.h"
#include "conelod/group_integrity.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"
#include "test_util.h"

namespace conelod {
namespace {

void ExpectLevelsValid(const IndexedMesh& m, const GroupHierarchy& h, const std::vector<SimplifiedLevel>& levels) {
  ASSERT_EQ(int(levels.size()), h.levelCount());
  size_t below = m.faces.size();
  for (const SimplifiedLevel& L : levels) {
    SCOPED_TRACE("level " + std::to_string(L.level));
    EXPECT_LE(L.mesh.faces.size(), below);
    below = L.mesh.faces.size();
    ASSERT_EQ(L.sourceFace.size(), L.mesh.faces.size());
    ASSERT_EQ(L.sourceVertex.size(), L.mesh.positions.size());
    for (size_t f = 0; f < L.sourceFace.size(); ++f) {
      ASSERT_LT(L.sourceFace[f], m.faces.size());
      EXPECT_EQ(L.faceGroup[f], h.level(L.level).faceGroup[L.sourceFace[f]]);
    }
    // This level's groups and every coarser level's, against the input.
    for (int j = L.level; j <= h.levelCount(); ++j) {
      std::vector<int> after;
      for (uint32_t f : L.sourceFace) after.push_back(h.level(j).faceGroup[f]);
      GroupIntegrity gi;
      ASSERT_TRUE(MeasureGroupIntegrity(m, h.level(j).faceGroup, L.mesh, after, gi).ok());
      EXPECT_EQ(gi.groupsSplit, 0) << "level " << j << " groups";
      EXPECT_EQ(gi.groupsVanished, 0) << "level " << j << " groups";
    }
  }
}

TEST(BuildSimplifiedLevels, SphereLevelsAreCoarserAndIntact) {
  const IndexedMesh m = test::Sphere(4);
  GroupHierarchy h;
  ASSERT_TRUE(BuildConeHierarchy(m, ConeGroupingParams(), h).ok());
  ASSERT_GE(h.levelCount(), 3);
  HierarchicalSimplificationParams p;
  std::vector<SimplifiedLevel> levels;
  ASSERT_TRUE(BuildSimplifiedLevels(m, h, p, levels).ok());
  ExpectLevelsValid(m, h, levels);
  EXPECT_LT(levels.back().mesh.faces.size(), levels.front().mesh.faces.size());
  EXPECT_LE(levels.front().mesh.faces.size(), m.faces.size() / 2);
}

TEST(BuildSimplifiedLevels, Bunny) {
  CMesh cm;
  ASSERT_EQ(LoadPly(cm, test::MeshPath("stanford_bunny_bun_zipper.ply")), "");
  const IndexedMesh m = ToIndexedMesh(cm);
  GroupHierarchy h;
  ASSERT_TRUE(BuildConeHierarchy(m, ConeGroupingParams(), h).ok());
  std::vector<SimplifiedLevel> levels;
  ASSERT_TRUE(BuildSimplifiedLevels(m, h, HierarchicalSimplificationParams(), levels).ok());
  ExpectLevelsValid(m, h, levels);
  EXPECT_LT(levels.back().mesh.faces.size(), m.faces.size() / 20);
}

TEST(BuildSimplifiedLevels, BadInputAndCancellation) {
  const IndexedMesh m = test::Sphere(3);
  GroupHierarchy h;
  ASSERT_TRUE(BuildConeHierarchy(m, ConeGroupingParams(), h).ok());
  std::vector<SimplifiedLevel> levels;
  HierarchicalSimplificationParams p;
  p.levelRatio = 0;
  EXPECT_FALSE(BuildSimplifiedLevels(m, h, p, levels).ok());
  p.levelRatio = 0.5;
  EXPECT_FALSE(BuildSimplifiedLevels(test::Sphere(2), h, p, levels).ok()) << "hierarchy of another mesh";
  const Status s = BuildSimplifiedLevels(m, h, p, levels, [](int percent, const char*) { return percent < 30; });
  EXPECT_EQ(s.code, Status::Code::Cancelled);
  EXPECT_TRUE(levels.empty());
}

}  // namespace
}  // namespace conelod
