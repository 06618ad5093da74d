// ConeLOD — hierarchical simplification: one simplified mesh per level of a group hierarchy.
//
// Kamiya, Suzuki, Kawachi, "LODs for efficient displaying triangle meshes" (§6-7, fig. 12): level
// k of the LOD is the mesh simplified while preserving the groups of hierarchy level k, and each
// level is coarser than the one below (the paper's bunny gave 8 levels). We build the levels as a
// chain: level 1 simplifies the input, level k+1 simplifies level k further, each with the
// group-preserving collapse of group_qem.h. The groups of level k are preserved by condition 1 for
// level k AND for every coarser level above it: intact fine groups do not keep their unions (the
// coarser groups) connected, so without that a later level would start from broken groups.
//
// Speed (BEYOND the paper): a large level is cut into parts along the contours of coarse groups
// (a median cut of the groups' centroids, along the longest or the second-longest axis by level,
// so that consecutive levels cut in different places) and the parts are simplified on several
// threads. Only the vertices on the cuts are held in place for that level; every other vertex
// sees its whole neighbourhood, so its collapses are judged exactly as in one piece. The cut into
// parts depends on the mesh only, never on the number of threads: the output is deterministic.
#pragma once

#include <cstdint>
#include <vector>

#include "conelod/grouping/group_hierarchy.h"
#include "conelod/mesh/attributes.h"
#include "conelod/simplify/group_qem.h"
#include "conelod/mesh/indexed_mesh.h"
#include "conelod/status.h"

namespace conelod {

struct HierarchicalSimplificationParams {
  GroupQemParams qem;       // conditions and quality options of every level (its targetFaces is ignored)
  double levelRatio = 0.5;  // each level targets this fraction of the faces of the level below
                            // (level 1: of the input), in (0, 1]
  // A level whose input has at least 2 x facesPerPart faces is cut into parts (2, 4 or 8, about
  // facesPerPart faces each) along the contours of coarse groups, and the parts are simplified
  // side by side, each to levelRatio of its faces; the vertices the parts share stay where they
  // are at that level (the next level cuts elsewhere). 0: never cut.
  size_t facesPerPart = 100000;
  int threads = 0;  // threads that simplify the parts; 0: one per core. The result is the
                    // same whatever the number.
};

// Colour, normals and texture coordinates carried through the levels (issue 26): each level is
// simplified with the attribute quadrics (attribute_quadric.h) of the level below's corner values,
// so its attributes are interpolated from the one below as a one-target run's are from the input,
// seams kept (a seam vertex stays or goes along its seam; its corners keep their values).
struct HierarchyAttributes {
  VertexAttributes layout;          // the channels (its `values` are not read)
  std::vector<float> inputCorners;  // per input face corner (3 f + k), layout.channels() values each
  double weight = 1.0;              // AttributeQuadrics::Init's weight (conelod simplify --attribute-weight)
  bool seamMoves = false;           // AttributeQuadrics::AllowSeamMoves (conelod simplify: on)
};
struct SimplifiedLevel {
  int level = 0;  // the hierarchy level (1-based) whose groups it preserves
  IndexedMesh mesh;
  std::vector<uint32_t> sourceFace;    // per face: the input face it is
  std::vector<uint32_t> sourceVertex;  // per vertex: the input vertex kept at it (moved, possibly)
  std::vector<int> faceGroup;          // per face: its group at `level`
  size_t targetFaces = 0;
  GroupQemStats stats;
  // With HierarchyAttributes: per face corner (3 f + k), the layout's channels at the corner's
  // vertex (AttributeQuadrics::Evaluate); empty otherwise.
  std::vector<float> corner;
  size_t seamVertices = 0;  // with attributes: the level below's seam vertices (AttributeQuadrics)
};

// The part (0..parts-1) of every face of `mesh`: recursive median cuts of the groups' centroids
// (weighted by their face counts), so that every group lies in one part and the parts have about
// the same number of faces. `parity` picks each cut's axis: -1 the longest extent of the centroids
// every time; 0 / 1 the longest / the second longest first, the next cut in each half the other one.
std::vector<uint8_t> CutGroupsIntoParts(const IndexedMesh& mesh, const std::vector<int>& faceGroup, int parts,
                                        int parity);

// The threads the parts of a level run on: params.threads, or one per core when it is 0.
int SimplificationThreads(const HierarchicalSimplificationParams& params);

// One SimplifiedLevel per hierarchy level, finest first. Progress is reported on the calling thread. A level's face
// count is at most the one below it (equal when its groups allow no further collapse). On failure or cancellation `out`
// is left empty.
// `attributes` (optional): carried through every level (HierarchyAttributes; the one-piece and the
// parts' collapses alike).
Status BuildSimplifiedLevels(const IndexedMesh& mesh, const GroupHierarchy& hierarchy,
                             const HierarchicalSimplificationParams& params, std::vector<SimplifiedLevel>& out,
                             const Progress& progress = Progress(), const HierarchyAttributes* attributes = nullptr);

}  // namespace conelod
