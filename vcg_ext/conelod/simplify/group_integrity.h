// ConeLOD — group integrity: did the face groups survive a simplification?
//
// Kamiya, Suzuki, Kawachi, "LODs for efficient displaying triangle meshes" (§6, fig. 8): a
// simplification that ignores the groups splits some of them into pieces or removes them. We
// count, per group id, its edge-connected pieces before and after: a group is intact when it still
// has a face and no more pieces than before. Groups already in several pieces before are reported
// as such (groupsDisconnectedBefore), never silently "fixed". Group ids are per-face ints >= 0;
// GroupIdsFromValues turns MeshLab's per-face quality into ids.
#pragma once

#include <vector>

#include "conelod/mesh/indexed_mesh.h"
#include "conelod/status.h"

namespace conelod {

// Number of edge-connected pieces of every group: one {id, pieces} per distinct id, by id.
struct GroupPieces {
  std::vector<int> ids;        // distinct group ids, increasing
  std::vector<int> pieces;     // pieces[i]: edge-connected pieces of group ids[i] (faces that use a
                               // vertex twice, points or segments, are no piece: 0 if only those)
  int piecesOf(int id) const;  // 0 when the id has no face
};
GroupPieces CountGroupPieces(const IndexedMesh& mesh, const std::vector<int>& faceGroup);

struct GroupIntegrity {
  int groupsBefore = 0;                    // distinct ids before
  int groupsAfter = 0;                     // distinct ids after
  int groupsVanished = 0;                  // ids with faces before and none after
  int groupsSplit = 0;                     // ids with more edge-connected pieces after than before
  int groupsDisconnectedBefore = 0;        // ids already in several pieces before
  int groupsDisconnectedAfter = 0;         // ids in several pieces after
  int groupsNew = 0;                       // ids after that did not exist before (should be 0)
  std::vector<int> vanishedIds, splitIds;  // the first few of each, for messages
  // Set by the caller: groups removed on purpose with whole components (GroupQemStats::
  // groupsRemoved), counted in groupsVanished but not against integrity.
  int groupsRemoved = 0;
  // Fraction of the groups before, but those removed on purpose, that still exist and are not
  // split (1 = 100% intact): every remaining group is one piece.
  double intact() const {
    const int kept = groupsBefore - groupsRemoved;
    return kept > 0 ? double(kept - (groupsVanished - groupsRemoved) - groupsSplit) / kept : 1.0;
  }
};

// Compares the groups of `before` and `after` (ids must mean the same group in both). Invalid
// when an id list does not have one id >= 0 per face.
Status MeasureGroupIntegrity(const IndexedMesh& before, const std::vector<int>& groupBefore, const IndexedMesh& after,
                             const std::vector<int>& groupAfter, GroupIntegrity& out);
// The same, given the groups' pieces before (CountGroupPieces of the mesh before, counted while it
// was there: `conelod simplify` frees the input during the collapse).
Status MeasureGroupIntegrity(const GroupPieces& before, const IndexedMesh& after, const std::vector<int>& groupAfter,
                             GroupIntegrity& out);

// Groups whose faces' normals no longer fit in a cone of half-angle limitDeg (their exact minimal
// cone, normal_cone.h, is wider by more than 1e-6 rad): after a simplification, the groups of a
// level whose cones exceed the level's threshold (GroupLevel::thresholdDeg) and so cull worse.
// Zero-area faces have no normal and are ignored. `overIds` (optional): the first few such ids.
int CountConesOverLimit(const IndexedMesh& mesh, const std::vector<int>& faceGroup, double limitDeg,
                        std::vector<int>* overIds = nullptr);

// Group ids from per-face values (e.g. per-face quality): faces with equal values form one group.
// When every value is an integer in [0, 2^31) the ids are the values; otherwise they are the ranks
// of the distinct values over all the lists together, so that the same value gets the same id in
// every list (a mesh before and after simplification). Non-finite values are an error.
Status GroupIdsFromValues(const std::vector<const std::vector<float>*>& values, std::vector<std::vector<int>>& ids);

}  // namespace conelod
