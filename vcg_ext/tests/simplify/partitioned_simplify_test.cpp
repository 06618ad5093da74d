// Tests of partitioned_simplify.h: a big simplification in parts side by side, then a final pass
// over the stitched mesh. Every group stays whole, the target is reached, the result does not
// depend on the number of threads, it stays close to the serial run, and below the threshold it
// IS the serial run.
#include "conelod/simplify/partitioned_simplify.h"

#include <gtest/gtest.h>

#include <thread>

#include "conelod/grouping/cone_grouping.h"
#include "conelod/mesh/sampled_distance.h"
#include "conelod/simplify/group_integrity.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"
#include "test_util.h"

namespace conelod {
namespace {

// A shared test mesh and its groups at the automatic cone level for `targetFaces` (as
// `conelod simplify --groups cone:auto`).
void LoadGrouped(const char* name, size_t targetFaces, IndexedMesh& m, std::vector<int>& groups) {
  CMesh cm;
  ASSERT_EQ(LoadPly(cm, test::MeshPath(name)), "");
  m = ToIndexedMesh(cm);
  GroupHierarchy h;
  ASSERT_TRUE(BuildConeHierarchy(m, ConeGroupingParams(), h).ok());
  groups = h.level(AutoGroupLevel(h, targetFaces)).faceGroup;
}

bool Same(const GroupQemResult& a, const GroupQemResult& b) {
  return a.mesh.faces == b.mesh.faces && a.mesh.positions == b.mesh.positions && a.sourceFace == b.sourceFace &&
         a.sourceVertex == b.sourceVertex;
}

void ExpectWholeGroups(const IndexedMesh& m, const std::vector<int>& groups, const GroupQemResult& r) {
  ASSERT_EQ(r.sourceFace.size(), r.mesh.faces.size());
  ASSERT_EQ(r.sourceVertex.size(), r.mesh.positions.size());
  std::vector<int> after(r.sourceFace.size());
  for (size_t f = 0; f < after.size(); ++f) {
    ASSERT_LT(r.sourceFace[f], m.faces.size());
    after[f] = groups[r.sourceFace[f]];
    if (f > 0) {
      EXPECT_LT(r.sourceFace[f - 1], r.sourceFace[f]) << "faces out of input order";
    }
  }
  for (size_t v = 1; v < r.sourceVertex.size(); ++v) {
    EXPECT_LT(r.sourceVertex[v - 1], r.sourceVertex[v]);
  }
  GroupIntegrity gi;
  ASSERT_TRUE(MeasureGroupIntegrity(m, groups, r.mesh, after, gi).ok());
  EXPECT_EQ(gi.groupsSplit, 0);
  EXPECT_EQ(gi.groupsVanished, int(r.stats.groupsRemoved));
  EXPECT_EQ(gi.groupsNew, 0);
}

// The bunny in 8 parts: whole groups, the target, the same result on 1, 2 and 3 threads, and the
// accuracy of the serial run (RMS distance within 2 %, measured +0.x %).
TEST(SimplifyPartitioned, BunnyInPartsMatchesSerial) {
  IndexedMesh m;
  std::vector<int> groups;
  const size_t target = 6945;  // 10 %
  ASSERT_NO_FATAL_FAILURE(LoadGrouped("stanford_bunny_bun_zipper.ply", target, m, groups));
  GroupQemParams q;
  q.targetFaces = target;
  q.removeComponents = true;  // as the CLI
  PartitionParams p;
  p.minFaces = 1;
  p.facesPerPart = 10000;
  ASSERT_EQ(PartitionCount(m.faces.size(), q, p), 8);
  GroupQemResult one, two, three, serial;
  PartitionStats st;
  p.threads = 1;
  ASSERT_TRUE(SimplifyPartitioned(m, groups, q, p, one, Progress(), &st).ok());
  EXPECT_EQ(st.parts, 8);
  EXPECT_GT(st.frozenVertices, 0u);
  EXPECT_GT(st.facesAfterParts, target) << "the seams are left for the final pass";
  EXPECT_GT(st.finalPassCollapses, 0u);
  EXPECT_LE(one.mesh.faces.size(), target);
  EXPECT_GE(one.mesh.faces.size(), target - 2);
  EXPECT_EQ(one.stats.facesIn, m.faces.size());
  ASSERT_NO_FATAL_FAILURE(ExpectWholeGroups(m, groups, one));
  p.threads = 2;
  ASSERT_TRUE(SimplifyPartitioned(m, groups, q, p, two).ok());
  p.threads = 3;
  ASSERT_TRUE(SimplifyPartitioned(m, groups, q, p, three).ok());
  EXPECT_TRUE(Same(one, two)) << "the result depends on the number of threads";
  EXPECT_TRUE(Same(one, three)) << "the result depends on the number of threads";

  ASSERT_TRUE(SimplifyPreservingGroups(m, groups, q, serial).ok());
  EXPECT_FALSE(Same(one, serial)) << "8 parts should differ from one piece";
  SurfaceDistance dParts, dSerial;
  ASSERT_TRUE(SampledDistance(m, one.mesh, 50000, dParts).ok());
  ASSERT_TRUE(SampledDistance(m, serial.mesh, 50000, dSerial).ok());
  EXPECT_LT(dParts.rms, 1.02 * dSerial.rms) << "parts " << dParts.rms << ", serial " << dSerial.rms;
}

// Below the threshold (or with minFaces = 0) it is the serial run, bit for bit.
TEST(SimplifyPartitioned, BelowTheThresholdIsSerial) {
  const IndexedMesh m = test::Sphere(4);
  std::vector<int> groups;
  GroupHierarchy h;
  ASSERT_TRUE(BuildConeHierarchy(m, ConeGroupingParams(), h).ok());
  groups = h.level(1).faceGroup;
  GroupQemParams q;
  q.targetFaces = m.faces.size() / 5;
  PartitionParams p;  // default threshold: 2,000,000 faces
  EXPECT_EQ(PartitionCount(m.faces.size(), q, p), 1);
  GroupQemResult parts, serial;
  PartitionStats st;
  ASSERT_TRUE(SimplifyPartitioned(m, groups, q, p, parts, Progress(), &st).ok());
  ASSERT_TRUE(SimplifyPreservingGroups(m, groups, q, serial).ok());
  EXPECT_EQ(st.parts, 0);
  EXPECT_TRUE(Same(parts, serial));
  p.minFaces = 0;
  EXPECT_EQ(PartitionCount(size_t(1) << 30, q, p), 1);
  p.minFaces = 1000;
  p.facesPerPart = 1;
  EXPECT_EQ(PartitionCount(m.faces.size(), q, p), kMaxPartitions);
}

// A flat grid with a few large groups: parts may be empty or unbalanced; still whole groups.
TEST(SimplifyPartitioned, FewGroupsAndOneGroup) {
  const IndexedMesh m = test::Grid(40);  // 3200 faces
  std::vector<int> groups(m.faces.size());
  for (size_t f = 0; f < groups.size(); ++f) groups[f] = int(f / 800);  // 4 bands
  GroupQemParams q;
  q.targetFaces = 400;
  PartitionParams p;
  p.minFaces = 1;
  p.facesPerPart = 100;  // 32 parts wanted, 4 groups
  GroupQemResult r;
  ASSERT_TRUE(SimplifyPartitioned(m, groups, q, p, r).ok());
  ASSERT_NO_FATAL_FAILURE(ExpectWholeGroups(m, groups, r));
  EXPECT_LE(r.mesh.faces.size(), 400u);
  std::fill(groups.begin(), groups.end(), 0);
  ASSERT_TRUE(SimplifyPartitioned(m, groups, q, p, r).ok());
  ASSERT_NO_FATAL_FAILURE(ExpectWholeGroups(m, groups, r));
  EXPECT_LE(r.mesh.faces.size(), 400u);
}

TEST(SimplifyPartitioned, BadInputAndCancellation) {
  const IndexedMesh m = test::Sphere(4);
  std::vector<int> groups(m.faces.size(), 0);
  GroupQemParams q;
  q.targetFaces = 100;
  PartitionParams p;
  p.minFaces = 1;
  p.facesPerPart = 500;
  GroupQemResult r;
  std::vector<int> bad = groups;
  bad[3] = -1;
  EXPECT_FALSE(SimplifyPartitioned(m, bad, q, p, r).ok());
  EXPECT_TRUE(r.mesh.faces.empty());
  EXPECT_FALSE(SimplifyPartitioned(m, std::vector<int>(5, 0), q, p, r).ok()) << "groups of another mesh";
  q.qualityThr = -1;
  EXPECT_FALSE(SimplifyPartitioned(m, groups, q, p, r).ok());
  q.qualityThr = 0.3;
  // Cancelled from the progress callback, which is only ever called on this thread.
  p.threads = 2;
  const auto caller = std::this_thread::get_id();
  bool otherThread = false;
  const Status s = SimplifyPartitioned(m, groups, q, p, r, [&](int percent, const char*) {
    otherThread |= std::this_thread::get_id() != caller;
    return percent < 5;
  });
  EXPECT_EQ(s.code, Status::Code::Cancelled);
  EXPECT_FALSE(otherThread) << "progress was called from a worker thread";
}

}  // namespace
}  // namespace conelod
