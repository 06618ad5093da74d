// ConeLOD — attributes (colour, normals, texture coordinates) carried through the group-preserving
// collapse (group_qem.h).
//
// Garland & Heckbert, "Simplifying surfaces with color and texture using quadric error metrics"
// (IEEE Visualization 1998), extend each face's quadric to the space (position, attributes): on a
// face the attributes are a linear function of position, s(p) = g . p + d per channel (g in the
// face's plane, d fixed by the corners). For a given position p, the attribute value that
// minimises the extended quadric of a vertex is the area-weighted mean of its faces' planes at p,
//     s*(p) = (sum_f a_f (g_f . p + d_f)) / (sum_f a_f),
// which needs only the sums G = sum a_f g_f and D = sum a_f d_f per channel and the weight
// W = sum a_f, summed on every collapse as the quadrics are. This is Hoppe's memory-lean choice
// ("New quadric metric for simplifying meshes with appearance attributes", Visualization 1999):
// the position comes from the geometric quadric alone (the attribute-free placement is kept, so
// the geometry changes only through the collapse order), and the attributes follow from it. We
// keep only the linear part: 4 doubles a channel instead of G&H's (3 + k)^2 / 2.
//
// Cost added to a collapse's error: the weighted variance that merging the two endpoints' models
// at the new position p adds (Ward's criterion),
//     attributeWeight * (0.003 diagonal)^2 * Wa Wb / (Wa + Wb)^2 * sum_c (sa_c(p) - sb_c(p))^2,
// in squared length as the geometric error: at weight 1 a full-scale difference of 1 in every
// channel costs as much as a distance of 0.3 % of the diagonal. (G&H's unit-cube convention, 1 for
// one diagonal, let colour override geometry on the coloured dragon: 7 times its geometric error
// at 10 % of the faces; docs/attributes.md.)
//
// Seams, as wedges (Hoppe 1999): the attributes are given per face corner, so one vertex of the
// position-welded mesh may carry several values (a texture seam: one position, two texture
// coordinates; a colour seam; a crease's split normals). A vertex whose corners differ is a seam
// vertex. Its corners keep exact values of their own sides (both sides share the vertex: no
// crack); it is removed only into another seam vertex, and each of its faces then takes a value
// at the keeper from its own side, never from across a seam:
//  - along its seam (the edge's two faces on different wedges), or off it where the edge's faces
//    see one value at both ends, each face whose value at `gone` an edge face shares takes that
//    edge face's value at `keep`: the seam shortens along itself, exactly (no cost);
//  - a face whose value at `gone` no edge face shares (a chart junction: three or more wedges, or
//    a small chart whose vertices are all on its border, crossed by the edge) keeps its own value,
//    now at keep's place: its chart's texture stretches over the distance d moved (as MeshLab's
//    texture QEM lets a seam move, at a price). That costs kSeamMove x (the share of gone's faces
//    that do so) x d^2, added to the collapse's priority, so that junctions go after the collapses
//    that move no seam of the same error.
// Along a seam between two plain seam points (two wedges each) the merged vertex may also go
// anywhere on the edge (AllowSeamSlides, Slide): each side's values are interpolated along the
// edge, from the edge face on its side, so both sides stay on one segment of their charts and the
// seam keeps its texture; the simplifier puts it at the geometric quadric's minimum on the edge.
// Where the values of a seam vertex hold is its anchor (group_qem.cpp, seamPlace): without
// AllowSeamMoves the vertex stays there; with it, the vertex may leave it at a cost (the distance
// in the tangent plane: along the normal the texture stays where it was), and each of its texture
// wedges then takes its chart's linear function at the new place, cut where that would leave the
// wedge's own faces in texture space (Reparameterize: inside the chart the texture follows; across
// the seam it stretches); the new place is the anchor.
// (Without AllowSeamMoves, only along the seam between two vertices of two wedges each: junctions
// stay.) A vertex that is not on a seam may be removed into a seam vertex when the edge's faces see one
// value there; its faces then take that value. So a collapse never drags texture coordinates
// across a seam; as in meshoptimizer's simplifier, a seam vertex's wedges move together.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include <vcg/space/point3.h>

#include "conelod/mesh/attributes.h"
#include "conelod/mesh/indexed_mesh.h"
#include "conelod/status.h"

namespace conelod {

class AttributeQuadrics {
 public:
  // The current corners of face f (the simplifier's face array: a collapse replaces the removed
  // vertex in place, so corner k of face f stays corner k).
  using FaceCorners = std::function<const std::array<uint32_t, 3>&(uint32_t f)>;

  // mesh: the (position-welded) mesh the collapse runs on; cornerValues: per face corner (3 f + k),
  // `layout.channels()` values each, laid out as `layout` says (its `values` are not read);
  // weight >= 0 (the CLI's --attribute-weight).
  Status Init(const IndexedMesh& mesh, const VertexAttributes& layout, std::vector<float> cornerValues, double weight);
  // Off (Init's default): a seam vertex goes only along its seam into a vertex of two wedges, and
  // chart junctions stay (texture coordinates exactly their chart's at every vertex: the .clod
  // levels). On: the rules at the top, junctions and small charts included (conelod simplify, the
  // MeshLab filter).
  void AllowSeamMoves(bool on) { seamMoves_ = on; }
  bool seamMoves() const { return seamMoves_; }
  // On (Init's default): a collapse along a seam edge whose ends are both plain seam points (two
  // wedges each, the edge's faces on different wedges at both ends) may place the merged vertex
  // anywhere on the edge (the simplifier's constrained minimum), each side's values interpolated
  // along the edge (Slide). Off: such a collapse keeps one end's position (a half-edge collapse).
  void AllowSeamSlides(bool on) { seamSlides_ = on; }
  bool seamSlides() const { return seamSlides_; }
  bool active() const { return channels_ > 0; }
  int channels() const { return channels_; }
  bool seam(uint32_t v) const { return wedges_[v] >= 2; }
  size_t seamVertices() const;

  // The cost of merging a and b at p (input coordinates), squared length.
  double Cost(uint32_t a, uint32_t b, const vcg::Point3d& p) const;
  // Whether `gone` may be removed into `keep` (see the top), and what it costs beyond Cost(), in
  // squared length: -1 when it may not; 0 when every face of `gone` finds its value at `keep` on its
  // own side; otherwise the seam-move cost of the faces that keep their own (moveSq: the squared
  // distance from gone to keep). e0, e1: the faces on the edge (e1 may be none: UINT32_MAX);
  // goneFaces[count]: the faces of `gone` (those on the edge included).
  double SeamCost(uint32_t gone, uint32_t keep, uint32_t e0, uint32_t e1, const uint32_t* goneFaces, size_t count,
                  const FaceCorners& faces, double moveSq) const;
  // The collapse of `gone` into `keep`, before the simplifier replaces `gone` in `goneFaces`' corners:
  // the corner values of those faces (seams) and the models.
  void Collapse(uint32_t keep, uint32_t gone, const uint32_t* goneFaces, size_t count, const FaceCorners& faces);
  // Whether the edge (a, b) with faces e0, e1 runs along a seam between two plain seam points (see
  // AllowSeamSlides): then the merged vertex may go anywhere on the edge.
  bool SlidesAlong(uint32_t a, uint32_t b, uint32_t e0, uint32_t e1, const FaceCorners& faces) const;
  // The collapse of `gone` into `keep` when the merged vertex goes to keep + t (gone - keep), t in
  // [0, 1], on a seam edge (SlidesAlong), before the simplifier replaces `gone`: every face of keep
  // and gone off the edge takes, at the merged vertex, its side's values interpolated along the
  // edge, (1 - t) value(keep) + t value(gone), from the edge face on its side; the models merge.
  void Slide(uint32_t keep, uint32_t gone, double t, const uint32_t* keepFaces, size_t keepCount,
             const uint32_t* goneFaces, size_t goneCount, const FaceCorners& faces);

  // Seam vertex v moves from `from` (where its corner values hold) to `to`: each of its texture
  // wedges (its faces' corners of one (u, v)) moves by the area-weighted gradient of its faces
  // (positions by `pos`, v's at `from`) times the move, cut where the new value would leave the
  // wedge's faces in texture space (it stays inside its chart). Colours and normals are kept.
  void Reparameterize(uint32_t v, const vcg::Point3d& from, const vcg::Point3d& to, const uint32_t* faceList,
                      size_t count, const FaceCorners& faces, const std::function<vcg::Point3d(uint32_t)>& pos);

  // A memoryless step (GroupQemParams::refreshRatio): every model built again, as Init builds them,
  // from the live faces (live(f), f < faceCount) at their vertices' places (pos: input
  // coordinates), each corner at the value it holds now (a seam vertex's own; a plain vertex's
  // model at its place).
  void Refresh(size_t faceCount, const FaceCorners& faces, const std::function<bool(uint32_t)>& live,
               const std::function<vcg::Point3d(uint32_t)>& pos);

  // The attributes of corner k of face f, at vertex v now at p (input coordinates), into
  // out[channels()]: a seam vertex's corner value; otherwise s*(p), colours clamped to [0, 1],
  // normals made unit length.
  void Evaluate(uint32_t f, int k, uint32_t v, const vcg::Point3d& p, float* out) const;

  // The simplifier's own numbering (group_qem.cpp's spatial order): vertex i becomes input vertex
  // vertexInput[i], face f input face faceInput[f] (corners in the same order), so that the
  // collapse may run in that order with attributes too; RestoreInputOrder (before Evaluate) gives
  // back the input's numbering. The values move, none changes: the collapse sees the same models.
  void Renumber(const std::vector<uint32_t>& vertexInput, const std::vector<uint32_t>& faceInput);
  void RestoreInputOrder();

 private:
  double predict(uint32_t v, int c, const vcg::Point3d& q) const;  // s*_c at q (centred)
  // Adds face t's attribute planes (corners at p, centred, with values `value`) to its vertices' models.
  void AddFace(const std::array<uint32_t, 3>& t, const vcg::Point3d p[3], const std::array<const float*, 3>& value);
  const float* corner(uint32_t f, int k) const { return corner_.data() + (3 * size_t(f) + size_t(k)) * channels_; }
  float* corner(uint32_t f, int k) { return corner_.data() + (3 * size_t(f) + size_t(k)) * channels_; }
  const float* valueAt(uint32_t f, uint32_t v, const FaceCorners& faces) const;
  bool same(const float* x, const float* y) const;

  int channels_ = 0;
  bool seamMoves_ = false;
  bool seamSlides_ = true;
  VertexAttributes layout_;
  std::vector<float> corner_;    // per face corner
  std::vector<uint8_t> wedges_;  // distinct corner values per vertex, saturated at 3
  vcg::Point3d center_;
  double scale_ = 0;                               // weight * (0.003 diagonal)^2
  std::vector<double> model_;                      // per vertex: W, then per channel Gx Gy Gz D
  std::vector<uint32_t> vertexInput_, faceInput_;  // Renumber's maps (empty: the input's numbering)
  // Per channel: the value every corner has, or NaN. A channel the same on every corner carries no
  // information: it costs nothing and is that value everywhere, exactly (a colour every vertex
  // shares leaves the collapse as it is without it; docs/attributes.md).
  std::vector<float> constant_;
};

}  // namespace conelod
