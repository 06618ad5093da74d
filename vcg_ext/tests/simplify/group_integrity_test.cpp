// Tests of group_integrity.h: pieces, vanished and split groups on hand-made cases; ids from
// per-face values.
#include "conelod/simplify/group_integrity.h"

#include <gtest/gtest.h>

#include <cmath>

#include "test_util.h"

namespace conelod {
namespace {

// Grid(3): quad (x, y) has faces 2 (3 y + x) and 2 (3 y + x) + 1.
std::vector<int> QuadGroups(const std::vector<int>& perQuad) {
  std::vector<int> g;
  for (int q : perQuad) g.insert(g.end(), 2, q);
  return g;
}

TEST(CountGroupPieces, CountsEdgeConnectedPiecesPerGroup) {
  const IndexedMesh m = test::Grid(3);
  // Group 5 in two opposite corners (touching nothing), group 2 a cross in the middle.
  const auto g = QuadGroups({5, 2, 0, 2, 2, 2, 0, 2, 5});
  const GroupPieces p = CountGroupPieces(m, g);
  EXPECT_EQ(p.ids, (std::vector<int>{0, 2, 5}));
  EXPECT_EQ(p.piecesOf(5), 2);
  EXPECT_EQ(p.piecesOf(2), 1);
  EXPECT_EQ(p.piecesOf(0), 2);  // two corners that only touch the cross
  EXPECT_EQ(p.piecesOf(9), 0);
}

TEST(CountGroupPieces, FacesTouchingAtAVertexAreTwoPieces) {
  IndexedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  m.faces = {{0, 1, 2}, {0, 3, 4}};  // a bow tie
  EXPECT_EQ(CountGroupPieces(m, {1, 1}).piecesOf(1), 2);
}

TEST(MeasureGroupIntegrity, ReportsVanishedSplitAndAlreadyDisconnectedGroups) {
  const IndexedMesh before = test::Grid(3);
  const auto gb = QuadGroups({5, 1, 1, 3, 3, 3, 4, 4, 5});  // 5 already in two pieces
  // After: group 4 gone (its faces deleted), group 3 cut in two by removing its middle quad.
  IndexedMesh after = before;
  std::vector<int> ga;
  after.faces.clear();
  for (size_t f = 0; f < before.faces.size(); ++f) {
    const size_t quad = f / 2;
    if (gb[f] == 4 || quad == 4) continue;
    after.faces.push_back(before.faces[f]);
    ga.push_back(gb[f]);
  }
  GroupIntegrity gi;
  ASSERT_TRUE(MeasureGroupIntegrity(before, gb, after, ga, gi).ok());
  EXPECT_EQ(gi.groupsBefore, 4);
  EXPECT_EQ(gi.groupsAfter, 3);
  EXPECT_EQ(gi.groupsVanished, 1);
  EXPECT_EQ(gi.vanishedIds, std::vector<int>{4});
  EXPECT_EQ(gi.groupsSplit, 1);
  EXPECT_EQ(gi.splitIds, std::vector<int>{3});
  EXPECT_EQ(gi.groupsDisconnectedBefore, 1);  // 5, reported, and not counted as split
  EXPECT_EQ(gi.groupsDisconnectedAfter, 2);   // 5 and 3
  EXPECT_DOUBLE_EQ(gi.intact(), 0.5);
  // The same from the pieces counted before (`conelod simplify` frees the input during the collapse).
  GroupIntegrity fromPieces;
  ASSERT_TRUE(MeasureGroupIntegrity(CountGroupPieces(before, gb), after, ga, fromPieces).ok());
  EXPECT_EQ(fromPieces.groupsBefore, gi.groupsBefore);
  EXPECT_EQ(fromPieces.groupsAfter, gi.groupsAfter);
  EXPECT_EQ(fromPieces.vanishedIds, gi.vanishedIds);
  EXPECT_EQ(fromPieces.splitIds, gi.splitIds);
  EXPECT_EQ(fromPieces.groupsDisconnectedBefore, gi.groupsDisconnectedBefore);
  EXPECT_EQ(fromPieces.groupsDisconnectedAfter, gi.groupsDisconnectedAfter);
  EXPECT_EQ(fromPieces.groupsNew, gi.groupsNew);
  EXPECT_FALSE(MeasureGroupIntegrity(CountGroupPieces(before, gb), after, {1, 2}, fromPieces).ok());
  // The identity is 100% intact.
  ASSERT_TRUE(MeasureGroupIntegrity(before, gb, before, gb, gi).ok());
  EXPECT_DOUBLE_EQ(gi.intact(), 1.0);
  EXPECT_EQ(gi.groupsDisconnectedBefore, 1);
  // Bad ids.
  EXPECT_FALSE(MeasureGroupIntegrity(before, gb, after, {1, 2}, gi).ok());
  std::vector<int> negative = gb;
  negative[0] = -1;
  EXPECT_FALSE(MeasureGroupIntegrity(before, negative, before, gb, gi).ok());
}

TEST(GroupIdsFromValues, IntegersAreIdsOtherValuesAreRanksSharedByAllLists) {
  std::vector<std::vector<int>> ids;
  const std::vector<float> a = {3, 0, 3, 12}, b = {12, 3};
  ASSERT_TRUE(GroupIdsFromValues({&a, &b}, ids).ok());
  EXPECT_EQ(ids[0], (std::vector<int>{3, 0, 3, 12}));
  EXPECT_EQ(ids[1], (std::vector<int>{12, 3}));
  const std::vector<float> c = {0.5f, -1.f, 0.5f}, d = {2.25f, -1.f};
  ASSERT_TRUE(GroupIdsFromValues({&c, &d}, ids).ok());
  EXPECT_EQ(ids[0], (std::vector<int>{1, 0, 1}));
  EXPECT_EQ(ids[1], (std::vector<int>{2, 0}));
  const std::vector<float> bad = {1, std::nanf("")};
  EXPECT_NE(GroupIdsFromValues({&bad}, ids).message.find("NaN"), std::string::npos);
}

}  // namespace
}  // namespace conelod
