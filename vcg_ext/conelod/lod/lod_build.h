// ConeLOD — building the streamable level-of-detail file (.clod): the cluster DAG and its writer.
// What a node, a group and a cut are, and how a file is read and refined: lod_read.h.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <vcg/space/point3.h>

#include "conelod/grouping/cone_grouping.h"
#include "conelod/lod/lod_read.h"
#include "conelod/simplify/hierarchical_simplification.h"
#include "conelod/mesh/indexed_mesh.h"
#include "conelod/mesh/weld.h"
#include "conelod/status.h"

namespace conelod {

// ---------------------------------------------------------------------------------------------
// Writing

struct LodBuildParams {
  // Level-0 clusters: cone half-angle limit grouping.coneThresholdDeg, multiplied by
  // grouping.thresholdGrowth at each level above (at most 90 degrees); the other grouping
  // fields are not used by the DAG.
  ConeGroupingParams grouping;
  // qem: the collapse's options for every group (targetFaces is set per group, frozen borders
  // are added); levelRatio: each group of the fine levels targets this fraction of its faces
  // (coarseLevelRatio below for the others); threads.
  HierarchicalSimplificationParams simplification;
  // The coarse levels (at most 3/8 of the input's faces: level 2, about a quarter, and above)
  // simplify each group to max(levelRatio, coarseLevelRatio) of its faces; 0: levelRatio at every
  // level. A cut mixes two neighbouring levels, and with errors ~ 1 / faces such a mix is up to
  // 1.19x one simplification at its count at a ratio of 0.5, 1.10x at 0.6 (docs/lod_viewer.md,
  // "Fidelity of cuts"); the file holds the sum of the levels, so 0.6 on the coarse levels only
  // (where the cuts of 2-25 % of the input lie) costs about 1.06x the uniform 0.5's bytes, where
  // 0.6 at every level cost 1.22-1.27x.
  double coarseLevelRatio = 0.6;
  // The ratio (at least levelRatio) on the top levels (those grouped by topGroupClusters, below)
  // until the top is simplified in whole parts (which keep coarseLevelRatio); 0: coarseLevelRatio
  // there too. Not the default: 0.7 took the bunny's 5 % cut from 1.13-1.19x our static collapse
  // at its count to 1.08-1.10x over four orders of its faces, but moved the small cuts' fill and
  // their view dependence by chance (at 0.65, 0.68, 0.7 and 0.72 one or two of BunnyLod's fill and
  // view tests fail: docs/lod_viewer.md, "A gentler ratio on the top levels").
  double topLevelRatio = 0;
  size_t clusterFaces = 128;  // target faces of a cluster (a node), at every level
  int groupClusters = 12;     // clusters gathered into one group before simplification
  // Clusters per group on the fine levels (those simplified at levelRatio: above 3/8 of the
  // input's faces, levels 0 and 1); 0: groupClusters. Larger groups lock a smaller share of their
  // faces: level 2, where the cuts at 25 % of the input lie, went from 1.16-1.18x our static
  // collapse at its count with 12 to 1.04-1.08x with 24 (the armadillo and the bunny); their
  // larger steps are taken only by cuts above about a quarter of the input.
  int fineGroupClusters = 24;
  // Clusters per group on a fine level that still holds 32 groups of this many (262,144 faces at
  // 128 faces a cluster, so on inputs of about half a million faces and more); 0: never. A view
  // still chooses among many regions there, and the larger groups free more border: the welded
  // dragon's 25 % cuts (mostly level 2) went from 1.10-1.16x our static collapse at their count to
  // 1.07-1.10x over three builds, its file 6,944,244 -> 6,870,466 bytes; the bunny's and the
  // armadillo's levels are under that size.
  int largeFineGroupClusters = 64;
  // Clusters per group on a coarse level (below the fine ones, above the top) that still holds
  // largeGroupCount groups of this many (24,576 faces at 128 faces a cluster: inputs of more than
  // about 100,000 faces, whose level 2 is a quarter of them); 0: never. As on the fine levels, larger
  // groups lock a smaller share of their faces: the dragon's levels 3-7 went from 1.18-1.36x our
  // static collapse at their counts (level 3, from groups of 12: 1.35x) to 1.05-1.11x, its 2 / 5 / 10
  // / 25 % cuts from 1.11 / 1.20 / 1.10 / 1.16x to 1.08 / 1.09 / 1.07 / 1.16x (bench/lod_fidelity
  // --cuts, ordered by the largest distance, version 8), the file 6,874,726 -> 6,816,609 bytes. On
  // the levels where a view still has a few groups to choose among (under 8 of them) the groups stay
  // small: with 24 on every coarse level the dragon's 2 % cut filled 95.6 % of its budget (99.4 %
  // so).
  int largeGroupClusters = 24;
  int largeGroupCount = 8;
  // Clusters per group on the top levels (under the faces of 4 groups of groupClusters clusters:
  // 6,144 by default; or under topFaceShare of the input's faces); 0: groupClusters. Smaller
  // groups there refine the small cuts in smaller steps, so that they fill their budget (the
  // bunny's 2 % and 5 % cuts filled 97.8 / 98.0 % with 12, 98.1 / 99.9 % with 6), and a small
  // mesh's top levels are more than one group each.
  int topGroupClusters = 6;
  // The levels under this fraction of the input's faces are top levels too (in [0, 1]; 0: by the
  // face count above alone). At 0.06 the dragon's levels from 48,595 faces down (8 of them above
  // 6,144 faces) were groups of 6: their locked borders a larger share, levels 7-9 1.23-1.31x
  // our static collapse at their count and the 2 % cut (level 7) 1.29x; by the count alone
  // (groups of 12 there) the 2 % cut is 1.07x. A mesh of under 102,400 faces has the same top
  // either way (6 % of it is under 6,144 faces): the bunny's and the armadillo's files are the same.
  double topFaceShare = 0;
  // Below the top levels, a group that greedy growth leaves under half its clusters (hemmed in by
  // full groups) joins the neighbouring group it shares the most edges with, up to 3 / 2 of the
  // clusters a group gathers (lod_dag.cpp, MergeSmallGroups). Without it the dragon's level-0
  // groups average 8 clusters of 24 and its levels 1 and 2 are 1.38x and 1.33x our static
  // collapse at their counts; with it 15 clusters, 1.23x and 1.13x, and the file 0.95x the size.
  bool mergeSmallGroups = true;
  // Grouping a level's clusters, an edge two clusters share weighs this many edges when the two
  // were made from different groups of the level below (that level's locked border), so that the
  // groups straddle it and free it; 1: every shared edge alike.
  double lockedBorderWeight = 1;
  // No collapse in a group costs more than this (RMS distance of its quadric, fraction of the
  // diagonal; the smaller of this and simplification.qem.maxError when that is set): a group
  // whose locked border leaves no cheap collapse stops short of levelRatio rather than fold.
  // Once a whole level no longer shrinks under the cap, each small connected part becomes one
  // group (nothing locked) and the cap is doubled once; a top still above 1 % of the input goes
  // on without it (lod_dag.cpp). The dragon's levels under 16,000 faces: 0.39-0.47x MeshLab's QEM
  // at the same face count with 0.002, 0.41-0.70x with 0.004, 0.8-4.7x without a cap.
  double maxGroupError = 0.002;
  // A group's collapse takes memoryless steps at this ratio (GroupQemParams::refreshRatio; the cap
  // above is then to the surface of the step; conelod lod build --refresh-ratio): a group simplified
  // to 0.5 or 0.6 of its faces builds its quadrics again from its surface at 0.8 of them (and at
  // 0.64 on the way to 0.5). Cuts of the bunny, the armadillo and the dragon at 2 / 5 / 10 / 25 %
  // (bench/lod_fidelity --cuts, ordered by the largest distance and before largeGroupClusters, as
  // in version 8): 1.10x our one-piece collapse at their counts in the geometric
  // mean, 1.13x with 0 (the level's quadrics to the group's end); 0.85 and 0.9: 1.08x, but the
  // bunny's screen-space cuts lose their view dependence at 30 % (BunnyLod,
  // SmallBudgetsRefineWhereTheEyeLooks) and with 0.85 its 10 % cut fills 97.7 % of its budget
  // (docs/lod_viewer.md, "Memoryless steps in the groups").
  double refreshRatio = 0.8;
  // The positions' quantization (lod_read.h, LodGrid): no vertex moves by more than this fraction
  // of the diagonal of the box of the DAG's positions (kMinLodPrecision..kMaxLodPrecision).
  double precision = kDefaultLodPrecision;
  // Spatial chunks (conelod lod build --memory; docs/scale.md): 0 builds the DAG over the whole
  // mesh (today's build). Else the faces are split into kd chunks of at most chunkFaces faces (by
  // face centroid, median splits on the longest axis, every leaf at the same depth); the level-0
  // clusters and the groups of the fine levels stay within a chunk, so a chunk's border is locked
  // while its levels are built, and sibling chunks merge one kd depth per level (sooner when a
  // level no longer shrinks), which frees their common border. A mesh of at most chunkFaces faces
  // is one chunk: its file is byte for byte the unchunked one.
  size_t chunkFaces = 0;
  // With attributes (LodAttributes): how much an attribute change costs a collapse, as
  // conelod simplify's --attribute-weight (attribute_quadric.h); >= 0. Unused without attributes.
  double attributeWeight = 1.0;
};

// --memory: the budget's smallest value, and the faces of a chunk per byte of it (a chunk's own
// working set, about 200 bytes a face measured, is then a tenth of the budget).
constexpr uint64_t kLodMinMemoryBytes = uint64_t(16) << 20;
constexpr uint64_t kLodMemoryBytesPerChunkFace = 2048;
inline size_t LodChunkFacesForMemory(uint64_t bytes) { return size_t(bytes / kLodMemoryBytesPerChunkFace); }

// The cluster DAG before it is written (BuildLodDag), level 0 = the input.
struct LodDag {
  std::vector<vcg::Point3f> positions;  // global vertices: [0, input vertices) are the input's
  size_t inputVertices = 0;
  struct Level {
    std::vector<std::array<uint32_t, 3>> faces;  // global vertex ids
    std::vector<uint32_t> faceCluster;           // per face: its cluster (index within the level)
    std::vector<int> clusterGroup;               // per cluster: its group at this level (-1: a root)
    std::vector<int> clusterCreator;  // per cluster: the group of the level below it was made from (-1 at level 0)
    std::vector<float> clusterError;  // per cluster: its error (the creator group's); 0 at level 0
    std::vector<float> groupError;    // per group of this level: error of the clusters made from it
    // Per cluster above level 0: its creator group's typical distance (the geometric mean of the
    // RMS and the largest distance from the group's vertices to its simplified faces, not
    // accumulated; what the refinement by error in model units orders by); empty at level 0.
    std::vector<float> clusterTypical;
    size_t clusterCount() const { return clusterGroup.size(); }
  };
  std::vector<Level> levels;
  LodAttributes attributes;  // per global vertex (streams as the input's; empty: geometry only)
};

// Builds the DAG. Errors are geometric, in model units: a group's error is the largest distance
// from its vertices to its simplified surface plus the largest error of its clusters, so a
// node's error is at least its children's.
// `attributes` (optional, per vertex of `mesh`): carried through every level (LodAttributes).
Status BuildLodDag(const IndexedMesh& mesh, const LodBuildParams& params, LodDag& out,
                   const Progress& progress = Progress(), size_t* chunks = nullptr,
                   const LodAttributes* attributes = nullptr);

struct LodBuildStats {
  size_t inputVertices = 0, inputFaces = 0;  // of the mesh the DAG was built on (BuildLodFile: welded)
  size_t mergedVertices = 0;                 // BuildLodFile: input vertices welded into another (weld.h)
  size_t droppedVertices = 0;                // BuildLodFile: unreferenced input vertices left out
  size_t chunks = 1;                         // spatial chunks of the build (LodBuildParams::chunkFaces)
  int levels = 0;                            // node levels, level 0 (the input) included
  std::vector<size_t> levelFaces;            // faces per node level, [0] = the input's
  std::vector<size_t> levelNodes;            // nodes per node level
  size_t nodes = 0;
  uint64_t fileBytes = 0;
  // Of fileBytes: the node records (HIER), and the compressed positions, triangles and global
  // vertex ids of the geometry (GEOS); quantizationError: the grid's bound, model units.
  uint64_t recordBytes = 0, positionBytes = 0, triangleBytes = 0, vertexIdBytes = 0;
  uint64_t colorBytes = 0, normalBytes = 0;  // the attribute streams (versions 5, 6), compressed
  uint64_t texCoordBytes = 0;                // the UV stream (bit 8), compressed
  uint64_t textureBytes = 0;                 // the texture image stored in the file (TEXR), as it is
  size_t attributeConflicts = 0;  // BuildLodFile: welded vertices whose attributes differed (the lowest kept)
  double quantizationError = 0;
  double groupingSeconds = 0, simplifySeconds = 0, writeSeconds = 0,
         seconds = 0;  // grouping: the
                       // level-0 clusters; simplify: the DAG's other levels
};

// Writes the file of a DAG built by BuildLodDag from `mesh`, positions quantized with `precision`
// (LodBuildParams::precision). Streams node by node: the file is never held in memory. On failure
// no file is left at `path`. The nodes are encoded on `threads` threads (0: one per core; BuildLodFile
// passes LodWriterThreads): the file is the same byte for byte for every count.
Status WriteLodFile(const IndexedMesh& mesh, const LodDag& dag, const std::string& path, LodBuildStats* stats = nullptr,
                    const Progress& progress = Progress(), double precision = kDefaultLodPrecision, int threads = 0);

// The writer's threads in a build: params.simplification.threads (0: one per core); with
// params.chunkFaces (--memory) at most one per 2,048 faces of a chunk (4 at 16M, 16 at 64M): each
// thread holds about 0.4 MiB (its codecs' buffers, its share of the window of encoded nodes), so
// that they take at most a tenth of the budget.
int LodWriterThreads(const LodBuildParams& params);

// Welds the mesh's vertices by position (WeldByPosition, weld.h: coincident vertices become one,
// unreferenced ones are left out), builds the DAG of the welded mesh and writes it: level 0 of the
// file is the welded mesh. BuildLodDag and WriteLodFile take their mesh as it is. The mesh must
// pass RequireValidForFaces. `attributes` (optional, per vertex of `mesh`): a welded vertex takes
// its representative's (the lowest input vertex at its position; stats->attributeConflicts counts
// the vertices whose values differed from it); the file then carries their streams.
Status BuildLodFile(const IndexedMesh& mesh, const LodBuildParams& params, const std::string& path,
                    LodBuildStats* stats = nullptr, const Progress& progress = Progress(),
                    const LodAttributes* attributes = nullptr);
// The same file from a mesh it takes (welded in place, then its positions and faces become the
// DAG's level 0: no copy of the input is held beside the DAG); `mesh` is left empty. With
// attributes the mesh is welded by a copy (the representatives give the welded vertices' values).
// With params.chunkFaces (`lod build --memory`) both overloads spill each finished level to a
// temporary folder beside `path` and write the file from there (lod_spill.h, docs/scale.md): the
// same bytes, the faces of one or two levels in memory; the folder is removed before they return.
Status BuildLodFile(IndexedMesh&& mesh, const LodBuildParams& params, const std::string& path,
                    LodBuildStats* stats = nullptr, const Progress& progress = Progress(),
                    const LodAttributes* attributes = nullptr);

// `conelod lod build --memory` from a PLY file (docs/scale.md; lod_stream.cpp): BuildLodFile of
// the geometry ReadPly reads, with params.chunkFaces, without the input's faces or level 0 ever
// whole in memory: the PLY is read streaming (its positions held: 12 bytes a vertex), welded as
// BuildLodFile welds, and its faces are written to one file per kd chunk in the temporary folder
// beside `path`; each chunk's level 0 and the part of level 1 it makes are built from its file
// (BuildLodDagFromChunks), then the levels above as BuildLodFile builds them. The kd split planes
// come from a sample of the face centroids (every s-th face, s = ceil(faces / sampleFaces); 0:
// min(2^20, 16 chunkFaces)), so the chunks hold about chunkFaces faces; with every face in the
// sample the chunks are KdChunks's and the file is BuildLodFile's with the same params byte for
// byte (when its level 0 shrinks under the chunks' borders, as it does but on tiny chunks). An
// input of one chunk is read back whole and takes BuildLodFile. Vertex attributes are not read
// (a caller that keeps them uses BuildLodFile). `readError`: set to the reader's message when the
// input could not be read as a PLY (nothing else is then wrong).
Status BuildLodFileFromPly(const std::string& input, const LodBuildParams& params, const std::string& path,
                           LodBuildStats* stats = nullptr, const Progress& progress = Progress(),
                           std::string* readError = nullptr, size_t sampleFaces = 0);
// The face count a PLY file's header declares (0 when it cannot be read); vertexAttributes: set when
// its vertex element has colour, normals or texture coordinates, or its faces texcoord lists.
uint64_t PlyFaceCount(const std::string& path, bool* vertexAttributes = nullptr);

}  // namespace conelod
