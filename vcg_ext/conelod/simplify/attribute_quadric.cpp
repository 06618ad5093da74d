// ConeLOD — attributes through the group-preserving collapse (attribute_quadric.h).
#include "conelod/simplify/attribute_quadric.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include <vcg/space/box3.h>

namespace conelod {

using vcg::Point3d;

namespace {
constexpr uint32_t kNoFace = UINT32_MAX;
// At weight 1 a full-scale difference in every channel costs as much as a distance of this
// fraction of the diagonal: chosen on the coloured dragon (docs/attributes.md) so that the
// colour error drops while the geometric error stays within 5 % of the attribute-free run.
constexpr double kUnitFraction = 0.003;
// A collapse that leaves some of gone's faces with their own value at keep's place (a chart
// junction or a small chart degrading; attribute_quadric.h) costs this fraction of the squared
// distance moved, times the share of gone's faces that do so: chosen on the textured dragon
// (docs/attributes.md) with the drift (group_qem.cpp's kSeamDrift): the geometry nearest the
// attribute-free run with the texture error below MeshLab's texture QEM.
constexpr double kSeamMove = 0.02;
}  // namespace

Status AttributeQuadrics::Init(const IndexedMesh& mesh, const VertexAttributes& layout, std::vector<float> cornerValues,
                               double weight) {
  const size_t V = mesh.positions.size(), F = mesh.faces.size();
  channels_ = layout.channels();
  if (!(weight >= 0) || !std::isfinite(weight)) return Status::Invalid("the attribute weight must be >= 0");
  if (cornerValues.size() != 3 * F * size_t(channels_))
    return Status::Invalid("the attributes are given for " + std::to_string(cornerValues.size()) +
                           " values, the mesh's " + std::to_string(3 * F) + " face corners need " +
                           std::to_string(3 * F * size_t(channels_)));
  for (const auto& t : mesh.faces)
    for (uint32_t v : t)
      if (v >= V) return Status::Invalid("a face uses a vertex out of range");
  layout_ = layout;
  layout_.values.clear();
  corner_ = std::move(cornerValues);
  constant_.assign(size_t(channels_), std::numeric_limits<float>::quiet_NaN());
  if (F > 0)
    for (int c = 0; c < channels_; ++c) {
      bool same = true;
      for (size_t i = size_t(c); same && i < corner_.size(); i += size_t(channels_))
        same = corner_[i] == corner_[size_t(c)];
      if (same) constant_[size_t(c)] = corner_[size_t(c)];
    }
  vcg::Box3d box;
  for (const auto& p : mesh.positions) box.Add(Point3d::Construct(p));
  center_ = box.IsNull() ? Point3d(0, 0, 0) : box.Center();
  const double diag = box.IsNull() || !(box.Diag() > 0) ? 1.0 : box.Diag();
  scale_ = weight * (kUnitFraction * diag) * (kUnitFraction * diag);
  // Wedges: distinct corner values per vertex (the first value seen, then any other).
  wedges_.assign(V, 0);
  std::vector<uint32_t> firstCorner(V, kNoFace);
  for (uint32_t f = 0; f < F; ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh.faces[f][size_t(k)];
      if (firstCorner[v] == kNoFace) {
        firstCorner[v] = 3 * f + uint32_t(k);
        wedges_[v] = 1;
      } else if (wedges_[v] == 1 && !same(corner(firstCorner[v] / 3, int(firstCorner[v] % 3)), corner(f, k))) {
        wedges_[v] = 2;  // counted exactly below for the seam vertices
      }
    }
  // Seam vertices: count their distinct values (2, or 3 for "more than two").
  std::vector<std::vector<uint32_t>> cornersOf;
  {
    std::vector<uint32_t> seamId(V, kNoFace);
    for (uint32_t v = 0; v < V; ++v)
      if (wedges_[v] >= 2) {
        seamId[v] = uint32_t(cornersOf.size());
        cornersOf.emplace_back();
      }
    for (uint32_t f = 0; f < F; ++f)
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = mesh.faces[f][size_t(k)];
        if (seamId[v] != kNoFace) cornersOf[seamId[v]].push_back(3 * f + uint32_t(k));
      }
    for (uint32_t v = 0; v < V; ++v) {
      if (seamId[v] == kNoFace) continue;
      std::vector<const float*> distinct;
      for (uint32_t c : cornersOf[seamId[v]]) {
        const float* x = corner(c / 3, int(c % 3));
        bool known = false;
        for (const float* y : distinct) known |= same(x, y);
        if (!known) distinct.push_back(x);
        if (distinct.size() >= 3) break;
      }
      wedges_[v] = uint8_t(distinct.size());
    }
  }
  model_.assign(V * (1 + 4 * size_t(channels_)), 0.0);
  for (uint32_t f = 0; f < F; ++f) {
    const auto& t = mesh.faces[f];
    const Point3d p[3] = {Point3d::Construct(mesh.positions[t[0]]) - center_,
                          Point3d::Construct(mesh.positions[t[1]]) - center_,
                          Point3d::Construct(mesh.positions[t[2]]) - center_};
    AddFace(t, p, {corner(f, 0), corner(f, 1), corner(f, 2)});
  }
  return Status::Ok();
}

void AttributeQuadrics::AddFace(const std::array<uint32_t, 3>& t, const Point3d p[3],
                                const std::array<const float*, 3>& value) {
  const size_t stride = 1 + 4 * size_t(channels_);
  const Point3d e1 = p[1] - p[0], e2 = p[2] - p[0], n = e1 ^ e2;
  const double n2 = n.SquaredNorm(), area = 0.5 * std::sqrt(n2);
  // g = the gradient in the face's plane: g.e1 = s1 - s0, g.e2 = s2 - s0, g.n = 0, i.e.
  // g = ((s1 - s0) (e2 x n) + (s2 - s0) (n x e1)) / |n|^2. A face without area: no gradient,
  // and a tiny weight so that a vertex of degenerate faces only still has a model.
  const double a = area > 0 ? area : 1e-30;
  const bool flat = !(n2 > 0) || !std::isfinite(n2);
  const Point3d u1 = flat ? Point3d(0, 0, 0) : (e2 ^ n) / n2, u2 = flat ? Point3d(0, 0, 0) : (n ^ e1) / n2;
  for (uint32_t v : t) model_[v * stride] += a;
  for (int c = 0; c < channels_; ++c) {
    const double s0 = value[0][c], s1 = value[1][c], s2 = value[2][c];
    const Point3d g = flat ? Point3d(0, 0, 0) : u1 * (s1 - s0) + u2 * (s2 - s0);
    const double d = flat ? (s0 + s1 + s2) / 3 : s0 - g * p[0];
    for (uint32_t v : t) {
      double* m = model_.data() + v * stride + 1 + 4 * size_t(c);
      m[0] += a * g[0];
      m[1] += a * g[1];
      m[2] += a * g[2];
      m[3] += a * d;
    }
  }
}

void AttributeQuadrics::Refresh(size_t faceCount, const FaceCorners& faces, const std::function<bool(uint32_t)>& live,
                                const std::function<Point3d(uint32_t)>& pos) {
  const size_t C = size_t(channels_), V = wedges_.size(), stride = 1 + 4 * C;
  // What each plain vertex carries now: its model's best value at its place (Evaluate's, unclamped).
  std::vector<float> value(V * C);
  std::vector<Point3d> at(V);
  for (uint32_t v = 0; v < V; ++v) {
    if (!(model_[v * stride] > 0)) continue;  // dead, or no face
    at[v] = pos(v) - center_;
    if (!seam(v))
      for (size_t c = 0; c < C; ++c) value[v * C + c] = float(predict(v, int(c), at[v]));
  }
  model_.assign(V * stride, 0.0);
  for (uint32_t f = 0; f < faceCount; ++f) {
    if (!live(f)) continue;
    const auto& t = faces(f);
    const Point3d p[3] = {at[t[0]], at[t[1]], at[t[2]]};
    std::array<const float*, 3> s;
    for (int k = 0; k < 3; ++k) s[size_t(k)] = seam(t[size_t(k)]) ? corner(f, k) : value.data() + t[size_t(k)] * C;
    AddFace(t, p, s);
  }
}

size_t AttributeQuadrics::seamVertices() const {
  size_t n = 0;
  for (uint8_t w : wedges_) n += w >= 2;
  return n;
}

bool AttributeQuadrics::same(const float* x, const float* y) const {
  for (int c = 0; c < channels_; ++c)
    if (!(x[c] == y[c])) return false;
  return true;
}

const float* AttributeQuadrics::valueAt(uint32_t f, uint32_t v, const FaceCorners& faces) const {
  const auto& t = faces(f);
  return corner(f, t[0] == v ? 0 : (t[1] == v ? 1 : 2));
}

double AttributeQuadrics::predict(uint32_t v, int c, const Point3d& q) const {
  const size_t stride = 1 + 4 * size_t(channels_);
  const double* m = model_.data() + v * stride;
  const double* g = m + 1 + 4 * size_t(c);
  return m[0] > 0 ? (g[0] * q[0] + g[1] * q[1] + g[2] * q[2] + g[3]) / m[0] : 0.0;
}

double AttributeQuadrics::Cost(uint32_t a, uint32_t b, const Point3d& p) const {
  if (!(scale_ > 0) || seam(a) || seam(b)) return 0;  // a seam vertex keeps its values: nothing blends
  const size_t stride = 1 + 4 * size_t(channels_);
  const double wa = model_[a * stride], wb = model_[b * stride];
  if (!(wa > 0 && wb > 0)) return 0;
  const Point3d q = p - center_;
  double sum = 0;
  for (int c = 0; c < channels_; ++c) {
    if (!std::isnan(constant_[size_t(c)])) continue;
    const double d = predict(a, c, q) - predict(b, c, q);
    sum += d * d;
  }
  return scale_ * wa * wb / ((wa + wb) * (wa + wb)) * sum;
}

double AttributeQuadrics::SeamCost(uint32_t gone, uint32_t keep, uint32_t e0, uint32_t e1, const uint32_t* goneFaces,
                                   size_t count, const FaceCorners& faces, double moveSq) const {
  const bool oneAtKeep = e1 == kNoFace || same(valueAt(e0, keep, faces), valueAt(e1, keep, faces));
  // Into a seam vertex: the edge's faces must see one value at it (else the seam runs along the
  // edge, and the removed vertex's faces would not know their side).
  if (!seam(gone)) return !seam(keep) || oneAtKeep ? 0 : -1;
  if (!seam(keep)) return -1;
  if (!seamMoves_) {  // along a seam: two wedges at each end, the edge's faces on different wedges at both
    if (wedges_[gone] != 2 || wedges_[keep] != 2 || e1 == kNoFace) return -1;
    return !same(valueAt(e0, gone, faces), valueAt(e1, gone, faces)) && !oneAtKeep ? 0 : -1;
  }
  const float* g0 = valueAt(e0, gone, faces);
  const float* g1 = e1 == kNoFace ? nullptr : valueAt(e1, gone, faces);
  if (g1 && same(g0, g1) && !oneAtKeep) return -1;  // one side at gone, two at keep
  size_t around = 0, own = 0;
  for (size_t i = 0; i < count; ++i) {
    const uint32_t f = goneFaces[i];
    const auto& t = faces(f);
    if (t[0] == keep || t[1] == keep || t[2] == keep) continue;  // on the edge: removed
    ++around;
    const float* v = valueAt(f, gone, faces);
    own += !same(v, g0) && !(g1 && same(v, g1));
  }
  return own == 0 ? 0 : kSeamMove * double(own) / double(around) * moveSq;
}

void AttributeQuadrics::Collapse(uint32_t keep, uint32_t gone, const uint32_t* goneFaces, size_t count,
                                 const FaceCorners& faces) {
  if (seam(keep)) {
    // The faces of `gone` take the keeper's value on their side: that of the edge face whose
    // value at `gone` they share (all of them, e[0]'s, when `gone` is not on a seam); a face that
    // shares none (SeamCost's seam move) keeps its own.
    uint32_t e[2] = {kNoFace, kNoFace};
    for (size_t i = 0; i < count; ++i) {
      const auto& t = faces(goneFaces[i]);
      if ((t[0] == keep || t[1] == keep || t[2] == keep) && e[1] == kNoFace) e[e[0] == kNoFace ? 0 : 1] = goneFaces[i];
    }
    bool moved = false;
    for (size_t i = 0; i < count && e[0] != kNoFace; ++i) {
      const uint32_t f = goneFaces[i];
      if (f == e[0] || f == e[1]) continue;
      const auto& t = faces(f);
      if (t[0] == keep || t[1] == keep || t[2] == keep) continue;  // a face on the edge (3+ faces)
      uint32_t side = e[0];
      if (seam(gone)) {
        const float* v = valueAt(f, gone, faces);
        side = same(v, valueAt(e[0], gone, faces))                      ? e[0]
               : e[1] != kNoFace && same(v, valueAt(e[1], gone, faces)) ? e[1]
                                                                        : kNoFace;
      }
      if (side == kNoFace) {
        moved = true;
        continue;
      }
      const float* value = valueAt(side, keep, faces);
      float* target = corner(f, t[0] == gone ? 0 : (t[1] == gone ? 1 : 2));
      std::copy(value, value + channels_, target);
    }
    if (moved && wedges_[keep] < 3) ++wedges_[keep];
  }
  const size_t stride = 1 + 4 * size_t(channels_);
  for (size_t i = 0; i < stride; ++i) model_[keep * stride + i] += model_[gone * stride + i];
}

bool AttributeQuadrics::SlidesAlong(uint32_t a, uint32_t b, uint32_t e0, uint32_t e1, const FaceCorners& faces) const {
  if (!seamSlides_ || e0 == kNoFace || e1 == kNoFace || wedges_[a] != 2 || wedges_[b] != 2) return false;
  return !same(valueAt(e0, a, faces), valueAt(e1, a, faces)) && !same(valueAt(e0, b, faces), valueAt(e1, b, faces));
}

void AttributeQuadrics::Slide(uint32_t keep, uint32_t gone, double t, const uint32_t* keepFaces, size_t keepCount,
                              const uint32_t* goneFaces, size_t goneCount, const FaceCorners& faces) {
  // The edge's two faces (among gone's: those that hold keep too).
  uint32_t e[2] = {kNoFace, kNoFace};
  for (size_t i = 0; i < goneCount; ++i) {
    const auto& tr = faces(goneFaces[i]);
    if ((tr[0] == keep || tr[1] == keep || tr[2] == keep) && e[1] == kNoFace) e[e[0] == kNoFace ? 0 : 1] = goneFaces[i];
  }
  if (e[1] == kNoFace) {  // not an edge of two faces: as a half-edge collapse
    Collapse(keep, gone, goneFaces, goneCount, faces);
    return;
  }
  // Each side's ends and its value at the merged vertex (copied: the edge faces' corners stay).
  const size_t C = size_t(channels_);
  std::vector<float> end(4 * C), mid(2 * C);
  for (int s = 0; s < 2; ++s) {
    std::copy_n(valueAt(e[s], keep, faces), C, end.data() + (2 * s) * C);
    std::copy_n(valueAt(e[s], gone, faces), C, end.data() + (2 * s + 1) * C);
    for (size_t c = 0; c < C; ++c)
      mid[s * C + c] = float((1 - t) * end[(2 * s) * C + c] + t * end[(2 * s + 1) * C + c]);
  }
  for (int pass = 0; pass < 2; ++pass) {
    const uint32_t v = pass == 0 ? keep : gone, other = pass == 0 ? gone : keep;
    const uint32_t* list = pass == 0 ? keepFaces : goneFaces;
    const size_t count = pass == 0 ? keepCount : goneCount;
    for (size_t i = 0; i < count; ++i) {
      const uint32_t f = list[i];
      const auto& tr = faces(f);
      if (tr[0] == other || tr[1] == other || tr[2] == other) continue;  // on the edge: removed
      float* target = corner(f, tr[0] == v ? 0 : (tr[1] == v ? 1 : 2));
      const float* side = same(target, end.data() + (2 * 0 + pass) * C)   ? mid.data()
                          : same(target, end.data() + (2 * 1 + pass) * C) ? mid.data() + C
                                                                          : nullptr;
      if (side) std::copy_n(side, C, target);  // two wedges: always one of the sides
    }
  }
  const size_t stride = 1 + 4 * size_t(channels_);
  for (size_t i = 0; i < stride; ++i) model_[keep * stride + i] += model_[gone * stride + i];
}

void AttributeQuadrics::Reparameterize(uint32_t v, const Point3d& from, const Point3d& to, const uint32_t* faceList,
                                       size_t count, const FaceCorners& faces,
                                       const std::function<Point3d(uint32_t)>& pos) {
  if (!layout_.texCoords || count == 0) return;
  const int o = layout_.texCoordOffset();
  const Point3d move = to - from;
  // Wedges by texture coordinates: value, area-weighted gradient sums (u, v), area.
  struct Wedge {
    float u, v;
    Point3d gu, gv;
    double area;
  };
  std::vector<Wedge> wedges;
  std::vector<uint32_t> wedgeOf(count);
  for (size_t i = 0; i < count; ++i) {
    const uint32_t f = faceList[i];
    const auto& t = faces(f);
    const int k = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
    const float* x = corner(f, k) + o;
    size_t w = 0;
    while (w < wedges.size() && !(wedges[w].u == x[0] && wedges[w].v == x[1])) ++w;
    if (w == wedges.size()) wedges.push_back({x[0], x[1], Point3d(0, 0, 0), Point3d(0, 0, 0), 0.0});
    wedgeOf[i] = uint32_t(w);
    const Point3d p0 = t[0] == v ? from : pos(t[0]), p1 = t[1] == v ? from : pos(t[1]),
                  p2 = t[2] == v ? from : pos(t[2]);
    const Point3d e1 = p1 - p0, e2 = p2 - p0, n = e1 ^ e2;
    const double n2 = n.SquaredNorm();
    if (!(n2 > 0) || !std::isfinite(n2)) continue;
    const double area = 0.5 * std::sqrt(n2);
    const Point3d u1 = (e2 ^ n) / n2, u2 = (n ^ e1) / n2;
    const float* s0 = corner(f, 0) + o;
    const float* s1 = corner(f, 1) + o;
    const float* s2 = corner(f, 2) + o;
    wedges[w].gu += (u1 * (double(s1[0]) - s0[0]) + u2 * (double(s2[0]) - s0[0])) * area;
    wedges[w].gv += (u1 * (double(s1[1]) - s0[1]) + u2 * (double(s2[1]) - s0[1])) * area;
    wedges[w].area += area;
  }
  // Each wedge's shift, cut where it would leave the wedge's own faces in texture space (the
  // chart): the new value stays in the fan of the old one.
  std::vector<double> du(wedges.size(), 0.0), dv(wedges.size(), 0.0), reach(wedges.size(), 0.0);
  for (size_t w = 0; w < wedges.size(); ++w)
    if (wedges[w].area > 0) {
      du[w] = (wedges[w].gu * move) / wedges[w].area;
      dv[w] = (wedges[w].gv * move) / wedges[w].area;
    }
  for (size_t i = 0; i < count; ++i) {
    const size_t w = wedgeOf[i];
    if (du[w] == 0 && dv[w] == 0) continue;
    const uint32_t f = faceList[i];
    const auto& t = faces(f);
    const int k = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
    const float* a = corner(f, k) + o;
    const float* b = corner(f, (k + 1) % 3) + o;
    const float* c = corner(f, (k + 2) % 3) + o;
    const double bx = double(b[0]) - a[0], by = double(b[1]) - a[1], cx = double(c[0]) - a[0], cy = double(c[1]) - a[1];
    const double det = bx * cy - by * cx;
    if (!(std::fabs(det) > 0)) continue;
    const double alpha = (du[w] * cy - dv[w] * cx) / det, beta = (bx * dv[w] - by * du[w]) / det;
    if (alpha >= 0 && beta >= 0 && alpha + beta > 0) reach[w] = std::max(reach[w], 1.0 / (alpha + beta));
  }
  for (size_t i = 0; i < count; ++i) {
    const size_t w = wedgeOf[i];
    const double s = std::min(1.0, reach[w]);
    if (!(s > 0)) continue;
    const uint32_t f = faceList[i];
    const auto& t = faces(f);
    float* x = corner(f, t[0] == v ? 0 : (t[1] == v ? 1 : 2)) + o;
    x[0] = float(wedges[w].u + s * du[w]);
    x[1] = float(wedges[w].v + s * dv[w]);
  }
}

void AttributeQuadrics::Evaluate(uint32_t f, int k, uint32_t v, const Point3d& p, float* out) const {
  if (seam(v)) {
    std::copy(corner(f, k), corner(f, k) + channels_, out);
    return;
  }
  const Point3d q = p - center_;
  for (int c = 0; c < channels_; ++c)
    out[c] = std::isnan(constant_[size_t(c)]) ? float(predict(v, c, q)) : constant_[size_t(c)];
  for (int c = 0; c < layout_.colorChannels; ++c) out[c] = std::min(1.0f, std::max(0.0f, out[c]));
  if (layout_.normals) {
    float* n = out + layout_.normalOffset();
    const double len = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
    if (len > 0)
      for (int k2 = 0; k2 < 3; ++k2) n[k2] = float(n[k2] / len);
  }
}

void AttributeQuadrics::Renumber(const std::vector<uint32_t>& vertexInput, const std::vector<uint32_t>& faceInput) {
  RestoreInputOrder();
  const size_t V = wedges_.size(), F = corner_.size() / (3 * size_t(std::max(channels_, 1)));
  if (vertexInput.size() != V || faceInput.size() != F) return;  // not this mesh's numbering: keep the input's
  const size_t stride = 1 + 4 * size_t(channels_), cornerStride = 3 * size_t(channels_);
  std::vector<uint8_t> wedges(V);
  std::vector<double> model(model_.size());
  for (size_t i = 0; i < V; ++i) {
    wedges[i] = wedges_[vertexInput[i]];
    std::copy_n(model_.data() + vertexInput[i] * stride, stride, model.data() + i * stride);
  }
  std::vector<float> corner(corner_.size());
  for (size_t f = 0; f < F; ++f)
    std::copy_n(corner_.data() + faceInput[f] * cornerStride, cornerStride, corner.data() + f * cornerStride);
  wedges_.swap(wedges);
  model_.swap(model);
  corner_.swap(corner);
  vertexInput_ = vertexInput;
  faceInput_ = faceInput;
}

void AttributeQuadrics::RestoreInputOrder() {
  if (vertexInput_.empty() && faceInput_.empty()) return;
  const size_t stride = 1 + 4 * size_t(channels_), cornerStride = 3 * size_t(channels_);
  std::vector<uint8_t> wedges(wedges_.size());
  std::vector<double> model(model_.size());
  for (size_t i = 0; i < vertexInput_.size(); ++i) {
    wedges[vertexInput_[i]] = wedges_[i];
    std::copy_n(model_.data() + i * stride, stride, model.data() + vertexInput_[i] * stride);
  }
  std::vector<float> corner(corner_.size());
  for (size_t f = 0; f < faceInput_.size(); ++f)
    std::copy_n(corner_.data() + f * cornerStride, cornerStride, corner.data() + faceInput_[f] * cornerStride);
  wedges_.swap(wedges);
  model_.swap(model);
  corner_.swap(corner);
  vertexInput_.clear();
  faceInput_.clear();
}

}  // namespace conelod
