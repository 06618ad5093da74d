// ConeLOD — the streamable level-of-detail file (.clod), its on-demand reader, and view-dependent
// refinement.
//
// Kamiya, Suzuki, Kawachi, "LODs for efficient displaying triangle meshes", §7-9, with
// the crack-free cluster DAG of Karis et al., "Nanite: a deep dive" (SIGGRAPH 2021 course) in place
// of the paper's tree of groups. The model is cut into clusters (normal-cone groups); at each level
// neighbouring clusters are gathered into groups, each group is simplified on its own with its
// outer border locked (GroupQemRegion::frozenVertex), and the simplified group is re-cut into the
// clusters of the next level. The next level gathers clusters differently, so a border locked at
// one level is freed at the next. A viewer opens the file reading only the header, the roots
// and their geometry, draws that at once, and refines while the user is idle; geometry is read
// node by node on demand and can be evicted, so resident memory follows what is drawn, not the
// model's size. The byte layout is documented in lod_format.md beside this file.
//
// Nodes. A node is one cluster of one level: level 0 holds the input's own faces (extracting every
// level-0 node gives back the input mesh). A node of level k >= 1 was made by simplifying one
// group G of level k-1: its `children` are the clusters of G, its `siblings` every cluster made
// from G (itself included), its `error` G's error. Unless it is a root it belongs to one group of
// its own level, whose error is its `parentError` and whose simplified clusters are its `parents`.
// Replacing all the siblings of a node by their children ("expanding" their group) keeps the
// cut watertight: the group's border was locked, so the children meet the rest of the cut at the
// very same vertices. Every cut reached from the roots by expansions, in any order, is
// crack-free and covers the input exactly once. Vertices carry global ids (input vertices keep
// their index; a vertex a simplification moved or made gets a new id), identical in every level
// that uses them: a cut's mesh welds by id, so no border edge and no T-junction appear between
// levels. Node ids are dense (0 .. nodeCount-1), coarsest level first.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <vcg/space/box3.h>
#include <vcg/space/point3.h>

#include "conelod/mesh/indexed_mesh.h"
#include "conelod/grouping/normal_cone.h"
#include "conelod/status.h"

namespace conelod {

// ---------------------------------------------------------------------------------------------
// Reading

struct LodNode {
  static constexpr uint32_t kNoGroup = 0xFFFFFFFFu;
  int level = 0;                   // node level (0 = original geometry)
  uint32_t group = kNoGroup;       // its group within its level; kNoGroup for a root
  std::vector<uint32_t> children;  // node ids (level - 1): the clusters of the group it was made from
  std::vector<uint32_t> siblings;  // node ids (same level): every cluster made from that group, itself included
  std::vector<uint32_t> parents;   // node ids (level + 1): the clusters made from its own group
  NormalCone cone;                 // exact minimal cone of the normals of THIS node's faces
  vcg::Point3f center;             // bounding sphere of this node's vertices
  float radius = 0;
  uint32_t faceCount = 0;
  uint32_t vertexCount = 0;
  float error = 0;        // upper estimate of this node's deviation from the input, model units
                          // (its creator group's; 0 at level 0; the same for all siblings)
  float parentError = 0;  // its own group's error (>= error); +infinity for a root
  // Version 9: its creator group's typical distance (LodDag::Level::clusterTypical; <= error, not
  // accumulated; 0 at level 0); -1 in older files (the refinement then takes error less its
  // children's largest).
  float typical = -1;
};

// The one grid every position of a file is quantized on (version 3): coordinate c of a vertex is
// stored as the integer q = round((c - origin[c]) / step), 0 <= q < 2^bits, and read back as
// float(origin[c] + q * step). One grid for the whole file, so a vertex that several nodes (of
// any levels) share decodes to the very same floats in each of them: cuts stay watertight.
struct LodGrid {
  double origin[3] = {0, 0, 0};
  double step = 1;
  uint32_t bits = 0;
  uint32_t Quantize(double c, int axis) const;  // clamped to [0, 2^bits)
  float Dequantize(uint32_t q, int axis) const { return float(origin[axis] + double(q) * step); }
  vcg::Point3f Round(const vcg::Point3f& p) const;  // Dequantize(Quantize(p))
  // Largest distance between a position inside the grid and its Round(): half a cell's diagonal
  // plus the float rounding of the decoded coordinates.
  double ErrorBound() const;
};

// The grid for positions spanning `box`: its cell is chosen so that no position moves by more than
// `precision` times the box's diagonal (ErrorBound), its bits from the box's size. precision must
// be in [1e-9, 0.01] (kMinLodPrecision, kMaxLodPrecision).
LodGrid ChooseLodGrid(const vcg::Box3f& box, double precision);
constexpr double kMinLodPrecision = 1e-9, kMaxLodPrecision = 0.01;
// Of the diagonal: the grid's own RMS (a cell / sqrt(12) across the surface, 1.6e-6) stays far
// enough below the RMS distance of the finest simplified level to the input (the dragon's level 1:
// 1.3e-5) that no level's RMS of the dragon, the bunny or the armadillo grows by 1 % (docs/lod_viewer.md).
constexpr double kDefaultLodPrecision = 5e-6;

// The texture image a textured .clod carries (its TEXR chunk, lod_format.md): the image file's
// bytes as they were read, its file name (a plain name: no folder, no control character) and
// its MIME type (image/jpeg, image/png, ...).
struct LodTexture {
  std::string name, mime;
  std::vector<uint8_t> bytes;
  bool empty() const { return bytes.empty(); }
};
constexpr size_t kMaxLodTextureNameBytes = 255;  // a texture's name or MIME type, at most
// "" when `name` may name a texture beside a mesh (a plain file name), else why not.
std::string CheckLodTextureName(const std::string& name);
// The MIME type of an image file from its first bytes (JPEG, PNG, BMP, TGA by its name, ...);
// "application/octet-stream" when unknown.
std::string LodTextureMime(const std::string& name, const std::vector<uint8_t>& bytes);

// Per-vertex attributes carried through the DAG into the file (versions 5, 6), each stream either
// empty or one value per vertex: colour as RGBA8 (stored exactly), the normal as its octahedral
// u16 x 2 code (lodfile::EncodeNormal; within kLodNormalErrorBound radians of the input's
// direction), texture coordinates as u16 x 2 over the file's UV box (EncodeLodTexCoord; within
// half a step of the box, LodTexCoordErrorBound). A simplified level interpolates them with the
// attribute quadrics of the group-preserving collapse (attribute_quadric.h); a vertex keeps its id
// only when neither its position nor its stored attributes changed.
struct LodAttributes {
  std::vector<std::array<uint8_t, 4>> colors;
  std::vector<std::array<uint16_t, 2>> normals;
  std::vector<std::array<uint16_t, 2>> texCoords;
  float uvMin[2] = {0, 0}, uvMax[2] = {0, 0};  // the UV box the texCoords codes span
  // With texCoords (building only; not stored): per vertex the lowest vertex id at the same
  // position. A texture seam's position has one vertex per (position, UV) (wedges): the DAG
  // treats them as one place (clusters, groups, frozen borders; the collapse's seams).
  std::vector<uint32_t> place;
  LodTexture texture;  // the image the coordinates refer to (optional; written to the TEXR chunk)
  bool empty() const { return colors.empty() && normals.empty() && texCoords.empty(); }
  // "" or why the streams do not fit `vertices` vertices.
  std::string Check(size_t vertices) const;
};
// Texture coordinates and their u16 codes over the box [uvMin, uvMax] (per axis: q = round((u -
// min) / (max - min) x 65535), clamped; read back as float(min + q (max - min) / 65535)).
std::array<uint16_t, 2> EncodeLodTexCoord(const float uv[2], const float uvMin[2], const float uvMax[2]);
void DecodeLodTexCoord(const std::array<uint16_t, 2>& code, const float uvMin[2], const float uvMax[2], float out[2]);
// The largest |u - Decode(Encode(u))| for u inside the box: half a step plus the float rounding.
double LodTexCoordErrorBound(const float uvMin[2], const float uvMax[2]);

// Codes of a unit normal and back (octahedral, 16 bits a coordinate; lod_format.md).
std::array<uint16_t, 2> EncodeLodNormal(const vcg::Point3f& n);
vcg::Point3f DecodeLodNormal(const std::array<uint16_t, 2>& code);
constexpr double kLodNormalErrorBound = 1e-4;  // radians (0.0057 degrees; 6.5e-5 measured)

// A node's geometry as read from the file.
struct LodGeometry {
  std::vector<uint32_t> vertexIds;             // per local vertex: its global id, the same in every
                                               //   level and node using it (the file's numbering,
                                               //   by first use, coarsest level first)
  std::vector<vcg::Point3f> positions;         // per local vertex, on the file's grid
  std::vector<std::array<uint32_t, 3>> faces;  // local vertex indices
  size_t bytes() const;
};

struct LodFileInfo {
  uint32_t version = 0;
  vcg::Box3f box;                // of the input's used vertices
  LodGrid grid;                  // the positions' quantization grid
  double quantizationError = 0;  // grid.ErrorBound(): no position is further from the DAG's
  int levels = 0;                // node levels, level 0 included
  uint64_t inputVertices = 0, inputFaces = 0;
  uint64_t globalVertices = 0;       // global vertex ids are below this
  std::vector<uint64_t> levelFaces;  // faces per node level
  std::vector<uint64_t> levelNodes;  // nodes per node level
  uint64_t nodeCount = 0;
  uint64_t fileBytes = 0;
  bool colors = false, normals = false;  // the attribute streams every node has (versions 5, 6)
  bool texCoords = false;                // the UV stream (bit 8), over uvMin..uvMax
  float uvMin[2] = {0, 0}, uvMax[2] = {0, 0};
  // The texture chunk (TEXR), when the file has one: its image's name, MIME type and size
  // (LodReader::LoadTexture reads the bytes).
  std::string textureName, textureMime;
  uint64_t textureBytes = 0;
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
  const LodNode& node(uint32_t id) const;   // requires hasNode(id)
  Status LoadChildren(uint32_t id);         // makes the records of id's children available (and
                                            //   checks they belong to the group id was made from)
  Status LoadNode(uint32_t id);             // makes one record available
  uint32_t levelOfNode(uint32_t id) const;  // from the id alone (ids are dense per level); id < nodeCount

  Status LoadGeometry(uint32_t id);                // reads and keeps the node's geometry
  const LodGeometry* geometry(uint32_t id) const;  // null when not loaded
  // The node's attributes per local vertex of its geometry (the streams the file has, versions 5, 6);
  // null when its geometry is not loaded or the file has none. Loaded and evicted with it.
  const LodAttributes* attributes(uint32_t id) const;
  void EvictGeometry(uint32_t id);
  // The texture image stored in the file (its TEXR chunk): read and checked against the chunk's
  // CRC. An error when the file has none (info().textureBytes == 0) or the chunk is corrupt.
  Status LoadTexture(LodTexture& out);

  // Bytes the reader holds now: node records, index, loaded geometry, buffers.
  size_t residentBytes() const;

 private:
  LodReader();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// ---------------------------------------------------------------------------------------------
// View-dependent refinement

// What the refinement expands first. Any order gives a crack-free cut (this header's first comment says why).
enum class LodPriority {
  ScreenError,  // the group's error projected at its nearest point (in pixels with projectionScale;
                //   without, error / distance), largest first; stops below maxPixelError
  ObjectError,  // by the error in model units, the same cut wherever the eye is: the group whose
                //   expansion removes the most squared error per face it adds first (its error
                //   accumulated by the mean: lod_refine.cpp, ObjectGain; no pixel bound); a group
                //   that does not fit the budget is passed over for smaller ones that do
  ConeFg        // the paper's f(g) (RefinementPriority) of the group's clusters, largest first
};

struct LodView {
  vcg::Point3d eye{0, 0, 0};       // perspective camera position (model coordinates)
  bool orthographic = false;       // true: an orthographic view looking along viewDir
  vcg::Point3d viewDir{0, 0, -1};  // unit; orthographic only
  size_t faceBudget = 0;           // at most this many faces in the cut (the roots may exceed it)
  bool cullBackFacing = true;      // back-facing nodes are flagged culled (not drawn) and groups
                                   // whose clusters all face away are expanded only after every
                                   // other group; the selection stays a watertight cut either way
  LodPriority priority = LodPriority::ScreenError;
  double projectionScale = 0;  // pixels per model unit at distance 1 (perspective: viewport
                               // height / (2 tan(fovy/2))) or per model unit (orthographic);
                               // 0: no screen (ScreenError then orders by error / distance)
  double maxPixelError = 1.0;  // ScreenError with projectionScale > 0: a group is expanded
                               // only while its projected error exceeds this many pixels, and
                               // groups whose clusters all face away are not expanded; 0: no
                               // pixel threshold (refine to the budget)
};

// A node's error projected on the screen at the nearest point of its bounding sphere: error /
// (distance from the eye to the sphere) x projectionScale (pixels; without a projection scale,
// error / distance); orthographic: error x projectionScale. An eye inside the sphere gives a huge
// value. The screen-space refinement expands a drawn node's group while this exceeds maxPixelError.
double ProjectedError(const LodNode& node, const LodView& view);

// The paper's refinement priority f(g) in [0,1] (larger = refine first): with a = angle(e, n),
// e from the node's centre to the eye (orthographic: -viewDir), n the cone axis, c the cone
// half-angle: (1 - cos(a + c)) / 2 when a + c < pi, else 1.
double RefinementPriority(const LodNode& node, const LodView& view);

struct LodCut {
  std::vector<uint32_t> nodes;  // covers every input face exactly once
  std::vector<uint8_t> culled;  // per entry of `nodes`: 1 when the whole node faces away from the view
  size_t faces = 0;             // faces of all nodes of the cut
  size_t drawnFaces = 0;        // faces of the nodes not culled
  size_t groupsDrawn = 0, groupsCulled = 0;
  int maxLevelDifference = 0;  // over pairs of cut nodes sharing a vertex
  size_t refinements = 0;      // nodes replaced by their children so far
  bool budgetReached = false;  // the refinement stopped because an expansion did not fit faceBudget
};

// Incremental refinement, for a viewer's idle time: Start() resets the cut to the roots, each
// Step() refines a few more nodes (reading their geometry), Done() tells when the budget or the
// finest level is reached. Geometry of nodes that left the cut is evicted.
// Screen-space error with a pixel threshold (ScreenError, projectionScale > 0, maxPixelError > 0):
// once Done(), either cut().budgetReached or every node of the cut that is not culled has a
// ProjectedError of at most maxPixelError, whatever the eye.
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

// The cut's geometry as one mesh, vertices welded by global id (so a cut of level-0 nodes gives
// back the input mesh's faces and vertex positions, and nodes of different levels share their
// border vertices). includeCulled = false drops culled nodes. A face that uses one vertex twice
// (an input face whose corners the build's weld joined: no surface) is left out, so the mesh may
// have fewer faces than cut.faces.
// faceLevel / faceNode (optional): per output face, its node level / node id. attributes
// (optional): per output vertex, the streams the file has (empty ones for a geometry-only file).
Status ExtractCutMesh(LodReader& reader, const LodCut& cut, bool includeCulled, IndexedMesh& out,
                      std::vector<int>* faceLevel = nullptr, std::vector<uint32_t>* faceNode = nullptr,
                      LodAttributes* attributes = nullptr);

}  // namespace conelod
