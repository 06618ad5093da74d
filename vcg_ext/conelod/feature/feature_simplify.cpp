// ConeLOD — feature-preserving simplification by edge operations (see feature_simplify.h).
#include "conelod/common.h"
#include "conelod/feature/feature_simplify.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <queue>
#include <unordered_map>
#include <unordered_set>

#include <vcg/space/box3.h>

#include "conelod/parallel.h"
#include "conelod/mesh/mesh_check.h"

namespace conelod {
namespace {

using P3 = vcg::Point3d;
constexpr uint32_t kNone = UINT32_MAX;
constexpr size_t kNoTri = SIZE_MAX;  // no triangle to try first

inline uint64_t EdgeKey(uint32_t a, uint32_t b) { return a < b ? (uint64_t(a) << 32) | b : (uint64_t(b) << 32) | a; }

inline double Clamp1(double x) { return std::max(-1.0, std::min(1.0, x)); }

inline double AngleBetween(const P3& a, const P3& b) {
  const double la = a.Norm(), lb = b.Norm();
  if (!(la > 0) || !(lb > 0)) return 0;
  return std::acos(Clamp1((a * b) / (la * lb)));
}

double PointSegmentDistance2(const P3& p, const P3& a, const P3& b) {
  const P3 ab = b - a;
  const double len2 = ab.SquaredNorm();
  double t = len2 > 0 ? ((p - a) * ab) / len2 : 0;
  t = std::max(0.0, std::min(1.0, t));
  return (p - (a + ab * t)).SquaredNorm();
}

// Triangle shape in [0,1]: 4 sqrt(3) area / (sum of squared edge lengths); 1 = equilateral.
double TriangleQuality(const P3& a, const P3& b, const P3& c) {
  const double s = (b - a).SquaredNorm() + (c - b).SquaredNorm() + (a - c).SquaredNorm();
  if (!(s > 0)) return 0;
  return 2.0 * std::sqrt(3.0) * ((b - a) ^ (c - a)).Norm() / s;
}

// A triangle with its unit normal (zero when degenerate), for repeated distance queries: the
// distance to its plane is a cheap lower bound of the distance to it.
struct Tri {
  P3 a, b, c, n;
  uint32_t face;
};

Tri MakeTri(const P3& a, const P3& b, const P3& c, uint32_t face) {
  P3 n = (b - a) ^ (c - a);
  const double len = n.Norm();
  return {a, b, c, len > 0 ? n / len : P3(0, 0, 0), face};
}

// Squared distance from p to the nearest of `tris`, trying tris[first] before the others (which
// follow in order; kNoTri: none first): a good first guess lets the plane test skip more of the
// others. With `enough2` > 0 the search stops once within it (the value is then some distance
// <= enough2). With `nearest`, the index of the nearest triangle, ties to the lowest index (as a
// plain scan in order finds it).
double DistanceToTris2(const P3& p, const std::vector<Tri>& tris, size_t first, double enough2,
                       size_t* nearest = nullptr) {
  double best = std::numeric_limits<double>::infinity();
  if (first < tris.size()) {
    const Tri& t = tris[first];
    best = PointTriangleDistance2(p, t.a, t.b, t.c);
    if (nearest) *nearest = first;
    if (best <= enough2) return best;
  }
  for (size_t i = 0; i < tris.size(); ++i) {
    if (i == first) continue;
    const Tri& t = tris[i];
    const double h = (p - t.a) * t.n;
    // Below `first` an equal distance wins (the lower index), above it only a smaller one.
    const bool below = i < first && first < tris.size();
    if (below ? h * h > best : h * h >= best) continue;
    const double d2 = PointTriangleDistance2(p, t.a, t.b, t.c);
    if (below ? d2 <= best : d2 < best) {
      best = d2;
      if (nearest) *nearest = i;
      if (best <= enough2) break;
    }
  }
  return best;
}

// The threads of the first pass and of the set-up's passes: FeatureSimplifyParams::threads, 0 =
// one per core, at most 8.
unsigned FeatureThreads(const FeatureSimplifyParams& p) {
  return p.threads == 0 ? std::min(8u, CoreCount()) : p.threads;
}
constexpr size_t kSetUpChunk = 4096;  // vertices or faces per chunk of the set-up's passes

// The faces around a vertex: up to kInline ids stored in place (no pointer to follow for the
// usual valences), more on the heap. The order is that of push_back / swap-removal, as with a
// std::vector.
class FaceList {
 public:
  static constexpr uint32_t kInline = 13;
  FaceList() = default;
  FaceList(const FaceList& o) { *this = o; }
  FaceList& operator=(const FaceList& o) {
    if (this == &o) return *this;
    n_ = 0;
    reserve(o.n_);
    std::copy(o.begin(), o.end(), data());
    n_ = o.n_;
    return *this;
  }
  uint32_t* begin() { return data(); }
  uint32_t* end() { return data() + n_; }
  const uint32_t* begin() const { return data(); }
  const uint32_t* end() const { return data() + n_; }
  size_t size() const { return n_; }
  bool empty() const { return n_ == 0; }
  void clear() { n_ = 0; }
  uint32_t& back() { return data()[n_ - 1]; }
  void pop_back() { --n_; }
  void push_back(uint32_t f) {
    if (n_ == cap_) reserve(2 * cap_);
    data()[n_++] = f;
  }
  void reserve(size_t want) {
    if (want <= cap_) return;
    std::unique_ptr<uint32_t[]> h(new uint32_t[want]);
    std::copy(begin(), end(), h.get());
    heap_ = std::move(h);
    cap_ = uint32_t(want);
  }

 private:
  uint32_t* data() { return heap_ ? heap_.get() : inline_; }
  const uint32_t* data() const { return heap_ ? heap_.get() : inline_; }
  uint32_t n_ = 0, cap_ = kInline;
  uint32_t inline_[kInline];
  std::unique_ptr<uint32_t[]> heap_;
};

// The working mesh shared by the detection and the simplification: positions, faces with their
// alive flags, per-vertex incident faces and per-vertex feature neighbours.
class Work {
 public:
  std::vector<P3> P;
  std::vector<std::array<uint32_t, 3>> F;
  std::vector<char> alive;
  std::vector<FaceList> VF;
  std::vector<std::vector<uint32_t>> feat;
  std::vector<char> locked;
  std::vector<uint32_t> into;  // per vertex: the vertex it was collapsed into (itself while it stays)
  // While the parts' lanes of a mesh simplified in parts run (Simplify): the vertices of faces
  // that span two parts, which no lane moves or collapses into; null otherwise.
  const std::vector<char>* frozen = nullptr;
  std::unordered_set<uint64_t> swapMade;  // feature edges created by extension swaps
  std::unordered_set<uint64_t> seam;      // FeatureSimplifyParams::seamEdges: never swapped
  double diag = 0;
  double degenerateArea2 = 0;  // squared |cross| below which a face counts as degenerate

  FeatureInfo info;  // counts, classes and curvatures (mesh and featureEdges filled at the end)
  std::vector<VertexClass> cls;
  std::vector<double> K, M;

  Status Build(const IndexedMesh& in, const FeatureSimplifyParams& p);

  bool IsFeature(uint32_t a, uint32_t b) const {
    for (uint32_t x : feat[a])
      if (x == b) return true;
    return false;
  }
  void AddFeature(uint32_t a, uint32_t b) {
    if (!IsFeature(a, b)) {
      feat[a].push_back(b);
      feat[b].push_back(a);
    }
  }
  void RemoveFeature(uint32_t a, uint32_t b) {
    auto drop = [](std::vector<uint32_t>& v, uint32_t x) {
      auto it = std::find(v.begin(), v.end(), x);
      if (it != v.end()) {
        *it = v.back();
        v.pop_back();
      }
    };
    drop(feat[a], b);
    drop(feat[b], a);
  }
  P3 Cross(uint32_t f) const {
    const auto& t = F[f];
    return (P[t[1]] - P[t[0]]) ^ (P[t[2]] - P[t[0]]);
  }
  // (Here and in the fan loops below, `|` instead of `||`: which corner matches is data, not a
  // pattern a branch predictor can learn.)
  bool Contains(uint32_t f, uint32_t v) const { return (F[f][0] == v) | (F[f][1] == v) | (F[f][2] == v); }
  // Faces containing both a and b, written to out (at most `cap`); returns the count.
  int EdgeFaces(uint32_t a, uint32_t b, uint32_t* out, int cap) const {
    int n = 0;
    for (uint32_t f : VF[a])
      if (Contains(f, b)) {
        if (n < cap) out[n] = f;
        ++n;
      }
    return n;
  }
  uint32_t Third(uint32_t f, uint32_t a, uint32_t b) const {
    for (uint32_t v : F[f])
      if (v != a && v != b) return v;
    return kNone;
  }
  bool HasEdge(uint32_t a, uint32_t b) const {
    for (uint32_t f : VF[a])
      if (Contains(f, b)) return true;
    return false;
  }
  void RemoveFaceFrom(uint32_t v, uint32_t f) {
    auto& l = VF[v];
    auto it = std::find(l.begin(), l.end(), f);
    if (it != l.end()) {
      *it = l.back();
      l.pop_back();
    }
  }

  double CurvatureK(uint32_t v) const;
  // Corner angles (radians) and area of a face, computed once per version of the face: the
  // curvature K of a vertex is recomputed whenever its fan changes, but a collapse changes only a
  // few of the faces around it.
  struct FaceAngles {
    double corner[3];
    double area;
  };
  mutable std::vector<FaceAngles> faceAngles;
  mutable std::vector<char> faceAnglesValid;  // 0: the face changed since (or never computed)
  const FaceAngles& Angles(uint32_t f) const;
  double CurvatureM(uint32_t v) const;
  bool IsManifoldVertex(uint32_t v, std::vector<uint32_t>& verts, std::vector<uint32_t>& parent,
                        std::vector<int>& degree) const;
  void ExtendFeatureLines(double featureAngleDeg);
  // On `threads` threads; every face's angles must be valid (it only reads them).
  void Classify(const FeatureSimplifyParams& p, unsigned threads);
  void FillInfo();
};

const Work::FaceAngles& Work::Angles(uint32_t f) const {
  FaceAngles& a = faceAngles[f];
  if (!faceAnglesValid[f]) {
    faceAnglesValid[f] = 1;
    const auto& t = F[f];
    for (int i = 0; i < 3; ++i) {
      const P3& p = P[t[i]];
      a.corner[i] = AngleBetween(P[t[(i + 1) % 3]] - p, P[t[(i + 2) % 3]] - p);
    }
    a.area = 0.5 * Cross(f).Norm();
  }
  return a;
}

double Work::CurvatureK(uint32_t v) const {
  double angles = 0, area = 0;
  for (uint32_t f : VF[v]) {
    const auto& t = F[f];
    const int i = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
    const FaceAngles& a = Angles(f);
    angles += a.corner[i];
    area += a.area;
  }
  const double S = area / 3.0;
  return S > 0 ? (2 * kPi - angles) / S : 0.0;
}

double Work::CurvatureM(uint32_t v) const {
  if (feat[v].size() != 2) return 0;
  const P3 el = P[feat[v][0]] - P[v], er = P[feat[v][1]] - P[v];
  const double L = 0.5 * (el.Norm() + er.Norm());
  return L > 0 ? (kPi - AngleBetween(el, er)) / L : 0.0;
}

// One fan (a disk or a half-disk) around v: every link vertex used at most twice and the link
// connected.
bool Work::IsManifoldVertex(uint32_t v, std::vector<uint32_t>& verts, std::vector<uint32_t>& parent,
                            std::vector<int>& degree) const {
  const auto& fan = VF[v];
  if (fan.size() <= 1) return true;
  // Local link: its vertices, their degrees and union-find parents (fans are small).
  verts.clear();
  parent.clear();
  degree.clear();
  auto local = [&](uint32_t x) {
    for (size_t i = 0; i < verts.size(); ++i)
      if (verts[i] == x) return int(i);
    verts.push_back(x);
    parent.push_back(uint32_t(verts.size() - 1));
    degree.push_back(0);
    return int(verts.size() - 1);
  };
  for (uint32_t f : fan) {
    const auto& t = F[f];
    const int i = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
    const int a = local(t[(i + 1) % 3]), b = local(t[(i + 2) % 3]);
    if (++degree[size_t(a)] > 2 || ++degree[size_t(b)] > 2) return false;
    const uint32_t ra = FindRoot(parent, uint32_t(a)), rb = FindRoot(parent, uint32_t(b));
    if (ra != rb) parent[ra] = rb;
  }
  const uint32_t root = FindRoot(parent, 0);
  for (uint32_t i = 1; i < verts.size(); ++i)
    if (FindRoot(parent, i) != root) return false;
  return true;
}

Status Work::Build(const IndexedMesh& in, const FeatureSimplifyParams& p) {
  const size_t nv = in.positions.size(), nf = in.faces.size();
  P.resize(nv);
  for (size_t v = 0; v < nv; ++v) P[v] = P3::Construct(in.positions[v]);
  F = in.faces;
  alive.assign(nf, 1);
  VF.assign(nv, {});
  feat.assign(nv, {});
  locked.assign(nv, 0);
  diag = BoundingBoxDiagonal(in);
  degenerateArea2 = std::pow(1e-12 * diag * diag, 2);

  into.resize(nv);
  for (uint32_t v = 0; v < nv; ++v) into[v] = v;
  seam.clear();
  for (const auto& e : p.seamEdges)
    if (e[0] != e[1] && e[0] < nv && e[1] < nv) seam.insert(EdgeKey(e[0], e[1]));

  std::vector<uint32_t> valence(nv, 0);
  for (const auto& t : F)
    for (uint32_t v : t) ++valence[v];
  for (size_t v = 0; v < nv; ++v) VF[v].reserve(valence[v] + 2);
  for (uint32_t f = 0; f < nf; ++f) {
    const auto& t = F[f];
    if (UsesAVertexTwice(t)) {
      // A face with a repeated vertex has no proper fan: keep it as it is, lock its vertices.
      for (uint32_t v : t) locked[v] = 1;
    }
    VF[t[0]].push_back(f);
    if (t[1] != t[0]) VF[t[1]].push_back(f);
    if (t[2] != t[0] && t[2] != t[1]) VF[t[2]].push_back(f);
  }

  // Undirected edges with their faces: (key, face, directed-forward) records sorted by key, then
  // face. Bucketed by the smaller vertex first (in face order), then each small bucket is sorted:
  // the same order as one global sort, at a fraction of its cost (setup 163 -> 133 M instructions on the bunny).
  struct HalfEdge {
    uint64_t key;
    uint32_t face;
    uint32_t forward;
  };
  std::vector<uint32_t> start(nv + 1, 0);
  for (const auto& t : F)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a != b) ++start[std::min(a, b) + 1];
    }
  for (size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  std::vector<HalfEdge> he(start[nv]);
  {
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (uint32_t f = 0; f < nf; ++f) {
      const auto& t = F[f];
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = t[k], b = t[(k + 1) % 3];
        if (a == b) continue;
        he[fill[std::min(a, b)]++] = {EdgeKey(a, b), f, a < b ? 1u : 0u};
      }
    }
  }
  for (size_t v = 0; v < nv; ++v)  // insertion sort of each bucket (valence-sized)
    for (uint32_t i = start[v] + 1; i < start[v + 1]; ++i) {
      const HalfEdge x = he[i];
      uint32_t j = i;
      for (; j > start[v] && (he[j - 1].key > x.key || (he[j - 1].key == x.key && he[j - 1].face > x.face)); --j)
        he[j] = he[j - 1];
      he[j] = x;
    }
  const double cosLimit = std::cos((180.0 - p.featureAngleDeg) * kPi / 180.0);  // A <= A_t <=> cos(normals) <= this
  for (size_t i = 0; i < he.size();) {
    size_t j = i;
    while (j < he.size() && he[j].key == he[i].key) ++j;
    const uint32_t a = uint32_t(he[i].key >> 32), b = uint32_t(he[i].key & 0xffffffffu);
    const size_t n = j - i;
    if (n == 1) {
      AddFeature(a, b);
      ++info.borderEdges;
    } else if (n == 2) {
      P3 n0 = Cross(he[i].face), n1 = Cross(he[i + 1].face);
      const double l0 = n0.Norm(), l1 = n1.Norm();
      if (l0 * l0 > degenerateArea2 && l1 * l1 > degenerateArea2) {
        // Consistently oriented neighbours traverse the edge in opposite directions; otherwise
        // one normal is reversed before measuring the angle.
        if (he[i].forward == he[i + 1].forward) n1 = -n1;
        if ((n0 * n1) / (l0 * l1) <= cosLimit) {
          AddFeature(a, b);
          ++info.dihedralEdges;
        }
      }
      if (!seam.empty() && seam.count(he[i].key)) {
        AddFeature(a, b);
        ++info.seamEdges;
      }
    } else {
      AddFeature(a, b);
      locked[a] = locked[b] = 1;
      ++info.nonManifoldEdges;
    }
    i = j;
  }
  // The per-vertex and per-face passes below run on the first pass's threads (each writes its
  // own vertices' or faces' entries only).
  const unsigned threads = FeatureThreads(p);
  ParallelChunks(nv, threads, kSetUpChunk, [&](size_t begin, size_t end, unsigned) {
    std::vector<uint32_t> verts, parent;  // scratch for the fan test
    std::vector<int> degree;
    for (size_t v = begin; v < end; ++v)
      if (!locked[v] && !IsManifoldVertex(uint32_t(v), verts, parent, degree)) locked[v] = 1;
  });

  if (p.extendFeatureLines) ExtendFeatureLines(p.featureAngleDeg);
  // Every face's corner angles and area now (the curvatures read nearly all of them), so that
  // Classify only reads them.
  faceAngles.resize(F.size());
  faceAnglesValid.assign(F.size(), 0);
  ParallelChunks(F.size(), threads, kSetUpChunk, [&](size_t begin, size_t end, unsigned) {
    for (size_t f = begin; f < end; ++f) Angles(uint32_t(f));
  });
  Classify(p, threads);
  return Status::Ok();
}

// §3.1, Fig. 3: extends feature lines that end at a vertex with one feature edge.
void Work::ExtendFeatureLines(double featureAngleDeg) {
  const double cosLimit = std::cos((180.0 - featureAngleDeg) * kPi / 180.0);
  const double cosTurn = std::cos(45.0 * kPi / 180.0);
  std::vector<uint32_t> work;
  for (uint32_t v = 0; v < P.size(); ++v)
    if (feat[v].size() == 1 && !locked[v]) work.push_back(v);
  size_t budget = F.size() * 3;  // every swap adds a swap-made edge, never swapped again
  while (!work.empty() && budget > 0) {
    const uint32_t c = work.back();
    work.pop_back();
    if (feat[c].size() != 1 || locked[c]) continue;
    const P3 dir = P[c] - P[feat[c][0]];
    if (!(dir.Norm() > 0)) continue;
    // Best candidate: the smallest turn, then the sharpest new edge.
    double bestTurn = -2, bestCos = 2;
    uint32_t bestF1 = kNone, bestF2 = kNone, bestA = 0, bestB = 0, bestD = 0;
    for (uint32_t f1 : VF[c]) {
      const auto& t = F[f1];
      const int i = t[0] == c ? 0 : (t[1] == c ? 1 : 2);
      const uint32_t a = t[(i + 1) % 3], b = t[(i + 2) % 3];  // f1 = (a, b, c) up to rotation
      if (a == b || a == c || b == c || locked[a] || locked[b]) continue;
      if (swapMade.count(EdgeKey(a, b)) || (!seam.empty() && seam.count(EdgeKey(a, b)))) continue;
      uint32_t ef[3];
      if (EdgeFaces(a, b, ef, 3) != 2) continue;
      const uint32_t f2 = ef[0] == f1 ? ef[1] : ef[0];
      const auto& u = F[f2];
      const int j = u[0] == b ? 0 : (u[1] == b ? 1 : 2);
      if (u[(j + 1) % 3] != a) continue;  // f2 must be (b, a, d): consistent orientation
      const uint32_t d = u[(j + 2) % 3];
      if (d == c || HasEdge(c, d)) continue;
      if (VF[a].size() < 4 || VF[b].size() < 4) continue;  // a and b keep a proper fan
      const P3 e = P[d] - P[c];
      const double turn = (dir * e) / (dir.Norm() * e.Norm());
      if (!(turn >= cosTurn)) continue;
      // New faces (a, d, c) and (d, b, c).
      const P3 o = Cross(f1) + Cross(f2);
      const P3 n1 = (P[d] - P[a]) ^ (P[c] - P[a]);
      const P3 n2 = (P[b] - P[d]) ^ (P[c] - P[d]);
      if (n1.SquaredNorm() <= degenerateArea2 || n2.SquaredNorm() <= degenerateArea2) continue;
      if (!(n1 * o > 0) || !(n2 * o > 0)) continue;
      const double cosN = (n1 * n2) / (n1.Norm() * n2.Norm());
      if (cosN > cosLimit) continue;  // the new edge is not sharp enough
      if (turn > bestTurn || (turn == bestTurn && cosN < bestCos)) {
        bestTurn = turn;
        bestCos = cosN;
        bestF1 = f1;
        bestF2 = f2;
        bestA = a;
        bestB = b;
        bestD = d;
      }
    }
    if (bestF1 == kNone) continue;
    const uint32_t a = bestA, b = bestB, d = bestD;
    F[bestF1] = {a, d, c};
    F[bestF2] = {d, b, c};
    RemoveFaceFrom(a, bestF2);
    RemoveFaceFrom(b, bestF1);
    VF[c].push_back(bestF2);
    VF[d].push_back(bestF1);
    if (IsFeature(a, b)) {
      RemoveFeature(a, b);
      ++info.removedBySwaps;
      if (feat[a].size() == 1) work.push_back(a);
      if (feat[b].size() == 1) work.push_back(b);
    }
    AddFeature(c, d);
    swapMade.insert(EdgeKey(c, d));
    ++info.swapEdges;
    --budget;
    if (feat[d].size() == 1) work.push_back(d);
  }
}

void Work::Classify(const FeatureSimplifyParams& p, unsigned threads) {
  const size_t nv = P.size();
  cls.assign(nv, VertexClass::Unused);
  K.assign(nv, 0.0);
  M.assign(nv, 0.0);
  const double d2 = diag * diag;
  ParallelChunks(nv, threads, kSetUpChunk, [&](size_t begin, size_t end, unsigned) {
    for (uint32_t v = uint32_t(begin); v < end; ++v) {
      if (VF[v].empty()) continue;
      const size_t fc = feat[v].size();
      if (locked[v] || fc == 1 || fc >= 3) {
        cls[v] = VertexClass::Feature;
      } else if (fc == 2) {
        cls[v] = VertexClass::FeatureLine;
        M[v] = CurvatureM(v);
      } else {
        K[v] = CurvatureK(v);
        cls[v] = (p.featureCurvature > 0 && std::abs(K[v]) * d2 >= p.featureCurvature) ? VertexClass::Feature
                                                                                       : VertexClass::Smooth;
      }
    }
  });
}

void Work::FillInfo() {
  info.vertexClass = cls;
  info.curvatureK = K;
  info.curvatureM = M;
  info.mesh.positions.resize(P.size());
  for (size_t v = 0; v < P.size(); ++v) info.mesh.positions[v] = vcg::Point3f::Construct(P[v]);
  info.mesh.faces.clear();
  for (size_t f = 0; f < F.size(); ++f)
    if (alive[f]) info.mesh.faces.push_back(F[f]);
  info.featureEdges.clear();
  for (uint32_t a = 0; a < feat.size(); ++a)
    for (uint32_t b : feat[a])
      if (a < b) info.featureEdges.push_back({a, b});
  std::sort(info.featureEdges.begin(), info.featureEdges.end());
}

// Per-face tracking of the error bound, shared by the engine and its evaluators.
struct TrackingStore {
  // face -> the removed original vertices it answers for, as positions (vertices never move, and
  // the error checks then read them in a row instead of looking each up in P)
  std::vector<std::vector<P3>> ownedStore;
  std::vector<double> outErrorStore;  // face -> bound on the distance from its points to the input
};

// What evaluating a vertex decided: nothing to do (no allowed edge), collapse it along `to`, or
// let it wait until the bound reaches `error`.
struct Evaluation {
  enum Kind : uint8_t { None, Collapse, Defer };
  Kind kind = None;
  uint32_t to = kNone;
  double d = 0;       // Collapse: the error distance d of the edge
  double outErr = 0;  // Collapse: the outward error estimate of the new faces
  double error = 0;   // Defer: the smallest bound under which the edge `to` may fit
};

// §3.3-3.4, the half of the engine that reads: ranks a vertex's edges and measures the error of
// the best one. It writes only its own scratch, so several evaluators may run at once while
// nothing is collapsed.
class Evaluator {
 public:
  Evaluator(Work& w, const FeatureSimplifyParams& p, TrackingStore& t)
      : w_(w), p_(p), owned_(t.ownedStore), outError_(t.outErrorStore), link_(w.P.size(), 0) {}

  // Checks the half-edge collapse from -> to; on success fills d (the paper's error distance:
  // from `from` to the nearest new face) and q (worst shape among the new faces). With
  // `topology` false the link condition is left to CheckTopology (the engine runs it only on the
  // candidate it is about to apply). With a finite `cutoff` (model units) d is exact only below
  // it, +infinity otherwise: ranking a vertex's edges needs the exact distance only for the edges
  // that can still beat the best one found so far.
  CollapseRefusal Check(uint32_t from, uint32_t to, double* d, double* q, bool topology = true,
                        double cutoff = std::numeric_limits<double>::infinity());
  CollapseRefusal CheckTopology(uint32_t from, uint32_t to);
  double NewFanQuality(uint32_t from, uint32_t to);
  // The paper's rule under the error bound `bound` (tracked when `track`): the allowed edge of v
  // with the smallest d, applied if its error fits, else v waits. `retryTo`: the edge known from
  // an earlier evaluation with the same fan (kNone: rank all edges). A function of the mesh
  // around v and of the tracking there.
  Evaluation Evaluate(uint32_t v, uint32_t retryTo, double bound, bool track);
  // Forgets the cached fan and link (the mesh changed since they were built).
  void ResetCaches() { fanOf_ = oldFanOf_ = linkFrom_ = kNone; }

 protected:
  struct FanFace {
    uint32_t face, x, y;  // the face is (from, x, y) in its own order
    P3 normal;            // its (unnormalised) normal before the collapse
  };
  void BuildFan(uint32_t from);
  void PrefetchRecord(uint32_t v) const {  // the vertex's faces (FaceList: two cache lines)
    const char* rec = reinterpret_cast<const char*>(&w_.VF[v]);
    Prefetch(rec);
    Prefetch(rec + 64);
  }
  P3 Corner(uint32_t f, int k, uint32_t from, uint32_t to) const {
    const uint32_t x = w_.F[f][size_t(k)];
    return w_.P[x == from ? to : x];
  }
  void GatherNewFan(uint32_t from, uint32_t to);
  // Squared distance from p to the new fan, trying newFanIds_[first] first (kNoTri: none); the
  // search stops once within `enough2` (the value is then some distance <= enough2).
  double DistanceToNewFan2(const P3& p, uint32_t from, uint32_t to, double enough2, size_t first) const;
  double CollapseError(uint32_t from, uint32_t to, double d, double limit);
  double OutwardError(uint32_t from, uint32_t to, double limit);

  Work& w_;
  const FeatureSimplifyParams& p_;
  std::vector<std::vector<P3>>& owned_;  // the TrackingStore's
  std::vector<double>& outError_;
  std::vector<FanFace> fan_;
  uint32_t fanOf_ = kNone, oldFanOf_ = kNone;
  std::vector<uint32_t> newFanIds_;  // faces around `to` after a collapse (GatherNewFan)
  size_t newFanFromBegin_ = 0;       // where from's faces (from -> to) start in newFanIds_
  std::vector<Tri> oldFan_;          // the faces around `from` before it, as triangles
  std::vector<uint32_t> link_;       // link_[x] == linkStamp_: x is a neighbour of linkFrom_
  uint32_t linkStamp_ = 0, linkFrom_ = kNone;
  struct Candidate {
    double d, q;
    uint32_t to;
  };
  std::vector<Candidate> cands_;
  std::vector<uint32_t> nbrs_;
};

// Whether the face t has vertices in two parts (its vertices are then seam vertices).
bool SpansParts(const std::vector<uint8_t>& part, const std::array<uint32_t, 3>& t) {
  return part[t[0]] != part[t[1]] || part[t[0]] != part[t[2]];
}

// The per-vertex state of the queues and of the tracking, shared by the lanes below: while the
// mesh is simplified in parts, each lane writes the entries of its own vertices only.
struct QueueState : TrackingStore {
  std::vector<uint32_t> stamp;     // the vertex's current queue entry
  std::vector<uint32_t> visit;     // == a lane's mark: seen in its current collapse
  std::vector<char> queued;        // v has a valid entry in its queue
  std::vector<char> fanChanged;    // v's fan changed while it was deferred
  std::vector<uint32_t> retry;     // readmitted with an unchanged fan: its ranking of edges (d, flips,
                                   // shapes: all from its own fan) is unchanged, so its edge is known
  std::vector<char> deferredMark;  // v waits in a deferred queue for a larger bound (its stored error
                                   // may be stale once its neighbourhood changes: it is re-evaluated
                                   // when the bound reaches it)
  // The first pass evaluated ahead (FirstPassAhead): every vertex's first evaluation, under the
  // first bound, depends on the input around it only. aheadStamp[v]: the queue entry it is for
  // (kNone: none, or no longer valid); a collapse invalidates those within two rings of it.
  std::vector<Evaluation> ahead;
  std::vector<uint32_t> aheadStamp;
  void Reset(size_t nv) {
    stamp.assign(nv, 0);
    visit.assign(nv, 0);
    queued.assign(nv, 0);
    fanChanged.assign(nv, 0);
    retry.assign(nv, kNone);
    deferredMark.assign(nv, 0);
  }
};

// §3.3-3.4: the collapse engine on a Work — one lane: its queues, its deferred vertices under the
// common error bound, its collapses. The whole mesh is one lane; a mesh simplified in parts has one
// lane per part and a seam lane (Simplify), and the parts' lanes run at the same time.
class FeatureSimplifier : public Evaluator {
 public:
  FeatureSimplifier(Work& w, const FeatureSimplifyParams& p, QueueState& q)
      : Evaluator(w, p, q),
        q_(q),
        stamp_(q.stamp),
        visit_(q.visit),
        queued_(q.queued),
        fanChanged_(q.fanChanged),
        retry_(q.retry),
        deferredMark_(q.deferredMark),
        ahead_(q.ahead),
        aheadStamp_(q.aheadStamp) {}

  void Collapse(uint32_t from, uint32_t to, double outErr);
  void Push(uint32_t v, bool recompute);
  // Pops and evaluates until both queues are empty (true) or `quota` faces have been removed
  // (false). progress (may be null) is called every 1024 pops with the percentage done, assuming
  // every lane of the round `lanes` removes as many faces as this one; cancelled is set when it
  // returns false, and ends the round of every lane.
  bool RunRound(size_t quota, const Progress* progress, size_t facesIn, size_t target, size_t facesBefore, size_t lanes,
                std::atomic<bool>& cancelled);
  // The error of the deferred vertex with the smallest error (false: none is deferred).
  bool SmallestDeferred(double& error);
  // Puts the deferred vertices under bound_ back in their queues.
  void Admit();
  bool FirstPassAhead(unsigned threads, const Progress& progress);
  // Lanes of a mesh simplified in parts (Simplify): the part of each vertex, the lanes by
  // part, and whether this is the seam lane (which runs alone, with Work::frozen lifted, on the
  // vertices of the seams and on the vertices their collapses touch).
  void SetParts(const std::vector<uint8_t>* part, std::vector<char>* seam, const std::vector<FeatureSimplifier*>* lanes,
                bool seamLane, uint32_t index, uint32_t count) {
    part_ = part;
    seam_ = seam;
    lanes_ = lanes;
    seamLane_ = seamLane;
    mark_ = index;  // visit_ marks unique to the lane
    markStep_ = count;
  }
  // A part's lane: queues for the seam lane the seam vertices Push was asked for.
  void HandPendingTo(FeatureSimplifier& seamLane);

  bool track_ = false;  // original vertices are tracked (an error bound is in force)
  bool grow_ = false;   // the bound grows until the target face count is reached
  double bound_ = std::numeric_limits<double>::infinity();
  size_t nK_ = 0, nM_ = 0;  // V_K and V_M vertices queued at the start (the queues' interleaving)
  size_t removed_ = 0;      // faces removed by this lane's collapses
  size_t collapses_ = 0;
  size_t faces_ = 0;  // faces of this lane's part at the start
  size_t aheadLeft_ = 0;
  uint32_t mark_ = 0;
  double maxD_ = 0, maxTracked_ = 0;

 private:
  struct Entry {
    float key;
    uint32_t v;
    uint32_t stamp;
    bool operator<(const Entry& o) const { return key > o.key; }  // min-heap
  };
  struct Deferred {
    double error;  // the smallest error bound under which one of v's collapses fits
    uint32_t v;
    uint32_t stamp;
    uint32_t to;  // the edge v -> to that was tried (the smallest d the topology allowed)
    bool operator<(const Deferred& o) const { return error > o.error; }  // min-heap
  };
  // CurvatureThreshold (§3.3): v (V_K or V_M) may be removed, |K| D^2 or |M| D under the threshold.
  bool Admitted(uint32_t v) const;
  // The inputs of CurvatureK(v), asked for ahead of a Push that recomputes it.
  void PrefetchCurvatureInputs(uint32_t v) const;
  void InvalidateAhead(uint32_t from, uint32_t to);
  // Whether evaluations made ahead may be left to drop: this lane's, or (the seam lane) any lane's.
  bool AheadToDrop() const { return (aheadLeft_ > 0 || seamLane_) && !aheadStamp_.empty(); }
  // v's evaluation made ahead, if any, is no longer used (its owner's count goes down).
  void DropAhead(uint32_t v) {
    if (aheadStamp_[v] == kNone) return;
    aheadStamp_[v] = kNone;
    --Owner(v).aheadLeft_;
  }

  QueueState& q_;
  std::vector<uint32_t>& stamp_;
  std::vector<uint32_t>& visit_;
  std::vector<char>& queued_;
  std::vector<char>& fanChanged_;
  std::vector<uint32_t>& retry_;
  std::vector<char>& deferredMark_;
  std::vector<Evaluation>& ahead_;
  std::vector<uint32_t>& aheadStamp_;
  std::priority_queue<Entry> heapK_, heapM_;
  std::priority_queue<Deferred> deferred_;
  std::vector<Deferred> admitted_;  // Admit's vertices to put back in their queues
  size_t popsK_ = 0, popsM_ = 0, iter_ = 0;
  // The lane whose first pass ahead covers v (its aheadLeft_), and whose deferred queue takes v.
  FeatureSimplifier& Owner(uint32_t v) {
    return part_ && !(seamLane_ && (*seam_)[v]) ? *(*lanes_)[(*part_)[v]] : *this;
  }
  const std::vector<uint8_t>* part_ = nullptr;
  std::vector<char>* seam_ = nullptr;
  uint32_t markStep_ = 1;
  const std::vector<FeatureSimplifier*>* lanes_ = nullptr;
  bool seamLane_ = false;
  std::vector<std::pair<uint32_t, bool>> pending_;  // seam vertices to push (recompute K / M)
  std::vector<Tri> newFan_;                         // the faces around `to` after a collapse, as triangles
  std::vector<P3> scratchPts_;                      // original vertices to re-assign after a collapse
  std::vector<size_t> scratchFirst_;                // for each, the triangle of newFan_ to try first
  std::vector<uint32_t> scratchRing_;
};

// The faces around `from` as (face, x, y, old normal) with (from, x, y) in the face's order:
// built once for all candidate edges of `from`.
void Evaluator::BuildFan(uint32_t from) {
  if (fanOf_ == from) return;
  fanOf_ = from;
  fan_.clear();
  oldFanOf_ = kNone;
  for (uint32_t f : w_.VF[from]) {
    const auto& t = w_.F[f];
    const int i = t[0] == from ? 0 : (t[1] == from ? 1 : 2);
    fan_.push_back({f, t[size_t((i + 1) % 3)], t[size_t((i + 2) % 3)], w_.Cross(f)});
  }
}

CollapseRefusal Evaluator::Check(uint32_t from, uint32_t to, double* dOut, double* qOut, bool topology, double cutoff) {
  Work& w = w_;
  if (from == to) return CollapseRefusal::NotAnEdge;
  if (w.frozen && ((*w.frozen)[from] | (*w.frozen)[to])) return CollapseRefusal::LockedVertex;
  BuildFan(from);
  int ne = 0;
  for (const FanFace& ff : fan_) ne += int((ff.x == to) | (ff.y == to));
  if (ne == 0) return CollapseRefusal::NotAnEdge;
  if (w.locked[from] || w.cls[from] == VertexClass::Feature || w.cls[from] == VertexClass::Unused)
    return CollapseRefusal::LockedVertex;
  if (ne > 2) return CollapseRefusal::Topology;
  if (w.cls[from] == VertexClass::FeatureLine) {
    if (w.feat[from].size() != 2 || (w.feat[from][0] != to && w.feat[from][1] != to))
      return CollapseRefusal::OffFeatureLine;
    const uint32_t other = w.feat[from][0] == to ? w.feat[from][1] : w.feat[from][0];
    if (w.IsFeature(to, other)) return CollapseRefusal::MergesFeatures;
  } else if (!w.feat[from].empty()) {
    return CollapseRefusal::OffFeatureLine;
  }
  // Geometry of the faces that stay, (from, x, y) -> (to, x, y): no flip, no degenerate face, no
  // duplicate face.
  const P3& pf = w.P[from];
  const P3& pt = w.P[to];
  const double cutoff2 = cutoff * cutoff;
  double d2 = cutoff2;  // faces whose plane is beyond the cutoff are not measured
  int modified = 0;
  for (const FanFace& ff : fan_) {
    if ((ff.x == to) | (ff.y == to)) continue;
    ++modified;
    const P3& px = w.P[ff.x];
    const P3& py = w.P[ff.y];
    const P3 nNew = (px - pt) ^ (py - pt);
    if (nNew.SquaredNorm() <= w.degenerateArea2) return CollapseRefusal::FlipsFace;
    if (ff.normal.SquaredNorm() > w.degenerateArea2 && !(nNew * ff.normal > 0)) return CollapseRefusal::FlipsFace;
    // The distance to the face's plane is a lower bound of the distance to the face.
    const double h = (pf - pt) * nNew;
    if (h * h < d2 * nNew.SquaredNorm()) d2 = std::min(d2, PointTriangleDistance2(pf, pt, px, py));
    if (fan_.size() <= 3) {
      // (to, x, y) must not already exist around `to` (a tetrahedron would fold onto itself).
      for (uint32_t g : w.VF[to])
        if (w.Contains(g, ff.x) && w.Contains(g, ff.y)) return CollapseRefusal::Topology;
    }
  }
  if (modified == 0) {
    // An ear (a border vertex with one face): measure against the faces left around `to`.
    d2 = std::numeric_limits<double>::infinity();
    for (uint32_t f : w.VF[to]) {
      if (w.Contains(f, from)) continue;
      const auto& t = w.F[f];
      d2 = std::min(d2, PointTriangleDistance2(pf, w.P[t[0]], w.P[t[1]], w.P[t[2]]));
    }
    if (!std::isfinite(d2)) return CollapseRefusal::Topology;  // would delete a whole piece
  }
  if (dOut) *dOut = d2 < cutoff2 ? std::sqrt(d2) : std::numeric_limits<double>::infinity();
  if (qOut) *qOut = NewFanQuality(from, to);
  return topology ? CheckTopology(from, to) : CollapseRefusal::None;
}

// The worst shape among the faces (to, x, y) that replace (from, x, y).
double Evaluator::NewFanQuality(uint32_t from, uint32_t to) {
  BuildFan(from);
  double q = 1;
  for (const FanFace& ff : fan_)
    if (ff.x != to && ff.y != to) q = std::min(q, TriangleQuality(w_.P[to], w_.P[ff.x], w_.P[ff.y]));
  return q;
}

// The link condition (the common neighbours of `from` and `to` are the vertices opposite their
// edge) and no pinch of the border.
CollapseRefusal Evaluator::CheckTopology(uint32_t from, uint32_t to) {
  Work& w = w_;
  uint32_t ef[3];
  const int ne = w.EdgeFaces(from, to, ef, 3);
  uint32_t opp[2] = {kNone, kNone};
  for (int i = 0; i < ne; ++i) opp[i] = w.Third(ef[i], from, to);
  if (linkFrom_ != from) {  // mark from's neighbours once for all its candidate edges
    linkFrom_ = from;
    ++linkStamp_;
    for (uint32_t f : w.VF[from])
      for (uint32_t x : w.F[f]) link_[x] = linkStamp_;
  }
  for (uint32_t f : w.VF[to])
    for (uint32_t x : w.F[f])  // a common neighbour other than the opposite vertices
      if ((link_[x] == linkStamp_) & (x != to) & (x != from) & (x != opp[0]) & (x != opp[1]))
        return CollapseRefusal::Topology;
  // An interior edge between two border vertices would pinch the surface.
  if (ne == 2) {
    auto onBorder = [&](uint32_t v) {
      for (uint32_t x : w.feat[v]) {
        uint32_t tmp[3];
        if (w.EdgeFaces(v, x, tmp, 3) == 1) return true;
      }
      return false;
    };
    if (onBorder(from) && onBorder(to)) return CollapseRefusal::Topology;
  }
  return CollapseRefusal::None;
}

// The faces around `to` after the collapse: to's own faces that stay, then the modified faces
// of `from` (from -> to). As face ids for the one-off checks, as triangles for the re-assignment.
void Evaluator::GatherNewFan(uint32_t from, uint32_t to) {
  newFanIds_.clear();
  for (uint32_t f : w_.VF[to])
    if (!w_.Contains(f, from)) newFanIds_.push_back(f);
  newFanFromBegin_ = newFanIds_.size();
  for (uint32_t f : w_.VF[from])
    if (!w_.Contains(f, to)) newFanIds_.push_back(f);
}

double Evaluator::DistanceToNewFan2(const P3& p, uint32_t from, uint32_t to, double enough2, size_t first) const {
  auto dist2 = [&](uint32_t f) {
    return PointTriangleDistance2(p, Corner(f, 0, from, to), Corner(f, 1, from, to), Corner(f, 2, from, to));
  };
  double best = std::numeric_limits<double>::infinity();
  if (first < newFanIds_.size()) {
    best = dist2(newFanIds_[first]);
    if (best <= enough2) return best;
  }
  for (size_t i = 0; i < newFanIds_.size(); ++i) {
    if (i == first) continue;
    best = std::min(best, dist2(newFanIds_[i]));
    if (best <= enough2) break;
  }
  return best;
}

// The largest distance from `from` and the original vertices its faces answer for to the new
// fan: exact when above `limit`, some value <= limit otherwise. A point's search stops at the
// first face within the limit, or within the largest distance found so far (it cannot raise the
// maximum then: the maximum stays exact). `from` itself comes first (its distance to the nearest
// new face, d, is known), then each point is tried first against the new version of the face it
// answered for.
double Evaluator::CollapseError(uint32_t from, uint32_t to, double d, double limit) {
  GatherNewFan(from, to);
  if (newFanIds_.empty()) return std::numeric_limits<double>::infinity();
  const double limit2 = limit * limit;
  if (d > limit) {
    const double worst = std::sqrt(DistanceToNewFan2(w_.P[from], from, to, limit2, kNoTri));
    if (worst > limit) return worst;
  }
  double worst2 = 0;  // squared: the root of the largest square is the largest root
  size_t next = newFanFromBegin_;
  for (uint32_t f : w_.VF[from]) {
    // Where to look first: a face that stays, at its new version; one that dies (from, to, o),
    // at the new face beyond its edge (from, o), which takes o's side of it.
    size_t first = kNoTri;
    if (!w_.Contains(f, to)) {
      first = next++;
    } else if (!owned_[f].empty()) {
      const uint32_t o = w_.Third(f, from, to);
      for (size_t i = newFanFromBegin_; i < newFanIds_.size() && first == kNoTri; ++i)
        if (w_.Contains(newFanIds_[i], o)) first = i;
    }
    for (const P3& x : owned_[f])
      worst2 = std::max(worst2, DistanceToNewFan2(x, from, to, std::max(limit2, worst2), first));
  }
  return std::sqrt(worst2);
}

// The other direction (output -> input), which the original vertices cannot see (a new face may
// overhang a concave edge while every removed vertex stays on it): sample points of the new faces
// (centroid and the midpoints of the new edges) against the old faces around `from`, plus the
// bound those old faces already carried. Sampled, so an estimate; accumulated, so conservative
// along a chain of collapses. Returns early (some value > limit) once over `limit`.
double Evaluator::OutwardError(uint32_t from, uint32_t to, double limit) {
  BuildFan(from);
  double old = 0;
  for (uint32_t f : w_.VF[from]) old = std::max(old, outError_[f]);
  if (old > limit) return old;
  const double room2 = (limit - old) * (limit - old);
  double worst2 = 0;
  if (oldFanOf_ != from) {
    oldFanOf_ = from;
    oldFan_.clear();
    for (const FanFace& ff : fan_) oldFan_.push_back(MakeTri(w_.P[from], w_.P[ff.x], w_.P[ff.y], ff.face));
  }
  // Each sample is tried first against the old face its new face replaces (oldFan_ is in fan_'s
  // order): mostly the nearest, so the search stops there.
  const P3& u = w_.P[to];
  for (size_t i = 0; i < fan_.size(); ++i) {
    const FanFace& ff = fan_[i];
    if (ff.x == to || ff.y == to) continue;
    const P3 &px = w_.P[ff.x], &py = w_.P[ff.y];
    // A sample's search stops within the room or within the largest distance found so far (the
    // maximum stays exact).
    worst2 = std::max(worst2, DistanceToTris2((u + px + py) / 3.0, oldFan_, i, std::max(room2, worst2)));
    // New edges (to, x): each is the x edge of one new face (the y edge of its neighbour).
    worst2 = std::max(worst2, DistanceToTris2((u + px) * 0.5, oldFan_, i, std::max(room2, worst2)));
  }
  return std::max(old, std::sqrt(worst2));
}

Evaluation Evaluator::Evaluate(uint32_t v, uint32_t retryTo, double bound, bool track) {
  Work& w = w_;
  const VertexClass c = w.cls[v];
  const double tie = 1e-9 * w.diag;
  // Candidate edges: all of them for V_K, the two line edges for V_M (or the one edge known).
  std::vector<Candidate>& cands = cands_;
  cands.clear();
  if (retryTo != kNone) {
    double d = 0;
    const uint32_t u = retryTo;
    if (Check(v, u, &d, nullptr, false) == CollapseRefusal::None && CheckTopology(v, u) == CollapseRefusal::None)
      cands.push_back({d, 1.0, u});
  }
  if (cands.empty()) {
    std::vector<uint32_t>& nbrs = nbrs_;
    nbrs.clear();
    if (c == VertexClass::FeatureLine) {
      nbrs = w.feat[v];
    } else {
      BuildFan(v);
      for (const FanFace& ff : fan_) {
        if (std::find(nbrs.begin(), nbrs.end(), ff.x) == nbrs.end()) nbrs.push_back(ff.x);
        if (std::find(nbrs.begin(), nbrs.end(), ff.y) == nbrs.end()) nbrs.push_back(ff.y);
      }
    }
    // The topology check and the error checks of the chosen edge read its end's record.
    for (uint32_t u : nbrs) PrefetchRecord(u);
    // Edges that cannot come within the tie of the best d so far skip the exact distances
    // (d = infinity); they are measured below only if the topology refuses the best edge.
    double best = std::numeric_limits<double>::infinity();
    for (uint32_t u : nbrs) {
      double d = 0;
      if (Check(v, u, &d, nullptr, false, best + tie) == CollapseRefusal::None) {
        cands.push_back({d, -1.0, u});
        best = std::min(best, d);
      }
    }
  }
  Evaluation ev;
  if (cands.empty()) return ev;
  // Smallest error distance d (Fig. 8); near-ties (flat regions) go to the better triangle shape.
  double dMin = std::numeric_limits<double>::infinity();
  for (const Candidate& cd : cands) dMin = std::min(dMin, cd.d);
  for (Candidate& cd : cands)
    if (cd.d <= dMin + tie) cd.q = NewFanQuality(v, cd.to);
  auto byDistance = [tie](const Candidate& a, const Candidate& b) {
    if (std::abs(a.d - b.d) > tie) return a.d < b.d;
    return a.q > b.q;
  };
  std::sort(cands.begin(), cands.end(), byDistance);
  for (size_t i = 0; i < cands.size(); ++i) {
    if (i == 1 && !std::isfinite(cands.back().d)) {
      // The topology refused the best edge: measure the edges the cutoff skipped, rank again.
      for (size_t j = 1; j < cands.size(); ++j)
        if (!std::isfinite(cands[j].d)) Check(v, cands[j].to, &cands[j].d, nullptr, false);
      std::sort(cands.begin() + 1, cands.end(), byDistance);
    }
    const Candidate& cd = cands[i];
    // The paper's rule: the edge with the smallest d (among those the topology allows) is the
    // one; under an error bound it is applied or the vertex waits for a larger bound.
    if (CheckTopology(v, cd.to) != CollapseRefusal::None) continue;
    double outErr = 0;
    if (track) {
      const double err = CollapseError(v, cd.to, cd.d, bound);
      if (err > bound) {
        ev.kind = Evaluation::Defer;
        ev.to = cd.to;
        ev.error = err;
        return ev;
      }
      outErr = OutwardError(v, cd.to, bound);
      if (outErr > bound) {
        ev.kind = Evaluation::Defer;
        ev.to = cd.to;
        ev.error = outErr;
        return ev;
      }
    }
    ev.kind = Evaluation::Collapse;
    ev.to = cd.to;
    ev.d = cd.d;
    ev.outErr = outErr;
    return ev;
  }
  ev.kind = Evaluation::Defer;  // every edge refused by the topology: nothing to wait for
  ev.error = std::numeric_limits<double>::infinity();
  return ev;
}

void FeatureSimplifier::Collapse(uint32_t from, uint32_t to, double outErr) {
  Work& w = w_;
  ResetCaches();
  const bool track = track_;
  if (track) {
    GatherNewFan(from, to);
    newFan_.clear();
    for (uint32_t f : newFanIds_)
      newFan_.push_back(MakeTri(Corner(f, 0, from, to), Corner(f, 1, from, to), Corner(f, 2, from, to), f));
    // The points to re-assign, each with the index in newFan_ of the new version of the face it
    // answered for (where to look first; none for `from` and for the faces that die).
    scratchPts_.clear();
    scratchFirst_.clear();
    scratchPts_.push_back(w.P[from]);
    scratchFirst_.push_back(kNoTri);
    size_t next = newFanFromBegin_;
    for (uint32_t f : w.VF[from]) {
      const size_t first = w.Contains(f, to) ? kNoTri : next++;
      for (const P3& x : owned_[f]) {
        scratchPts_.push_back(x);
        scratchFirst_.push_back(first);
      }
      owned_[f].clear();
    }
  }
  scratchRing_.clear();
  for (uint32_t f : w.VF[from])
    for (uint32_t x : w.F[f])
      if (x != from && x != to && std::find(scratchRing_.begin(), scratchRing_.end(), x) == scratchRing_.end())
        scratchRing_.push_back(x);
  // The curvatures of the ring are recomputed below (Push): ask for the records now.
  for (uint32_t x : scratchRing_) PrefetchRecord(x);
  // Feature edges: from's line edges (from, other) become (to, other).
  if (w.cls[from] == VertexClass::FeatureLine) {
    const uint32_t other = w.feat[from][0] == to ? w.feat[from][1] : w.feat[from][0];
    w.RemoveFeature(from, to);
    w.RemoveFeature(from, other);
    w.AddFeature(to, other);
  }
  // Faces: those on the edge die, the others take `to` instead of `from`.
  for (uint32_t f : w.VF[from]) {
    auto& t = w.F[f];
    if (w.Contains(f, to)) {
      w.alive[f] = 0;
      ++removed_;
      for (uint32_t x : t)
        if (x != from) w.RemoveFaceFrom(x, f);
    } else {
      for (auto& x : t)
        if (x == from) x = to;
      w.faceAnglesValid[f] = 0;
      w.VF[to].push_back(f);
      if (track) outError_[f] = outErr;
    }
  }
  w.VF[from].clear();
  w.cls[from] = VertexClass::Unused;
  w.into[from] = to;  // (lanes collapse different vertices: each writes its own entries)
  if (AheadToDrop()) InvalidateAhead(from, to);
  // ... and for their faces' corners and angles, read by Push after the re-assignment below.
  for (uint32_t x : scratchRing_) PrefetchCurvatureInputs(x);
  if (track) {
    // Each removed original vertex answers to its nearest face of the new fan.
    double worst = 0;
    for (size_t i = 0; i < scratchPts_.size(); ++i) {
      const P3& x = scratchPts_[i];
      size_t nearest = 0;
      const double d2 = DistanceToTris2(x, newFan_, scratchFirst_[i], 0.0, &nearest);
      if (!newFan_.empty()) owned_[newFan_[nearest].face].push_back(x);
      worst = std::max(worst, std::sqrt(d2));
    }
    maxTracked_ = std::max(maxTracked_, worst);
  }
  // The fans of `to` and of from's old ring changed: their curvatures are recomputed. The rest of
  // to's ring kept its fan, but its collapses into `to` may have become possible: vertices found
  // stuck before go back into their queue.
  // A `to` that waits for a larger bound keeps waiting with the error it was deferred with, like
  // the deferred vertices of from's ring: absorbing `from` gives its fan from's removed vertices to
  // cover as well, and on the bunny 96 % of such `to`s evaluated at once were deferred again.
  mark_ += markStep_;
  if (seamLane_) {
    // A face that now spans two parts makes its vertices seam vertices (the parts' lanes leave
    // them to this lane from now on); an evaluation made ahead for one is dropped.
    for (uint32_t f : w.VF[to]) {
      if (!SpansParts(*part_, w.F[f])) continue;
      for (uint32_t x : w.F[f]) {
        if ((*seam_)[x]) continue;
        if (!aheadStamp_.empty()) DropAhead(x);
        (*seam_)[x] = 1;
      }
    }
  }
  if (deferredMark_[to])
    fanChanged_[to] = 1;
  else
    Push(to, true);
  visit_[to] = mark_;
  for (uint32_t x : scratchRing_) {
    visit_[x] = mark_;
    if (!deferredMark_[x])
      Push(x, true);
    else
      fanChanged_[x] = 1;  // its curvature is recomputed when the bound admits it again
  }
  for (uint32_t f : w.VF[to])
    for (uint32_t x : w.F[f])
      if (visit_[x] != mark_) {
        visit_[x] = mark_;
        if (!queued_[x] && !deferredMark_[x]) Push(x, false);
      }
}

bool FeatureSimplifier::Admitted(uint32_t v) const {
  if (p_.curvatureThreshold <= 0) return true;
  const Work& w = w_;
  const double curv =
      w.cls[v] == VertexClass::Smooth ? std::abs(w.K[v]) * (w.diag * w.diag) : std::abs(w.M[v]) * w.diag;
  return curv < p_.curvatureThreshold;
}

void FeatureSimplifier::PrefetchCurvatureInputs(uint32_t v) const {
  for (uint32_t f : w_.VF[v]) {
    Prefetch(&w_.F[f]);
    Prefetch(&w_.faceAngles[f]);
  }
}

void FeatureSimplifier::Push(uint32_t v, bool recompute) {
  Work& w = w_;
  if (!seamLane_ && w.frozen && (*w.frozen)[v]) {  // a seam vertex: the seam lane's
    pending_.push_back({v, recompute});
    return;
  }
  ++stamp_[v];
  deferredMark_[v] = 0;
  retry_[v] = kNone;
  recompute = recompute || fanChanged_[v];
  fanChanged_[v] = 0;
  if (w.cls[v] == VertexClass::Smooth) {
    if (recompute) w.K[v] = w.CurvatureK(v);
    heapK_.push({float(std::abs(w.K[v])), v, stamp_[v]});
    queued_[v] = 1;
  } else if (w.cls[v] == VertexClass::FeatureLine) {
    if (recompute) w.M[v] = w.CurvatureM(v);
    heapM_.push({float(std::abs(w.M[v])), v, stamp_[v]});
    queued_[v] = 1;
  }
}

// The smallest error among the deferred vertices (stale entries dropped): the next bound is at
// least this (and at least x1.25 the current one, so that each round admits many vertices).
bool FeatureSimplifier::SmallestDeferred(double& error) {
  while (!deferred_.empty() && deferred_.top().stamp != stamp_[deferred_.top().v]) deferred_.pop();
  if (deferred_.empty()) return false;
  error = deferred_.top().error;
  return true;
}

void FeatureSimplifier::Admit() {
  admitted_.clear();
  while (!deferred_.empty() && deferred_.top().error <= bound_) {
    const Deferred d = deferred_.top();
    deferred_.pop();
    if (d.stamp == stamp_[d.v] && !queued_[d.v]) admitted_.push_back(d);
  }
  // Pushed in the same order; a vertex whose fan changed has its curvature recomputed, which
  // reads its faces and their angles, scattered: asked for a few vertices ahead.
  constexpr size_t kRecordAhead = 8, kFacesAhead = 4;
  for (size_t i = 0; i < admitted_.size(); ++i) {
    if (i + kRecordAhead < admitted_.size()) PrefetchRecord(admitted_[i + kRecordAhead].v);
    if (i + kFacesAhead < admitted_.size() && fanChanged_[admitted_[i + kFacesAhead].v])
      PrefetchCurvatureInputs(admitted_[i + kFacesAhead].v);
    const Deferred& d = admitted_[i];
    const bool same = !fanChanged_[d.v];
    Push(d.v, false);
    if (same) retry_[d.v] = d.to;
  }
}

// Evaluates every queued vertex the curvature threshold admits under the first bound,
// in index order, split over `threads` threads (this one included). Each writes only ahead_ and
// aheadStamp_ of its own vertices and its evaluator's scratch; nothing is collapsed meanwhile.
// If a thread fails, nothing made ahead is used. Progress is reported (and cancellation seen)
// on this thread only, between chunks; false: cancelled.
bool FeatureSimplifier::FirstPassAhead(unsigned threads, const Progress& progress) {
  const uint32_t nv = uint32_t(w_.P.size());
  ahead_.assign(nv, Evaluation());
  aheadStamp_.assign(nv, kNone);
  std::vector<uint32_t> batch;
  for (uint32_t v = 0; v < nv; ++v)
    if (queued_[v] && Admitted(v)) batch.push_back(v);  // queued: V_K or V_M (Push)
  const size_t n = batch.size();
  constexpr size_t kChunk = 512;
  threads = unsigned(std::min<size_t>(threads, (n + kChunk - 1) / kChunk));
  std::vector<Evaluator> helpers;  // one per thread beside this one (whose evaluator is *this)
  try {
    helpers.reserve(threads > 1 ? threads - 1 : 0);
    for (unsigned t = 1; t < threads; ++t) helpers.emplace_back(w_, p_, static_cast<TrackingStore&>(q_));
  } catch (...) {
    // no room for more: fewer threads
  }
  std::atomic<bool> cancelled(false);
  bool failed = false;
  try {
    ParallelChunks(n, unsigned(helpers.size() + 1), kChunk, [&](size_t begin, size_t end, unsigned thread) {
      if (cancelled) return;
      Evaluator& ev = thread == 0 ? *this : helpers[thread - 1];
      for (size_t i = begin; i < end; ++i) {
        const uint32_t v = batch[i];
        ahead_[v] = ev.Evaluate(v, kNone, bound_, track_);
        aheadStamp_[v] = stamp_[v];
      }
      if (thread == 0 && progress && !progress(0, "feature-preserving simplification")) cancelled = true;
    });
  } catch (...) {
    failed = true;
  }
  ResetCaches();
  if (failed || cancelled) {
    aheadStamp_.assign(nv, kNone);
    aheadLeft_ = 0;
    return !cancelled;
  }
  aheadLeft_ = n;
  return true;
}

// After a collapse: the evaluations made ahead that it may have changed — every vertex within two
// rings of `to` (from's old ring is in to's new one), since an evaluation reads its vertex's fan
// and its neighbours' fans, feature edges and tracking — are no longer used.
void FeatureSimplifier::InvalidateAhead(uint32_t from, uint32_t to) {
  DropAhead(from);
  DropAhead(to);
  for (uint32_t f : w_.VF[to])
    for (uint32_t y : w_.F[f])
      for (uint32_t g : w_.VF[y])
        for (uint32_t z : w_.F[g]) DropAhead(z);
}

bool FeatureSimplifier::RunRound(size_t quota, const Progress* progress, size_t facesIn, size_t target,
                                 size_t facesBefore, size_t lanes, std::atomic<bool>& cancelled) {
  Work& w = w_;
  const size_t start = removed_;
  while (removed_ - start < quota) {
    const bool haveK = !heapK_.empty(), haveM = !heapM_.empty();
    if (!haveK && !haveM) return true;
    // Interleave the two queues in proportion to their initial sizes.
    const bool takeK = haveK && (!haveM || double(popsK_ + 1) * double(nM_) <= double(popsM_ + 1) * double(nK_));
    auto& heap = takeK ? heapK_ : heapM_;
    const Entry e = heap.top();
    heap.pop();
    const uint32_t v = e.v;
    if (e.stamp != stamp_[v]) continue;  // stale
    // The vertex most likely next (the new top of this queue): its record now, its faces at the
    // end of this iteration, so that its misses overlap this evaluation.
    // A vertex readmitted with its fan unchanged retries one known edge: its end's record too.
    uint32_t ahead = kNone, aheadTo = kNone;
    if (!heap.empty()) {
      ahead = heap.top().v;
      PrefetchRecord(ahead);
      aheadTo = retry_[ahead];
      if (aheadTo != kNone) PrefetchRecord(aheadTo);
    }
    const VertexClass c = w.cls[v];
    if (c != (takeK ? VertexClass::Smooth : VertexClass::FeatureLine)) continue;
    queued_[v] = 0;
    (takeK ? popsK_ : popsM_) += 1;
    if ((++iter_ & 1023) == 0) {
      // Cancelled (here or by the report of another lane on this thread): no further report.
      if (cancelled) return false;
      if (progress && *progress) {
        const size_t done = facesIn - facesBefore + (removed_ - start) * lanes;
        const int pct = target > 0 ? int(100.0 * double(done) / double(facesIn - target))
                                   : int(100.0 * double(popsK_ + popsM_) / double(nK_ + nM_ + 1));
        if (!(*progress)(std::min(99, std::max(0, pct)), "feature-preserving simplification")) {
          cancelled = true;
          return false;
        }
      }
    }
    if (!Admitted(v)) continue;
    // The evaluation made ahead in the first pass, if nothing it read has changed since.
    // (The seam lane does not use them: they were made with the seams frozen.)
    bool useAhead = false;
    if (AheadToDrop() && aheadStamp_[v] != kNone) {  // made ahead: used, or dropped as outdated
      useAhead = !seamLane_ && aheadStamp_[v] == e.stamp && retry_[v] == kNone;
      DropAhead(v);
    }
    const Evaluation ev = useAhead ? ahead_[v] : Evaluate(v, retry_[v], bound_, track_);
    retry_[v] = kNone;
    if (ev.kind == Evaluation::Collapse) {
      maxD_ = std::max(maxD_, ev.d);
      Collapse(v, ev.to, ev.outErr);
      ++collapses_;
    } else if (ev.kind == Evaluation::Defer && grow_ && std::isfinite(ev.error)) {
      Owner(v).deferred_.push({ev.error, v, stamp_[v], ev.to});
      deferredMark_[v] = 1;
    } else if (ev.kind == Evaluation::None) {
      continue;
    }
    if (ahead != kNone && w.cls[ahead] != VertexClass::Unused)
      for (uint32_t f : w.VF[ahead]) {
        Prefetch(&w.F[f]);
        if (track_) {
          Prefetch(&owned_[f]);
          Prefetch(&outError_[f]);
        }
      }
    if (aheadTo != kNone && w.cls[aheadTo] != VertexClass::Unused)
      for (uint32_t f : w.VF[aheadTo]) Prefetch(&w.F[f]);
  }
  return false;
}

void FeatureSimplifier::HandPendingTo(FeatureSimplifier& seamLane) {
  for (const auto& x : pending_)
    if (!queued_[x.first] || x.second) seamLane.Push(x.first, x.second);
  pending_.clear();
}

// The number of parts a mesh is simplified in: 2, 4 or 8 with at least `facesPerPart` faces each,
// 1 (one piece) below 2 x facesPerPart or with facesPerPart 0.
unsigned PartCount(size_t faces, size_t facesPerPart) {
  unsigned parts = 1;
  if (facesPerPart == 0) return parts;
  while (parts < 8 && faces / (2 * parts) >= facesPerPart) parts *= 2;
  return parts;
}

// Vertex -> part: the used vertices cut at the median of their positions across the longest side
// of their box, each half again, and so on (ties by index). A function of the mesh only.
std::vector<uint8_t> CutIntoParts(const Work& w, unsigned parts) {
  std::vector<uint8_t> part(w.P.size(), 0);
  std::vector<uint32_t> verts;
  for (uint32_t v = 0; v < w.P.size(); ++v)
    if (w.cls[v] != VertexClass::Unused) verts.push_back(v);
  struct Range {
    size_t begin, end;
    unsigned first, count;  // the parts [first, first + count) share verts[begin, end)
  };
  std::vector<Range> todo{{0, verts.size(), 0, parts}};
  while (!todo.empty()) {
    const Range r = todo.back();
    todo.pop_back();
    if (r.count == 1) {
      for (size_t i = r.begin; i < r.end; ++i) part[verts[i]] = uint8_t(r.first);
      continue;
    }
    vcg::Box3d box;
    for (size_t i = r.begin; i < r.end; ++i) box.Add(w.P[verts[i]]);
    const int axis = box.MaxDim();
    const size_t mid = r.begin + (r.end - r.begin) / 2;
    std::nth_element(verts.begin() + long(r.begin), verts.begin() + long(mid), verts.begin() + long(r.end),
                     [&](uint32_t a, uint32_t b) {
                       const double pa = w.P[a][axis], pb = w.P[b][axis];
                       return pa < pb || (pa == pb && a < b);
                     });
    todo.push_back({r.begin, mid, r.first, r.count / 2});
    todo.push_back({mid, r.end, r.first + r.count / 2, r.count / 2});
  }
  return part;
}

// Runs the lanes' rounds under the common error bound until the face count reaches the target
// (0: none) or no collapse fits the largest bound allowed. In each round (one bound) the parts'
// lanes run at the same time on up to `threads` threads, with the seams frozen, until their queues
// are empty; then the seam lane (if any) alone, with the seams free, on the seam vertices that
// were admitted or touched meanwhile and whatever their collapses touch; then the bound is raised.
// A round that reaches the target is shared between the parts' lanes still busy in proportion to
// their faces, so that the result depends neither on which lane runs first nor on the number of
// threads. Progress is reported on this thread only. False: cancelled.
bool RunLanes(Work& w, const std::vector<FeatureSimplifier*>& lanes, FeatureSimplifier* seamLane,
              const FeatureSimplifyParams& p, size_t facesIn, unsigned threads, const Progress& progress) {
  const size_t target = p.targetFaceCount;
  const std::vector<char>* seam = w.frozen;  // lifted while the seam lane runs
  std::atomic<bool> cancelled(false);
  std::vector<char> exhausted(lanes.size(), 0);
  std::vector<char> admit(lanes.size(), 0);  // the bound was raised since the lane last ran
  bool seamAdmit = false, seamDone = seamLane == nullptr;
  for (;;) {
    size_t removed = seamLane ? seamLane->removed_ : 0;
    for (const FeatureSimplifier* l : lanes) removed += l->removed_;
    const size_t faces = facesIn - removed;
    if (target > 0 && faces <= target) return true;
    std::vector<size_t> active;
    size_t activeFaces = 0;
    for (size_t i = 0; i < lanes.size(); ++i)
      if (!exhausted[i]) {
        active.push_back(i);
        activeFaces += lanes[i]->faces_ - lanes[i]->removed_;
      }
    if (!active.empty()) {
      // The faces left to remove, shared in proportion to the lanes' faces (rounded down, the rest
      // one each to the first lanes): together exactly what is left.
      std::vector<size_t> quota(lanes.size(), std::numeric_limits<size_t>::max());
      if (target > 0) {
        const size_t left = faces - target;
        size_t given = 0;
        for (size_t i : active) {
          const size_t own = lanes[i]->faces_ - lanes[i]->removed_;
          quota[i] = activeFaces > 0 ? left * own / activeFaces : left / active.size();
          given += quota[i];
        }
        for (size_t k = 0; given < left; k = (k + 1) % active.size(), ++given) ++quota[active[k]];
        size_t kept = 0;
        for (size_t i : active)
          if (quota[i] > 0) active[kept++] = i;
        active.resize(kept);
      }
      auto run = [&](size_t i, bool reporting) {
        if (cancelled) return;  // a lane not started after a cancel is not started
        FeatureSimplifier& l = *lanes[i];
        if (admit[i]) l.Admit();
        admit[i] = 0;
        if (l.RunRound(quota[i], reporting ? &progress : nullptr, facesIn, target, faces, active.size(), cancelled))
          exhausted[i] = 1;
      };
      if (active.size() == 1 || threads <= 1) {
        for (size_t i : active) run(i, true);
      } else {
        ParallelChunks(active.size(), threads, 1,
                       [&](size_t begin, size_t, unsigned thread) { run(active[begin], thread == 0); });
      }
      if (cancelled) return false;
      continue;
    }
    if (!seamDone) {
      w.frozen = nullptr;  // the seams are free while the seam lane runs alone
      for (FeatureSimplifier* l : lanes) l->HandPendingTo(*seamLane);
      if (seamAdmit) seamLane->Admit();
      seamLane->RunRound(target > 0 ? faces - target : std::numeric_limits<size_t>::max(), &progress, facesIn, target,
                         faces, 1, cancelled);
      w.frozen = seam;
      seamAdmit = false;
      seamDone = true;
      if (cancelled) return false;
      continue;
    }
    // Every queue is empty: raise the bound to admit the deferred vertex with the smallest error
    // (at least x1.25, so that each round admits many), or stop.
    if (!lanes[0]->grow_) return true;
    double smallest = std::numeric_limits<double>::infinity();
    bool any = false;
    auto consider = [&](FeatureSimplifier* l) {
      double e = 0;
      if (l->SmallestDeferred(e)) {
        any = true;
        smallest = std::min(smallest, e);
      }
    };
    for (FeatureSimplifier* l : lanes) consider(l);
    if (seamLane) consider(seamLane);
    if (!any) return true;
    double next = std::max(lanes[0]->bound_ * 1.25, smallest);
    if (p.maxErrorDistance > 0) {
      if (smallest > p.maxErrorDistance) return true;
      next = std::min(next, p.maxErrorDistance);
    }
    for (FeatureSimplifier* l : lanes) l->bound_ = next;
    if (seamLane) seamLane->bound_ = next;
    std::fill(exhausted.begin(), exhausted.end(), 0);
    std::fill(admit.begin(), admit.end(), 1);
    seamAdmit = true;
    seamDone = seamLane == nullptr;
  }
}

// The simplification of §3.3-3.4 on a Work. A large mesh (growing bound, at least 2 x
// facesPerPart faces) is simplified in parts, one lane per part, all at the same time: the
// vertices are cut by CutIntoParts, and those of the faces that span two parts (the seams) are
// frozen while the parts' lanes run, so that no collapse of one part reads or writes what
// another's does. In every round of the bound the seams' vertices then get their turn in the seam
// lane, alone, so that they too go in the order of their errors.
Status Simplify(Work& w, const FeatureSimplifyParams& p, FeatureSimplifyResult& out, const Progress& progress) {
  const size_t nv = w.P.size();
  QueueState q;
  q.Reset(nv);
  size_t facesIn = 0;
  for (char a : w.alive) facesIn += a ? 1 : 0;
  const size_t target = p.targetFaceCount;
  // Error bound: fixed at maxErrorDistance (§3.4), or, with a target face count and
  // growErrorBound, starting tiny and raised only when no collapse fits (up to maxErrorDistance
  // if given). Without either, the paper's pure curvature order runs untracked.
  const bool grow = target > 0 && p.growErrorBound;
  const bool track = grow || p.maxErrorDistance > 0;
  double bound =
      grow ? 1e-6 * w.diag : (p.maxErrorDistance > 0 ? p.maxErrorDistance : std::numeric_limits<double>::infinity());
  if (grow && p.maxErrorDistance > 0) bound = std::min(bound, p.maxErrorDistance);
  if (track) {
    q.ownedStore.assign(w.F.size(), {});
    q.outErrorStore.assign(w.F.size(), 0.0);
  }
  const unsigned parts = grow && target < facesIn ? PartCount(facesIn, p.facesPerPart) : 1;
  std::vector<uint8_t> part;
  std::vector<char> seam;  // the vertices of faces that span two parts
  if (parts > 1) {
    part = CutIntoParts(w, parts);
    seam.assign(nv, 0);
    for (uint32_t f = 0; f < w.F.size(); ++f)
      if (w.alive[f] && SpansParts(part, w.F[f]))
        for (uint32_t v : w.F[f]) seam[v] = 1;
  }
  std::vector<std::unique_ptr<FeatureSimplifier>> store;
  std::vector<FeatureSimplifier*> lanes;
  for (unsigned i = 0; i < parts + (parts > 1 ? 1 : 0); ++i) {
    store.emplace_back(new FeatureSimplifier(w, p, q));
    store.back()->track_ = track;
    store.back()->grow_ = grow;
    store.back()->bound_ = bound;
    if (i < parts) lanes.push_back(store.back().get());
  }
  FeatureSimplifier* seamLane = parts > 1 ? store.back().get() : nullptr;
  if (parts > 1) {
    for (unsigned i = 0; i < parts; ++i) lanes[i]->SetParts(&part, &seam, &lanes, false, i, parts + 1);
    seamLane->SetParts(&part, &seam, &lanes, true, parts, parts + 1);
  }
  auto laneOf = [&](uint32_t v) -> FeatureSimplifier& {
    if (parts == 1) return *lanes[0];
    return seam[v] ? *seamLane : *lanes[part[v]];
  };
  for (uint32_t f = 0; f < w.F.size(); ++f)
    if (w.alive[f]) (parts > 1 ? *lanes[part[w.F[f][0]]] : *lanes[0]).faces_ += 1;
  for (uint32_t v = 0; v < nv; ++v) {
    FeatureSimplifier& l = laneOf(v);
    if (w.cls[v] == VertexClass::Smooth) ++l.nK_;
    if (w.cls[v] == VertexClass::FeatureLine) ++l.nM_;
    if (&l != seamLane) l.Push(v, false);  // Classify has just computed K and M
  }
  const unsigned threads = FeatureThreads(p);
  w.frozen = parts > 1 ? &seam : nullptr;  // the parts' lanes (and their first pass) see the seams frozen
  if (grow && p.firstPassAhead) {
    // Every vertex's first evaluation (a sixth of the time) depends on the input only: made
    // here, in memory order and on every core, and used in the queue's order unless a collapse
    // has come within two rings of the vertex by then (the output is the same either way).
    if (!lanes[0]->FirstPassAhead(threads, progress)) {
      w.frozen = nullptr;
      return Status::Cancelled();
    }
    for (FeatureSimplifier* l : lanes) l->aheadLeft_ = 0;
    for (uint32_t v = 0; v < nv; ++v)
      if (q.aheadStamp[v] != kNone) laneOf(v).aheadLeft_ += 1;
  }
  // The seam vertices are queued last: the first pass ahead leaves them to the seam lane.
  if (seamLane)
    for (uint32_t v = 0; v < nv; ++v)
      if (seam[v]) seamLane->Push(v, false);
  const bool ok = RunLanes(w, lanes, seamLane, p, facesIn, threads, progress);
  w.frozen = nullptr;
  if (!ok) return Status::Cancelled();
  double maxD = 0, maxTracked = 0;
  for (const auto& l : store) {
    out.collapses += l->collapses_;
    maxD = std::max(maxD, l->maxD_);
    maxTracked = std::max(maxTracked, l->maxTracked_);
  }
  out.finalErrorBound = track ? lanes[0]->bound_ : 0.0;
  out.parts = parts;

  // Output: live faces and the vertices they use, in input order.
  std::vector<uint32_t> outIndex(nv, kNone);
  std::vector<char> used(nv, 0);
  out.mesh = IndexedMesh();
  for (uint32_t f = 0; f < w.F.size(); ++f) {
    if (!w.alive[f]) continue;
    for (uint32_t v : w.F[f]) used[v] = 1;
    out.mesh.faces.push_back(w.F[f]);
    out.inputFace.push_back(f);
  }
  for (uint32_t v = 0; v < nv; ++v) {
    if (!used[v]) continue;
    outIndex[v] = uint32_t(out.mesh.positions.size());
    out.mesh.positions.push_back(vcg::Point3f::Construct(w.P[v]));
    out.inputVertex.push_back(v);
    out.vertexClass.push_back(w.cls[v]);
  }
  for (auto& t : out.mesh.faces)
    for (auto& v : t) v = outIndex[v];
  // Each input vertex's survivor: follow its collapses to the vertex that stays.
  out.survivor.assign(nv, kNone);
  for (uint32_t v = 0; v < nv; ++v) {
    uint32_t s = v;
    while (w.into[s] != s) s = w.into[s];
    for (uint32_t x = v; w.into[x] != x;) {  // shorten the chains for the next ones
      const uint32_t next = w.into[x];
      w.into[x] = s;
      x = next;
    }
    out.survivor[v] = outIndex[s];
  }
  for (uint32_t a = 0; a < nv; ++a)
    for (uint32_t b : w.feat[a])
      if (a < b && outIndex[a] != kNone && outIndex[b] != kNone) out.featureEdges.push_back({outIndex[a], outIndex[b]});
  std::sort(out.featureEdges.begin(), out.featureEdges.end());
  out.facesIn = facesIn;
  out.facesOut = out.mesh.faces.size();
  out.maxCollapseDistance = maxD;
  out.maxTrackedError = maxTracked;
  out.targetReached = target > 0 && out.facesOut <= target;
  return Status::Ok();
}

Status ValidateAndCheckInput(const IndexedMesh& mesh, const FeatureSimplifyParams& p) {
  Status s = ValidateParams(p);
  if (!s.ok()) return s;
  return RequireValidForFaces(mesh);
}

}  // namespace

double DihedralAngleDeg(const vcg::Point3d& n0, const vcg::Point3d& n1) {
  return 180.0 - AngleBetween(n0, n1) * 180.0 / kPi;
}

double BoundingBoxDiagonal(const IndexedMesh& mesh) {
  const vcg::Box3d box = UsedVertexBox(mesh);
  return box.IsNull() ? 0.0 : box.Diag();
}

size_t FeatureInfo::count(VertexClass c) const { return size_t(std::count(vertexClass.begin(), vertexClass.end(), c)); }

Status ValidateParams(const FeatureSimplifyParams& p) {
  if (!(p.featureAngleDeg >= 0 && p.featureAngleDeg <= 180))
    return Status::Invalid("FeatureAngleDeg must be between 0 and 180 degrees (got " +
                           std::to_string(p.featureAngleDeg) + ")");
  if (!(p.featureCurvature >= 0) || !std::isfinite(p.featureCurvature))
    return Status::Invalid("FeatureCurvature must be >= 0 (0 = off)");
  if (!(p.curvatureThreshold >= 0) || !std::isfinite(p.curvatureThreshold))
    return Status::Invalid("CurvatureThreshold must be >= 0 (0 = no limit)");
  if (!(p.maxErrorDistance >= 0) || !std::isfinite(p.maxErrorDistance))
    return Status::Invalid("MaxErrorDistance must be >= 0 (0 = off)");
  return Status::Ok();
}

Status DetectFeatures(const IndexedMesh& mesh, const FeatureSimplifyParams& params, FeatureInfo& out) {
  out = FeatureInfo();
  Status s = ValidateAndCheckInput(mesh, params);
  if (!s.ok()) return s;
  Work w;
  s = w.Build(mesh, params);
  if (!s.ok()) return s;
  w.FillInfo();
  out = std::move(w.info);
  return Status::Ok();
}

Status FeatureSimplify(const IndexedMesh& mesh, const FeatureSimplifyParams& params, FeatureSimplifyResult& out,
                       const Progress& progress) {
  out = FeatureSimplifyResult();
  Status s = ValidateAndCheckInput(mesh, params);
  if (!s.ok()) return s;
  if (params.targetFaceCount == 0 && params.maxErrorDistance == 0)
    return Status::Invalid(
        "give a stop criterion: a target face count (TargetFaceNum) or an error distance "
        "(MaxErrorDistance)");
  if (progress && !progress(0, "feature detection")) return Status::Cancelled();
  Work w;
  s = w.Build(mesh, params);
  if (!s.ok()) return s;
  FeatureSimplifyResult r;
  r.featureEdgesIn = 0;
  for (uint32_t a = 0; a < w.feat.size(); ++a)
    for (uint32_t b : w.feat[a]) r.featureEdgesIn += a < b ? 1 : 0;
  r.swapEdges = w.info.swapEdges;
  for (VertexClass c : w.cls) {
    if (c == VertexClass::Feature) ++r.featureVertices;
    if (c == VertexClass::FeatureLine) ++r.lineVerticesIn;
    if (c == VertexClass::Smooth) ++r.smoothVerticesIn;
  }
  s = Simplify(w, params, r, progress);
  if (!s.ok()) return s;
  if (progress && !progress(100, "feature-preserving simplification")) return Status::Cancelled();
  out = std::move(r);
  return Status::Ok();
}

CollapseRefusal CheckFeatureCollapse(const IndexedMesh& mesh, const FeatureSimplifyParams& params, uint32_t from,
                                     uint32_t to) {
  Work w;
  if (!ValidateAndCheckInput(mesh, params).ok() || !w.Build(mesh, params).ok()) return CollapseRefusal::NotAnEdge;
  if (from >= w.P.size() || to >= w.P.size()) return CollapseRefusal::NotAnEdge;
  QueueState q;
  FeatureSimplifier simp(w, params, q);
  return simp.Check(from, to, nullptr, nullptr, true);
}

namespace {

// Feature edges by dihedral angle (no extension) plus border and non-manifold edges, as segments.
std::vector<std::array<P3, 2>> FeatureSegments(const IndexedMesh& m, double featureAngleDeg) {
  FeatureSimplifyParams p;
  p.featureAngleDeg = featureAngleDeg;
  p.extendFeatureLines = false;
  Work w;
  w.Build(m, p);
  std::vector<std::array<P3, 2>> segs;
  for (uint32_t a = 0; a < w.feat.size(); ++a)
    for (uint32_t b : w.feat[a])
      if (a < b) segs.push_back({w.P[a], w.P[b]});
  return segs;
}

// Uniform grid over segments for "is this point within tol of a segment" queries.
class SegmentGrid {
 public:
  SegmentGrid(const std::vector<std::array<P3, 2>>& segs, double tol) : segs_(segs), tol_(tol) {
    double total = 0;
    for (const auto& s : segs) {
      box_.Add(s[0]);
      box_.Add(s[1]);
      total += (s[1] - s[0]).Norm();
    }
    cell_ = std::max(tol * 2, segs.empty() ? 1.0 : total / double(segs.size()));
    if (!(cell_ > 0)) cell_ = 1;
    for (uint32_t i = 0; i < segs.size(); ++i) {
      vcg::Box3d b;
      b.Add(segs[i][0]);
      b.Add(segs[i][1]);
      b.Offset(tol);
      const auto lo = CellOf(b.min), hi = CellOf(b.max);
      for (long x = lo[0]; x <= hi[0]; ++x)
        for (long y = lo[1]; y <= hi[1]; ++y)
          for (long z = lo[2]; z <= hi[2]; ++z) cells_[Key(x, y, z)].push_back(i);
    }
  }
  bool Near(const P3& p) const {
    const auto c = CellOf(p);
    auto it = cells_.find(Key(c[0], c[1], c[2]));
    if (it == cells_.end()) return false;
    for (uint32_t i : it->second)
      if (PointSegmentDistance2(p, segs_[i][0], segs_[i][1]) <= tol_ * tol_) return true;
    return false;
  }

 private:
  std::array<long, 3> CellOf(const P3& p) const {
    return {long(std::floor((p[0] - box_.min[0]) / cell_)), long(std::floor((p[1] - box_.min[1]) / cell_)),
            long(std::floor((p[2] - box_.min[2]) / cell_))};
  }
  static uint64_t Key(long x, long y, long z) {
    return (uint64_t(x + (1 << 20)) << 42) ^ (uint64_t(y + (1 << 20)) << 21) ^ uint64_t(z + (1 << 20));
  }
  const std::vector<std::array<P3, 2>>& segs_;
  double tol_, cell_ = 1;
  vcg::Box3d box_;
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells_;
};

}  // namespace

Status CompareFeatureLines(const IndexedMesh& reference, const IndexedMesh& simplified, double featureAngleDeg,
                           double tolerance, FeatureLineAgreement& out) {
  out = FeatureLineAgreement();
  FeatureSimplifyParams p;
  p.featureAngleDeg = featureAngleDeg;
  Status s = ValidateAndCheckInput(reference, p);
  if (!s.ok()) return Status::Invalid("reference: " + s.message);
  s = ValidateAndCheckInput(simplified, p);
  if (!s.ok()) return Status::Invalid("simplified mesh: " + s.message);
  if (!(tolerance > 0)) return Status::Invalid("the tolerance must be > 0");
  const auto ref = FeatureSegments(reference, featureAngleDeg);
  const auto simp = FeatureSegments(simplified, featureAngleDeg);
  out.referenceEdges = ref.size();
  out.simplifiedEdges = simp.size();
  const SegmentGrid refGrid(ref, tolerance), simpGrid(simp, tolerance);
  for (const auto& e : simp)
    if (refGrid.Near(e[0]) && refGrid.Near(e[1]) && refGrid.Near((e[0] + e[1]) * 0.5)) ++out.simplifiedOnReference;
  for (const auto& e : ref) {
    const double len = (e[1] - e[0]).Norm();
    out.referenceLength += len;
    if (simpGrid.Near(e[0]) && simpGrid.Near(e[1]) && simpGrid.Near((e[0] + e[1]) * 0.5))
      out.referenceLengthCovered += len;
  }
  return Status::Ok();
}

}  // namespace conelod
