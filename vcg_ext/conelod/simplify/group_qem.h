// ConeLOD — group-preserving quadric edge collapse.
//
// Kamiya, Suzuki, Kawachi, "LODs for efficient displaying triangle meshes" (§6): QEM edge collapse
// (Garland & Heckbert, SIGGRAPH 97) in which every collapse of an edge e = (v1, v2) with incident
// faces f1, f2 keeps the face groups intact, in one of two modes (GroupMode).
//
// Integrity mode (the default): after every collapse every group is still one non-empty
// edge-connected piece, and nothing else is asked (no fixed corners, no contour quadrics: the
// placement and quadrics of plain QEM). With a manifold neighbourhood and the link condition, a
// collapse removes f1, f2 and only adds adjacencies (the faces across (v1, x) and (v2, x), x the
// third vertex of f1 or f2, become neighbours), so only the groups of f1 and f2 can lose anything.
// Such a group vanishes when f1/f2 are its last faces (refused), and splits exactly when its faces
// next to f1/f2 are no longer connected inside it: connected through the merged vertex's fan, or
// by a search inside the group bounded to kIntegritySearchFaces faces (not found: refused). The
// same test runs for every coarser grouping (hierarchies). keepCones also refuses collapses that
// turn a changed face's normal out of its group's cone bound.
//
// Paper mode: the paper's conditions, as follows.
//   condition 1 (no group is split or destroyed): f1 has a face of its own group among its
//     neighbours other than f2, and f2 likewise; and, when f1 and f2 are in the SAME group, v1 or
//     v2 is not on a group boundary. The paper asks for the last clause in every case; we ask for
//     it only where it matters, which lets a contour edge (f1, f2 in two groups) collapse and the
//     group contours simplify, as the paper intends. With a manifold neighbourhood and the link
//     condition (both always checked) a collapse only removes f1, f2 and only makes faces
//     adjacent, never separates them; removing f1 cannot cut f1's group when f1's two other
//     neighbours become adjacent, and f1 + f2 of one group cannot cut it when one endpoint's whole
//     closed fan is in that group. So condition 1 guarantees that no group is split or vanishes
//     (group_qem_test.cpp checks it face by face). "Not on a group boundary" = every face around
//     the vertex in one group and a closed manifold fan (a mesh-border vertex does not qualify).
//   condition 2 (no vertex where many groups meet is created): v1 or v2 has at most 2 groups
//     around it (the paper), and the merged vertex has no more groups around it than
//     max(2, groups at v1, groups at v2) (so two contour vertices of different contours are not
//     merged into a new 3-group corner).
//   lock group boundaries (option): no vertex with 2 or more groups around it moves, so no group
//     contour changes and no contour edge collapses (crack-free refinement between groups).
// Placement (paper mode with condition 1, or the lock): a group corner (3+ groups, or a contour
// vertex that is not a simple point of one contour), a contour end on the mesh border, a
// non-manifold vertex and, with preserveBoundary, a mesh-border vertex never move; a collapse with
// one such endpoint goes to it; a collapse between two points of one contour stays on the old
// contour segment; an interior vertex collapsing into a contour vertex goes to the contour vertex.
// Otherwise (and in integrity mode always, but for non-manifold and preserved border vertices) the
// new vertex goes to the quadric's minimum (optimalPlacement), falling back to the best point of
// the edge when the quadric is singular or its minimum lies far from the edge.
//
// Non-manifold input (both modes), as meshoptimizer's vertex kinds: an edge with 3+ faces is a
// feature line (border-like quadrics); a vertex on such edges, or with several fans, never moves,
// but may be removed into a neighbour that stays: a manifold vertex into a non-manifold one, a
// point of a non-manifold line (1 or 2 such edges) only along the line, a vertex with several
// fans but no such edge along any edge; a junction of 3+ lines never goes. A general link
// condition refuses what would make an edge non-manifold (an edge may keep, never gain, more than
// two faces) or one face twice; the group test there is a search on the adjacency after the
// collapse (keepsGroupsWholeAcross). In paper mode these collapses keep the groups whole the same
// way (the paper's local clauses assume a manifold fan), and group boundaries never go. Next to a
// non-manifold vertex a face's quality counts as at least 0.1 in the priority, and in integrity
// mode the last face of a group (on scans: slivers on non-manifold edges) is exempt from the
// normal test (docs/group_qem.md, "Slivers and thin faces at non-manifold edges").
// Whole components: with removeComponents, a run that has no allowed collapse left above the
// target removes components made of whole groups, smallest first (GroupQemParams); with
// flipToUnblock, collapses refused by the link condition are then unblocked by edge flips inside
// one group (GroupQemParams::flipToUnblock).
//
// Error and priority follow vcglib's TriEdgeCollapseQuadric (what MeshLab's "Quadric Edge Collapse
// Decimation" runs): face-plane quadrics (area-weighted) plus border-edge quadrics weighted by
// boundaryWeight (and, in paper mode with condition 1 or with the lock, the same on group
// contours); priority = error / min(quality of the new faces, qualityThr), quality = 2 area /
// longest edge^2. Error is the quadric divided by its weight: a mean squared distance. Unlike
// vcglib we always keep the link condition (no non-manifold edge is created) and, with
// preserveNormal, refuse collapses that turn a face's normal by more than ~78 degrees (fold-overs).
//
// The loop is our own rather than vcglib's local_optimization (whose heap allocates one object per
// candidate and evaluates every candidate in full when it is pushed): flat arrays, per-vertex face
// lists in one array, a 4-ary heap of 16-byte entries, and lazy evaluation: an edge is queued at a
// cheap lower bound of its priority and judged in full (checks, placement, quality) only when it
// reaches the top; a judged entry whose neighbourhood has not changed since is executed as is.
// bench/bench_simplify.cpp times it against vcglib's TriEdgeCollapseQuadric in the same run.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "conelod/mesh/indexed_mesh.h"
#include "conelod/grouping/normal_cone.h"
#include "conelod/simplify/attribute_quadric.h"
#include "conelod/status.h"

namespace conelod {

// What keeping the groups means (see the top of this file).
//   Integrity (default): every group stays ONE non-empty edge-connected piece (a group in several
//     pieces in the input keeps no more pieces than it had) and nothing else is asked: contours and
//     group corners move and merge as any vertex, with the plain quadrics of vcglib.
//   Paper: conditions 1 and 2 of Kamiya-Suzuki-Kawachi as they are (contour-aware placement and
//     quadrics, fixed group corners).
enum class GroupMode { Integrity, Paper };
const char* ToString(GroupMode m);  // "integrity", "paper"

struct GroupQemParams {
  size_t targetFaces = 0;  // stop at this many faces or fewer; 0: no face-count target
  double maxError = 0;     // no collapse whose error (RMS distance of the merged quadric,
                           // as a FRACTION of the bounding-box diagonal) exceeds this; 0: none
  GroupMode mode = GroupMode::Integrity;
  bool condition1 = true;             // no group is split or destroyed (paper: condition 1; integrity:
                                      // the exact integrity test; false in both: plain QEM)
  bool condition2 = true;             // no vertex where 3 or more groups meet is created (paper mode only)
  bool keepCones = false;             // refuse collapses that turn a face's normal out of its group's coneBound
  std::vector<NormalCone> coneBound;  // keepCones: per group id (primary grouping), the cone every
                                      // changed face normal of the group must stay in (axis: the group's
                                      // input cone axis, half-angle: its level's threshold); ids past
                                      // the end or empty cones: no bound
  std::vector<std::vector<NormalCone>> coarserConeBound;  // keepCones: the same per coarser grouping
                                                          // (SimplifyPreservingGroups' coarserGroups, in order), so
                                                          // that a hierarchy's later levels start inside their bounds

  bool lockGroupBoundaries = false;  // no vertex on a group boundary moves
  double qualityThr = 0.3;           // new faces below this quality are penalised (0: no penalty), as vcglib
  bool optimalPlacement = true;      // quadric minimum; false: the better endpoint
  bool preserveBoundary = false;     // mesh-border vertices never move
  double boundaryWeight = 1.0;       // weight of the border (and group-contour) quadrics
  bool preserveNormal = true;        // refuse collapses that flip a face (normal turning > ~78 degrees)
  // An edge whose two faces lie nearly back to back (normals more than 120 degrees apart) is the
  // rim of a sheet: each face adds the plane through it orthogonal to the face, as at a border
  // (weighted by boundaryWeight). The LOD build turns it on: each of its levels is simplified from
  // the one below with fresh quadrics, and without these planes a sheet's rim slides into it at no
  // cost, level after level (the vrip dragon, welded: its levels 1-7 1.25-1.93x our one-piece
  // collapse at their counts, 0.94-1.27x with them). The one-piece collapse keeps the input's
  // quadrics and leaves it off (with it: the res2 dragon at 10 % 8 % further from its input).
  bool foldPlanes = false;
  // When no allowed collapse is left above targetFaces: remove whole connected components whose
  // every group (in every grouping) lies inside them, smallest (bounding-box diagonal) first,
  // until the target is reached (passing over one that would land below the target while smaller
  // ones may still land on it). No group is split; the removed groups vanish whole. The CLI and
  // the filter turn it on (--keep-components / KeepComponents refuse it); the LOD builders do not.
  bool removeComponents = false;
  // When no allowed collapse is left above targetFaces (after removeComponents): unblock collapses
  // refused by the link condition by flipping the edge to their extra common neighbour (integrity
  // mode only; never in paper mode, with attributes or in a GroupQemRegion). A flip only turns the
  // diagonal of two faces of one group (in every grouping) whose quad is nearly flat (each new
  // normal within ~78 degrees of each old one), never creates an edge that exists, and is undone
  // unless the collapse it was made for is then allowed and done; the collapses it frees follow
  // in the queue. Runs that reach their target are unchanged. The CLI and
  // the filter turn it on; the LOD builders and the hierarchy do not.
  bool flipToUnblock = false;
  // Collapse order. false (the struct's default, what the LOD build and the hierarchy keep): one
  // greedy queue, the cheapest allowed collapse first. true (`conelod simplify`'s and the filter's
  // default): in passes, as meshoptimizer's simplifier: every edge ranked at its lower bound and
  // sorted, then collapsed in that order while neither endpoint has survived a collapse of the same
  // pass and its full priority stays under 1.5x the rank of the pass's estimated last collapse; the
  // next pass ranks the edges left again. When at most an eighth of the live faces is left to
  // remove, or a pass stalls (under a sixth of its goal), the queue goes on from the state reached,
  // so that the run ends, and stops at a floor, as the queue's. Every check (groups, topology,
  // geometry) is the same; only the order, and so the output, differs. A frozen vertex's edges are
  // never ranked (the parts of partitioned_simplify.h run in passes). Ignored for a GroupQemRegion
  // with a separation (the LOD build keeps the queue).
  bool passes = false;
  // passes: a mesh of at most this many faces runs the queue alone (output for output); a larger
  // one hands over to the queue at a quarter of it (25,000 live faces by default: below that the
  // passes cost the queue's accuracy nothing measurable on the dragons, and the queue's evaluations
  // are dearer per collapse, docs/group_qem.md); 0: passes until the target is near or a stall.
  size_t queueFaces = 100000;
  // Memoryless steps (Lindstrom & Turk's memoryless simplification, once per step rather than at
  // every collapse): each time the live faces fall to this fraction of what they were at the last
  // step (the input's at first), every vertex's quadric (and attribute model) is built again from
  // the live faces, as init() builds them from the input's. A collapse's error then measures the
  // distance to the mesh of the last step, not to the input; the error nonetheless spreads better
  // (docs/group_qem.md, "Memoryless steps"; each LOD level is such a step). With passes a step
  // falls between two passes; in the queue every edge is queued again. A step is taken only where
  // a whole step follows it before the target. A maxError bound is then to the surface of the
  // last step (the LOD build's cap: each of its levels starts from the level below anyway).
  // 0: the input's quadrics to the end. OneTargetParams: kRefreshRatio (the CLI and the filter
  // keep 0 with a maxError or in paper mode: their bound is to the input).
  double refreshRatio = 0;
};

// `conelod simplify`'s and the filter's ratio (docs/group_qem.md: 0.5 and 0.7 gave less).
constexpr double kRefreshRatio = 0.8;

// What `conelod simplify` and the MeshLab filter run for one target unless told otherwise: ranked
// passes then the queue, memoryless steps (kRefreshRatio), whole components may go when stuck,
// edge flips unblock refused collapses.
GroupQemParams OneTargetParams(size_t targetFaces);
// Whether the run's bound is to the input (a maxError, or paper mode): the CLI and the filter then
// keep the input's quadrics (refreshRatio 0) unless asked.
inline bool BoundToInput(const GroupQemParams& p) { return p.maxError > 0 || p.mode == GroupMode::Paper; }

// Ok, or a message naming the bad parameter.
Status ValidateParams(const GroupQemParams& p);

struct GroupQemStats {
  size_t facesIn = 0, facesOut = 0;
  size_t collapses = 0;
  size_t passes = 0, collapsesInPasses = 0;  // GroupQemParams::passes: ranked passes run, and their collapses
  size_t evaluations = 0;                    // candidate collapses evaluated (cost of the run)
  // Evaluations refused, by the first reason found (one edge may be counted several times).
  size_t refusedTopology = 0;  // non-manifold edge/vertex, link condition, pinch
  size_t refusedCondition1 = 0;
  size_t refusedCondition2 = 0;
  size_t refusedLock = 0;       // lock group boundaries
  size_t refusedFixed = 0;      // both endpoints must stay where they are
  size_t refusedGeometry = 0;   // face flip or zero-area face
  size_t refusedCone = 0;       // keepCones: a normal would leave its group's cone
  double maxCollapseError = 0;  // largest error of a collapse done, fraction of the bbox diagonal
  enum class Stop { TargetReached, NoMoreCollapses, Cancelled } stop = Stop::NoMoreCollapses;
  // removeComponents: what was removed (groups of the primary grouping).
  size_t componentsRemoved = 0, groupsRemoved = 0, facesRemovedWithComponents = 0;
  // Components that removeComponents could have removed but did not (it is off, or the target
  // was reached first).
  size_t componentsRemovable = 0;
  // flipToUnblock: edges flipped, and the collapses they unblocked (each with its flips).
  size_t edgeFlips = 0, collapsesUnblocked = 0;
  // Stopped above targetFaces (the floor: facesOut): every edge left, judged once more, by
  // verdict (index: int(CollapseVerdict)); edgesOverMaxError: allowed but over maxError.
  size_t edgesLeft = 0, edgesLeftBy[9] = {}, edgesOverMaxError = 0;
};
// Why a run stopped above its target, in one line ("every remaining collapse would split or
// remove a group (12 edges), ..."): the CLI's message and the filter's log. Empty when it did not.
std::string DescribeFloor(const GroupQemStats& s, const GroupQemParams& p);

struct GroupQemResult {
  IndexedMesh mesh;                    // the simplified mesh (vertices in input order, minus the removed;
                                       // no face that uses a vertex twice, even if the input has some)
  std::vector<uint32_t> sourceFace;    // per output face: the input face it is (collapses only remove faces)
  std::vector<uint32_t> sourceVertex;  // per output vertex: the input vertex kept at it (moved, possibly)
  GroupQemStats stats;
};

// A part of a larger mesh, simplified on its own (hierarchical_simplification.cpp simplifies the
// parts of a large level side by side). Every face around a vertex that is not frozen is in the
// part, so its quadric, fan, groups and conditions are the same as in the whole mesh; a frozen
// vertex (one shared with another part) never moves and no edge at it collapses, so the parts
// never touch each other's faces.
struct GroupQemRegion {
  std::vector<uint8_t> frozenVertex;  // per vertex of the part: 1 = shared with another part
  double diagonal = 0;                // the whole mesh's bounding-box diagonal (errors and ties are
                                      // relative to it); 0: the part's own
  // > 0 (model units): a collapse never makes its vertex a neighbour of two distinct vertices
  // closer than this to each other that were not both neighbours of one of its two endpoints,
  // nor places it this close to a neighbour. The LOD build gives
  // its file's grid cell (lod_dag.cpp): two vertices in one cell are one vertex once read, and a
  // vertex joined to both would use the edge to that cell 3 or 4 times (the dragon's seams hold
  // distinct vertices 1.7e-6 apart, one cell).
  double separation = 0;
};

// Simplifies `mesh` until targetFaces (and/or maxError) is reached or no allowed collapse is left.
// faceGroup: one group id (>= 0) per face. `coarserGroups` (optional): further groupings whose
// groups condition 1 must also keep intact (hierarchical simplification: a finer level's groups
// being intact does not keep their unions connected). On bad input `out` is left empty; on
// cancellation by `progress` the run stops at once and `out` holds the valid mesh reached so far
// (Status::Cancelled): callers that promise to leave the user's data untouched just drop it.
// `region` (optional): `mesh` is a part of a larger mesh (see GroupQemRegion). `attributes`
// (optional, Init on `mesh`): colour, normals and texture coordinates carried along
// (attribute_quadric.h): their cost joins each collapse's priority, seam vertices stay, and the
// models merge on every collapse; AttributeQuadrics::Evaluate then gives the output's attributes.
Status SimplifyPreservingGroups(const IndexedMesh& mesh, const std::vector<int>& faceGroup,
                                const GroupQemParams& params, GroupQemResult& out,
                                const Progress& progress = Progress(),
                                const std::vector<const std::vector<int>*>& coarserGroups = {},
                                const GroupQemRegion* region = nullptr, AttributeQuadrics* attributes = nullptr);
// The same, taking `mesh` over: it is freed once the simplifier has its own copy (before the
// collapses), so that it does not sit under the collapse's arrays (issue 25's memory target:
// `conelod simplify` keeps no input mesh through the run). `mesh` is left empty.
Status SimplifyPreservingGroups(IndexedMesh&& mesh, const std::vector<int>& faceGroup, const GroupQemParams& params,
                                GroupQemResult& out, const Progress& progress = Progress());

// The verdict on one collapse, as the simplifier would judge it on the unmodified mesh (tests,
// diagnostics). Checks run in this order: topology, lock, condition 1 (in integrity mode: the
// integrity test), condition 2 (paper mode), placement (FixedEndpoints: both endpoints must stay
// where they are), geometry, cone (keepCones).
enum class CollapseVerdict {
  Allowed,
  NotAnEdge,
  Topology,
  LockedBoundary,
  Condition1,
  Condition2,
  FixedEndpoints,
  Geometry,
  Cone
};
const char* ToString(CollapseVerdict v);
// Why the simplification stopped, as the CLI and the plugin print it: "target reached", ...
const char* ToString(GroupQemStats::Stop s);
CollapseVerdict EvaluateCollapse(const IndexedMesh& mesh, const std::vector<int>& faceGroup,
                                 const GroupQemParams& params, uint32_t v1, uint32_t v2,
                                 vcg::Point3f* newPosition = nullptr);

}  // namespace conelod
