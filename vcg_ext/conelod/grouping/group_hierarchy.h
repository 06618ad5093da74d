// ConeLOD — a hierarchy of edge-connected face groups, as built by cone_grouping.h.
//
// Level 1 groups faces; level k > 1 groups the groups of level k-1. Every face belongs to
// exactly one group per level. Children of a level-1 group are face indices; children of a
// level-k group are indices of level-(k-1) groups. Parents are indices into the level above.
#pragma once

#include <vector>

#include <vcg/space/box3.h>
#include <vcg/space/point3.h>

#include "conelod/grouping/normal_cone.h"

namespace conelod {

struct Group {
  NormalCone cone;      // exact minimal cone of the group's face normals
  vcg::Point3f center;  // bounding sphere (encloses every vertex of the group)
  float radius = 0;
  vcg::Box3f box;  // bounding box of the group's vertices
  int faceCount = 0;
  double area = 0;
  int parent = -1;     // group index in the level above; -1 at the top level
  int firstChild = 0;  // children are Level::children[firstChild .. firstChild+childCount)
  int childCount = 0;
};

struct GroupLevel {
  double thresholdDeg = 0;  // the cone half-angle limit this level was built with
  std::vector<Group> groups;
  std::vector<int> children;   // concatenated child lists (faces at level 1, groups above)
  std::vector<int> faceGroup;  // per face: its group at this level

  // Figures for tables and logs. Cones that cannot be culled count as 180 degrees.
  double maxConeDeg() const;
  double meanConeDeg() const;
  int uncullableGroups() const;
};

struct GroupHierarchy {
  int faceCount = 0;
  std::vector<GroupLevel> levels;  // levels[0] is level 1 (the finest)

  int levelCount() const { return int(levels.size()); }
  const GroupLevel& level(int oneBased) const { return levels[size_t(oneBased - 1)]; }
};

}  // namespace conelod
