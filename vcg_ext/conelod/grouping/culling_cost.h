// ConeLOD — the cost of back-face culling with a group hierarchy.
//
// Kamiya, Suzuki, Kawachi (§5): per-face back-face culling costs N tests for N faces (cost 1).
// With groups the cost is the number of group tests plus the per-face tests inside the level-1
// groups found visible, over N. The hierarchy is traversed from the top: an invisible group is
// skipped with its whole subtree, a visible one tests its children. BEYOND the paper:
//  - three-state: a group that is fully front-facing draws its whole subtree with no further
//    test (same rejected faces, fewer tests);
//  - rejected fraction (faces culled at group level) against the ideal fraction (faces that draw
//    nothing for that view: back-facing or zero-area);
//  - a perspective camera: the eye on a sphere around the model, the conservative test of
//    ClassifyPerspective (the paper's test holds for orthographic views only).
// View directions are spread uniformly on the sphere (Fibonacci lattice).
#pragma once

#include <vector>

#include "conelod/grouping/group_hierarchy.h"
#include "conelod/mesh/indexed_mesh.h"
#include "conelod/status.h"

namespace conelod {

struct CullingCostParams {
  int views = 1000;
  // 0: orthographic views. > 1: a perspective eye at this many bounding-sphere radii from the
  // centre of the model's bounding sphere, looking at it.
  double cameraDistance = 0;
};

struct CostStats {
  double mean = 0, min = 0, max = 0;
};

struct CullingCostResult {
  int views = 0;
  bool perspective = false;
  double cameraDistance = 0;
  CostStats twoState;                // tests / N
  CostStats threeState;              // tests / N
  double rejectedFraction = 0;       // mean over views: faces culled by group tests / N
  double idealFraction = 0;          // mean over views: faces that draw nothing / N
  double frontAcceptedFraction = 0;  // mean: faces accepted by a fully-front group test / N
  double meanGroupTests = 0;         // mean group tests per view (two-state)
};

// Unit view directions (from the eye towards the model), uniform on the sphere.
std::vector<vcg::Point3d> ViewDirections(int count);

Status EvaluateCullingCost(const IndexedMesh& mesh, const GroupHierarchy& hierarchy, const CullingCostParams& params,
                           CullingCostResult& out, const Progress& progress = Progress());

}  // namespace conelod
