// ConeLOD — the streamable level-of-detail file (.clod), its on-demand reader, and view-dependent
// refinement.
//
// Kamiya, Suzuki, Kawachi, "LODs for efficient displaying triangle meshes", §7-9 (SPEC §4): the
// model is grouped by normal cones (cone_grouping.h), simplified once per hierarchy level while
// keeping the groups intact (hierarchical_simplification.h), and written as a file of chunks.
// A viewer opens it reading only the header, the top of the hierarchy and the coarsest geometry,
// draws that at once, and refines while the user is idle: breadth-first, in the order of the
// priority f(g), never letting adjacent groups differ by more than one level, back-facing groups
// (three-state cone test) last. Geometry is read group by group on demand and can be evicted, so
// resident memory follows what is drawn, not the model's size. The byte layout is documented in
// lod_format.md beside this file.
//
// Nodes. A node is one group drawn at one level of detail:
//   node level k >= 1: group g of hierarchy level k, with the faces of simplified level k that
//                      belong to g;
//   node level 0:      group g of hierarchy level 1, with the input's own faces of g (the original
//                      geometry; extracting every level-0 node gives back the input mesh).
// Children of a level-k node (k >= 2) are the level-(k-1) nodes of g's child groups; the one child
// of a level-1 node is the level-0 node of the same group; level-0 nodes are leaves. The roots are
// the nodes of the top hierarchy level. Every input face is covered by exactly one node of any cut.
// Node ids are dense (0 .. nodeCount-1), coarsest level first; a node's children have consecutive ids.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <vcg/space/box3.h>
#include <vcg/space/point3.h>

#include "conelod/cone_grouping.h"
#include "conelod/group_hierarchy.h"
#include "conelod/hierarchical_simplification.h"
#include "conelod/indexed_mesh.h"
#include "conelod/normal_cone.h"
#include "conelod/status.h"

namespace conelod {

// ---------------------------------------------------------------------------------------------
// Writing

struct LodBuildParams {
  ConeGroupingParams grouping;
  HierarchicalSimplificationParams simplification;
};

struct LodBuildStats {
  size_t inputVertices = 0, inputFaces = 0;
  int levels = 0;                   // node levels, level 0 (the input) included
  std::vector<size_t> levelFaces;   // faces per node level, [0] = the input's
  std::vector<size_t> levelNodes;   // nodes per node level
  size_t nodes = 0;
  uint64_t fileBytes = 0;
  double groupingSeconds = 0, simplifySeconds = 0, writeSeconds = 0, seconds = 0;
};

// Writes the file for a mesh whose hierarchy and simplified levels are already built (levels[k-1]
// preserves hierarchy level k). Streams chunk by chunk: the file is never held in memory. On
// failure no file is left at `path`.
Status WriteLodFile(const IndexedMesh& mesh, const GroupHierarchy& hierarchy,
                    const std::vector<SimplifiedLevel>& levels, const std::string& path,
                    LodBuildStats* stats = nullptr, const Progress& progress = Progress());

// Groups, simplifies and writes. The mesh must pass the grouping's input checks.
Status BuildLodFile(const IndexedMesh& mesh, const LodBuildParams& params, const std::string& path,
                    LodBuildStats* stats = nullptr, const Progress& progress = Progress());

// ---------------------------------------------------------------------------------------------
// Reading

struct LodNode {
  int level = 0;                 // node level (0 = original geometry)
  uint32_t group = 0;            // group index within its hierarchy level (level 0: the level-1 group)
  int64_t parent = -1;           // node id; -1 for a root
  uint32_t firstChild = 0;       // children are node ids firstChild .. firstChild+childCount-1
  uint32_t childCount = 0;
  std::vector<uint32_t> neighbours;  // node ids of the same level whose input faces share an edge with ours
  NormalCone cone;               // exact minimal cone of the normals of THIS node's faces
  vcg::Point3f center;           // bounding sphere of this node's vertices
  float radius = 0;
  uint32_t faceCount = 0;
  uint32_t vertexCount = 0;
  float error = 0;               // upper estimate of this node's deviation from the input, model units
};

// A node's geometry as read from the file.
struct LodGeometry {
  std::vector<uint32_t> vertexIds;              // per local vertex: its index in its level's shared
                                                //   vertex array (level 0: the input vertex index)
  std::vector<vcg::Point3f> positions;          // per local vertex
  std::vector<std::array<uint32_t, 3>> faces;   // local vertex indices
  size_t bytes() const;
};

struct LodFileInfo {
  uint32_t version = 0;
  vcg::Box3f box;                   // of the input's used vertices
  int levels = 0;                   // node levels, level 0 included
  uint64_t inputVertices = 0, inputFaces = 0;
  std::vector<uint64_t> levelFaces;  // faces per node level
  std::vector<uint64_t> levelNodes;  // nodes per node level
  uint64_t nodeCount = 0;
  uint64_t fileBytes = 0;
};

// Reads a .clod file on demand. Every read is bounds- and checksum-checked: a truncated or
// corrupt file gives a Status naming what is wrong, never a crash or an allocation larger than
// the file could justify. Not thread-safe.
class LodReader {
 public:
  // Reads the header, the offset index, the node records of the roots and the roots' geometry.
  static Status Open(const std::string& path, std::unique_ptr<LodReader>& out);
  // The same from a file image in memory (tests, the fuzz target); the reader keeps `bytes`.
  static Status OpenMemory(std::vector<uint8_t> bytes, std::unique_ptr<LodReader>& out);
  ~LodReader();

  const LodFileInfo& info() const;
  const std::vector<uint32_t>& roots() const;

  // Node records are read on demand: a node's record is available once its parent's children
  // were loaded (roots: at Open).
  bool hasNode(uint32_t id) const;
  const LodNode& node(uint32_t id) const;  // requires hasNode(id)
  Status LoadChildren(uint32_t id);        // makes the records of id's children available
  Status LoadNode(uint32_t id);            // makes one record available (and its ancestors')
  uint32_t levelOfNode(uint32_t id) const;  // from the id alone (ids are dense per level); id < nodeCount

  Status LoadGeometry(uint32_t id);               // reads and keeps the node's geometry
  const LodGeometry* geometry(uint32_t id) const;  // null when not loaded
  void EvictGeometry(uint32_t id);

  // Bytes the reader holds now: node records, index, loaded geometry, buffers.
  size_t residentBytes() const;

 private:
  LodReader();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// ---------------------------------------------------------------------------------------------
// View-dependent refinement

struct LodView {
  vcg::Point3d eye{0, 0, 0};       // perspective camera position (model coordinates)
  bool orthographic = false;       // true: an orthographic view looking along viewDir
  vcg::Point3d viewDir{0, 0, -1};  // unit; orthographic only
  size_t faceBudget = 0;           // at most this many faces in the cut (the roots may exceed it)
  bool cullBackFacing = true;      // back-facing nodes are refined only after every other node
                                   // (and, at each level, nodes whose cone axis faces away after
                                   // those facing the eye; lod_refine.cpp says why); false:
                                   // no node is culled or deferred
};

// The paper's refinement priority f(g) in [0,1] (larger = refine first): with a = angle(e, n),
// e from the node's centre to the eye (orthographic: -viewDir), n the cone axis, c the cone
// half-angle: (1 - cos(a + c)) / 2 when a + c < pi, else 1.
double RefinementPriority(const LodNode& node, const LodView& view);

struct LodCut {
  std::vector<uint32_t> nodes;   // covers every input face exactly once
  std::vector<uint8_t> culled;   // per entry of `nodes`: 1 when the whole node faces away from the view
  size_t faces = 0;              // faces of all nodes of the cut
  size_t drawnFaces = 0;         // faces of the nodes not culled
  size_t groupsDrawn = 0, groupsCulled = 0;
  int maxLevelDifference = 0;    // over pairs of adjacent nodes of the cut
  size_t refinements = 0;        // nodes replaced by their children so far
};

// Incremental refinement, for a viewer's idle time: Start() resets the cut to the roots, each
// Step() refines a few more nodes (reading their geometry), Done() tells when the budget or the
// finest level is reached. Geometry of nodes that left the cut is evicted.
class LodRefiner {
 public:
  explicit LodRefiner(LodReader& reader);
  ~LodRefiner();
  Status Start(const LodView& view);
  Status Step(size_t maxRefinements);
  bool Done() const;
  const LodCut& cut() const;  // culled flags and counts follow the view given to Start()

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Start() then Step() until Done().
Status RefineLod(LodReader& reader, const LodView& view, LodCut& cut);

// The cut's geometry as one mesh, vertices shared within a level (so a cut of level-0 nodes gives
// back the input mesh's faces and vertex positions). includeCulled = false drops culled nodes.
// faceLevel / faceNode (optional): per output face, its node level / node id.
Status ExtractCutMesh(LodReader& reader, const LodCut& cut, bool includeCulled, IndexedMesh& out,
                      std::vector<int>* faceLevel = nullptr, std::vector<uint32_t>* faceNode = nullptr);

}  // namespace conelod
