// ConeLOD — feature-preserving simplification by edge operations.
//
// Hayano, Matsuoka, Ueda, "Mesh Simplification Using Edge Operation with Feature Detection"
// (Ricoh Software Research Center), §3:
//  §3.1 Feature edges. The dihedral angle A of an edge is "the acute angle formed by the two faces
//       sharing the edge" (Fig. 1): the opening angle of the wedge the two faces make at the edge,
//       A = pi - (angle between the two face normals), so A = 180 deg on a flat region, 90 deg on
//       a cube edge and close to 0 on a knife edge. An edge is a feature edge iff A <= A_t.
//       Broken feature lines are extended by edge swaps (Fig. 3): at a vertex V_i with exactly one
//       feature edge, the edge E opposite V_i in one of its faces is swapped when the new edge
//       {V_i, V_r} (V_r = the vertex opposite E in the other face) has A <= A_t; the new edge is a
//       feature edge and the extension goes on from V_r.
//  §3.2 Feature vertices (V_C): 1 or >= 3 incident feature edges, or no feature edge and
//       |K| >= K_t with the discrete Gaussian curvature K = a / S, a = 2 pi - (sum of the corner
//       angles at V), S = (sum of the incident face areas) / 3 (eq. 1).
//  §3.3 Classes: V_C feature vertices (never removed); V_K no feature edge, ordered by |K|; V_M
//       exactly two feature edges E_l, E_r, ordered by |M|, M = b / L, b = pi - (angle between
//       E_l and E_r), L = (|E_l| + |E_r|) / 2 (eq. 2). The vertex with the smallest curvature is
//       removed by a half-edge collapse into one of its neighbours (vertices never move): among
//       its edges the one whose collapse gives the smallest error distance d between the removed
//       vertex and the new faces (Fig. 8); a V_M vertex only along its two feature edges, so the
//       feature line survives. Vertices with |K| or |M| at or above a curvature threshold are not
//       simplified.
//  §3.4 Stop: at an error distance from the original vertices (a collapse is applied only if
//       every original vertex removed so far stays within the distance of the new faces), or at
//       a target face count.
//
// Our reading where the paper is silent (documented in docs/feature_simplify.md):
//  - Curvatures are made scale-free with the bounding-box diagonal D of the input: thresholds
//    compare |K| D^2 and |M| D (the paper's thresholds are in model units).
//  - The paper takes "the smallest vertex of each of the two classes" in turn; we interleave the
//    two queues in proportion to their initial sizes, so feature lines and smooth regions are
//    simplified at the same relative rate. Ties in d (flat regions) go to the better triangles.
//  - Error distance (§3.4): every removed original vertex is assigned to its nearest output face
//    and re-assigned when that face changes; a collapse is allowed when `from` and the vertices
//    its faces answer for stay within the bound of the new faces (exact, one-sided: input
//    vertices -> output). The other direction (a new face overhanging a concave edge while every
//    vertex stays on the surface) is estimated by sampling the new faces against the old ones.
//  - BEYOND: with a target face count, the paper's pure curvature order ignores the error and
//    wrecks curved regions of zero Gaussian curvature (cylinders: K = 0). By default
//    (growErrorBound) the target is reached under an error bound that starts tiny and grows
//    x1.25 only when no collapse fits; within a bound, vertices still go by |K| / |M| and edges
//    by d. growErrorBound = false runs the paper's pure order.
//  - An extension swap must continue the line (the new edge turns by at most 45 deg from the
//    line's last edge), must not flip a face, and never undoes a swap it made.
//  - Border edges are feature lines (a border is simplified only along itself); non-manifold
//    edges are feature edges whose vertices are locked; so are non-manifold vertices and the
//    vertices of faces with a repeated vertex index. A collapse must satisfy the link condition,
//    must not flip a face, and must not merge two feature edges into one.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "conelod/mesh/indexed_mesh.h"
#include "conelod/status.h"

namespace conelod {

struct FeatureSimplifyParams {
  double featureAngleDeg = 135.0;   // A_t, degrees: an edge with dihedral angle A <= A_t is a feature edge
  bool extendFeatureLines = true;   // §3.1 edge swaps that close broken feature lines
  double featureCurvature = 0.0;    // K_t as |K| D^2: a vertex without feature edges and |K| D^2 >= K_t is a
                                    // feature vertex (V_C); 0 = off
  double curvatureThreshold = 0.0;  // vertices with |K| D^2 (V_K) or |M| D (V_M) >= this are not removed;
                                    // 0 = no limit
  double maxErrorDistance = 0.0;    // stop criterion 1, model units: every removed original vertex stays
                                    // within this distance of the output; 0 = off
  size_t targetFaceCount = 0;       // stop criterion 2: stop at this many faces (or fewer); 0 = off
  bool growErrorBound = true;       // with a target face count: simplify under an error bound on the
                                    // original vertices that starts tiny and grows x1.25 only when no
                                    // collapse fits (BEYOND the paper); false = the paper's pure
                                    // curvature order up to the target
  unsigned threads = 0;             // threads for the set-up (feature detection, classification) and
                                    // the first pass of the growing bound (every vertex's first
                                    // evaluation, which depends on the input only, made ahead in
                                    // memory order); 0 = one per core, at most 8. The output is the
                                    // same for any count.
  size_t facesPerPart = 32768;      // with the growing bound, a mesh of at least 2 x this many faces is
                                    // simplified in 2, 4 or 8 parts at the same time (on `threads`
                                    // threads), then along the seams between them; 0 = in one piece.
                                    // The parts depend on the mesh only, not on the threads.
  bool firstPassAhead = true;       // false: the first pass too is evaluated in the queue's order (the
                                    // same output, slower; for checking)
  // Edges (vertex pairs, either order) that are feature lines whatever their dihedral angle, as a
  // border is, and never swapped (issue 26: a texture seam of a mesh whose texture coordinates are
  // per face corner, as MeshLab holds them): a seam vertex goes only along its seam, a vertex where
  // three or more seam edges meet, or where a seam ends, stays (a feature vertex). Pairs that are
  // not edges of the mesh are ignored. Empty: none (the paper's features only).
  std::vector<std::array<uint32_t, 2>> seamEdges;
};

// Checks the parameters (at least one stop criterion); Ok or a message naming the bad one.
Status ValidateParams(const FeatureSimplifyParams& p);

enum class VertexClass : uint8_t {
  Smooth = 0,       // V_K: no feature edge
  FeatureLine = 1,  // V_M: exactly two feature edges
  Feature = 2,      // V_C: corner (1 or >= 3 feature edges), |K| D^2 >= K_t, or locked (non-manifold)
  Unused = 3        // unreferenced vertex
};

// The dihedral angle A (degrees) of the edge shared by two faces with unit normals n0, n1:
// pi - angle(n0, n1). 180 = flat, 90 = cube edge.
double DihedralAngleDeg(const vcg::Point3d& n0, const vcg::Point3d& n1);

// §3.1-3.2 on a mesh, without simplifying: feature edges, extension swaps, vertex classes.
struct FeatureInfo {
  IndexedMesh mesh;  // the input after the extension swaps (same vertices; swapped faces changed)
  std::vector<std::array<uint32_t, 2>> featureEdges;  // (a < b): dihedral, swap-made, border, non-manifold
  size_t dihedralEdges = 0;                           // edges with A <= A_t before the extension
  size_t swapEdges = 0;                               // feature edges created by extension swaps
  size_t removedBySwaps = 0;  // dihedral feature edges removed by those swaps (the folds they repair)
  size_t borderEdges = 0;
  size_t nonManifoldEdges = 0;
  size_t seamEdges = 0;  // interior manifold edges made feature lines by FeatureSimplifyParams::seamEdges
  std::vector<VertexClass> vertexClass;  // per vertex
  std::vector<double> curvatureK;        // raw K = a / S per vertex (0 on border / unused vertices)
  std::vector<double> curvatureM;        // raw M = b / L for V_M vertices, 0 otherwise
  size_t count(VertexClass c) const;
};
Status DetectFeatures(const IndexedMesh& mesh, const FeatureSimplifyParams& params, FeatureInfo& out);

struct FeatureSimplifyResult {
  IndexedMesh mesh;                                   // the simplified mesh (referenced vertices only)
  std::vector<uint32_t> inputVertex;                  // output vertex -> input vertex (vertices never move)
  std::vector<uint32_t> inputFace;                    // output face -> input face it descends from
  std::vector<VertexClass> vertexClass;               // per output vertex
  std::vector<std::array<uint32_t, 2>> featureEdges;  // output feature edges (output indices, a < b)
  // Input vertex -> the output vertex its collapses ended in (an output vertex's own input vertex:
  // itself); UINT32_MAX where no face used it.
  std::vector<uint32_t> survivor;
  size_t facesIn = 0, facesOut = 0;
  size_t featureEdgesIn = 0;  // after the extension, incl. border and non-manifold edges
  size_t swapEdges = 0;
  size_t featureVertices = 0;  // V_C (kept)
  size_t lineVerticesIn = 0, smoothVerticesIn = 0;
  size_t collapses = 0;
  double maxCollapseDistance = 0;  // largest d of an applied collapse
  double maxTrackedError = 0;      // largest distance of a removed original vertex to its output
                                   // face when last re-assigned (tracked under an error bound)
  double finalErrorBound = 0;      // the error bound in force at the end (0: none)
  unsigned parts = 1;              // parts simplified at the same time (FeatureSimplifyParams::facesPerPart)
  bool targetReached = false;      // false: stopped because no allowed collapse was left
};

// Simplifies `mesh`. The mesh must pass RequireValidForFaces (checked here). On failure or
// cancellation `out` is left empty.
Status FeatureSimplify(const IndexedMesh& mesh, const FeatureSimplifyParams& params, FeatureSimplifyResult& out,
                       const Progress& progress = Progress());

// Why a half-edge collapse (from -> to) is refused, for tests and diagnostics.
enum class CollapseRefusal {
  None,  // allowed
  NotAnEdge,
  LockedVertex,    // `from` is a feature vertex (V_C) or locked
  OffFeatureLine,  // `from` is on a feature line and `to` is not its neighbour along the line
  MergesFeatures,  // the collapse would merge two feature edges (close a feature loop)
  Topology,        // link condition, or a border pinch, or a duplicate face
  FlipsFace        // a face would turn over or become degenerate
};
// Checks one collapse on `mesh` after DetectFeatures (no simplification is done).
CollapseRefusal CheckFeatureCollapse(const IndexedMesh& mesh, const FeatureSimplifyParams& params, uint32_t from,
                                     uint32_t to);

// How well the feature lines of `reference` survive in `simplified`: the feature edges of both
// meshes are detected by dihedral angle (A <= featureAngleDeg, border edges included); an edge
// lies on the other mesh's feature lines when its two end points and midpoint are within
// `tolerance` (model units) of that mesh's feature edges.
struct FeatureLineAgreement {
  size_t referenceEdges = 0;          // feature edges of the reference
  size_t simplifiedEdges = 0;         // feature edges of the simplified mesh
  size_t simplifiedOnReference = 0;   // ... that lie on the reference's feature lines
  double referenceLength = 0;         // total length of the reference's feature edges
  double referenceLengthCovered = 0;  // ... of those lying on the simplified mesh's feature edges
};
Status CompareFeatureLines(const IndexedMesh& reference, const IndexedMesh& simplified, double featureAngleDeg,
                           double tolerance, FeatureLineAgreement& out);

// Bounding-box diagonal of the referenced vertices.
double BoundingBoxDiagonal(const IndexedMesh& mesh);

}  // namespace conelod
