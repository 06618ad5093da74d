// ConeLOD — hierarchical face grouping by an evaluation function.
//
// Kamiya, Suzuki, Kawachi, "LODs for efficient displaying triangle meshes" (§4): adjacent units
// (faces at level 1, groups of the previous level above) are merged greedily, best pair first,
// by  v = k_c v_c + k_s v_s + k_n v_n  (eq. 2), with
//   v_c = (pi - c) / pi     c = the merged group's cone HALF-angle, in radians (the paper's
//                           "cone": the largest angle between the group normal and a face normal);
//                           the same half-angle is bounded by the cone threshold;
//   v_s = S_p / S_c         projected area over the area of the enclosing circle; S_p is the
//                           length of the group's vector area (its area projected on the plane
//                           normal to its mean normal, exact while the projection does not fold)
//                           and S_c = pi r^2 with r the radius of the group's bounding sphere, an
//                           upper bound of the projection's enclosing circle (so v_s is a lower
//                           bound, computed in O(1) per candidate);
//   v_n = (N - n) / N       N faces in the mesh, n faces in the merged group.
// Pairs whose merged cone reaches the level's threshold are not merged. A level ends when no pair
// is left or when the number of groups reaches minTopGroups; the next level repeats the process
// on the groups with the threshold multiplied by thresholdGrowth.
//
// Merge order. The paper pops the best pair of the whole mesh at every step. Level 1 (nearly all
// the merges) first merges local maxima instead: sweeps over the units in index order merge
// every pair that is the best pair of both its units, and the merged unit goes on merging while
// its best pair stays mutual; once a sweep merges nothing, the best-first order finishes the
// level. A mutual best pair is what the best-first order would merge too unless a better pair
// next to it changed first; the sweeps visit the mesh in memory order, where the best-first
// order jumps across the whole mesh at every merge (1.6-2x faster on the dragon, same culling
// cost: docs/cone_grouping.md). Levels above the first keep the best-first order. On meshes of
// at least two chunks (ConeGroupingParams::chunkFaces), the sweeps run first within chunks of
// consecutive faces, each on its own and on the threads, merging only units with no neighbour
// outside their chunk; twice, the second time with the cuts moved by half a chunk; then the
// sweeps over the whole level and the best-first order go on from there (the same culling cost
// on the dragon: docs/cone_grouping.md).
//
// Candidate cones are the exact union of the two units' cones (an upper bound of the merged
// normals' minimal cone, so the threshold is never exceeded); a group's cone is recomputed
// exactly (MinimalCone, Welzl) whenever its face count has grown 8-fold at level 1 and 4-fold
// above (2-fold everywhere with strictGreedy) since the last exact computation — amortized
// O(N log N) — and every group of the output has its exact cone.
#pragma once

#include "conelod/grouping/group_hierarchy.h"
#include "conelod/mesh/indexed_mesh.h"
#include "conelod/status.h"

namespace conelod {

// The level-1 chunk size of `conelod group`, the Normal Cone Face Grouping and Cluster Culling
// Cost filters and `conelod cull-cost` (ConeGroupingParams::chunkFaces).
constexpr int kGroupingChunkFaces = 50000;

struct ConeGroupingParams {
  double coneWeight = 1.0;         // k_c
  double shapeWeight = 0.5;        // k_s
  double sizeWeight = 0.5;         // k_n
  double coneThresholdDeg = 15.0;  // level-1 limit on the group cone half-angle; >= 180: no limit
  double thresholdGrowth = 1.6;    // the limit is multiplied by this at each level above the first
  int maxLevels = 8;               // at most this many levels
  int minTopGroups = 8;            // stop merging once a level has this many groups (or fewer)
  // true: every level merges strictly the best pair of the whole level first and recomputes
  // cones exactly at every doubling (the paper's order; the output of ConeLOD before local
  // maxima, bit for bit; about 1.6-2x slower). false: see "Merge order" above.
  bool strictGreedy = false;
  // Level 1 (default mode) first merges within chunks of about this many consecutive faces, each
  // chunk on its own (on the threads), pairs whose units have no neighbour in another chunk; then
  // the sweeps and the best-first order go on over the whole level. The chunk count is the face
  // count over this, at most 64 (above 64 x chunkFaces faces the chunks grow), so the groups do not
  // depend on the thread count. 0, or fewer faces than two chunks: no chunks (every merge in the
  // order above). The grouping command and filter, and the
  // collapse's own grouping (`--groups cone:L|cone:auto`), use kGroupingChunkFaces: the same groups.
  int chunkFaces = 0;
  // Threads for the parts of the build that run in parallel (the face adjacency, the level-1
  // units and their first scores, level 1's chunks, the exact cones and spheres of each level's
  // groups); 0: one per core. The output is the same, bit for bit, for every thread count.
  int threads = 1;
  // For a simplification to this many faces (`--groups cone:auto`): the build stops at the level
  // AutoGroupLevel would choose, the first whose groups x kAutoFacesPerGroup <= autoTargetFaces,
  // and the levels above it are not built (each level built is that of the whole build, bit for
  // bit). 0: every level.
  size_t autoTargetFaces = 0;
};

// The grouping of a collapse to `targetFaces` (`--groups cone:L|cone:auto`, the collapse filter):
// `conelod group`'s (kGroupingChunkFaces, on `threads`; 0: one per core), built only up to
// AutoGroupLevel's level when `automatic`.
ConeGroupingParams CollapseGroupingParams(size_t targetFaces, bool automatic, int threads);

// Checks the parameters; Ok or a message naming the bad one.
Status ValidateParams(const ConeGroupingParams& p);

// Builds the hierarchy. The mesh must pass RequireValidForFaces (checked here too). On failure or
// cancellation `out` is left empty. `adjacency`: BuildFaceAdjacency(mesh) when the caller has it
// (for its own checks): read instead of building the same lists again (the output is the same);
// null: built here, into memory that the build's next arrays reuse (the lower peak).
Status BuildConeHierarchy(const IndexedMesh& mesh, const ConeGroupingParams& params, GroupHierarchy& out,
                          const Progress& progress = Progress(), const FaceAdjacency* adjacency = nullptr);

// Per level of `h` (index 0: level 1): GroupsAreEdgeConnected(adj, faceGroup of the level), `adj`
// the mesh's BuildFaceAdjacency. Level 1 is checked on the faces; a level above, when level 1's
// groups are connected and each lies in one group of the level (as the build makes them), on the
// graph of level 1's groups (a group is connected iff its level-1 groups are, through faces that
// share an edge), a few hundredths of the faces' work; else on the faces too. The same answers.
std::vector<char> LevelsAreEdgeConnected(const FaceAdjacency& adj, const GroupHierarchy& h);

// The automatic group level for a simplification to `targetFaces`: the finest level of `h` whose
// groups leave at least kAutoFacesPerGroup faces per group at the target (groups x 8 <= target),
// the top level when none does (1-based; 0 for an empty hierarchy). Below about 8 faces per group
// the groups, not the geometry, decide where the collapses go: the error grows quickly and, under
// 3-4 faces per group, the target stops being reachable.
constexpr int kAutoFacesPerGroup = 8;
int AutoGroupLevel(const GroupHierarchy& h, size_t targetFaces);

// Per group id of level `level` (1-based): the cone its face normals must stay in to keep the
// level's threshold (GroupQemParams::coneBound): the group's cone axis and the level's threshold.
std::vector<NormalCone> LevelConeBounds(const GroupHierarchy& h, int level);

}  // namespace conelod
