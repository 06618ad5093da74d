// ConeLOD — group-preserving quadric edge collapse (see group_qem.h).
#include "conelod/simplify/group_qem.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>

#include <vcg/space/box3.h>

#include "conelod/big_alloc.h"
#include "conelod/mesh/mesh_check.h"

namespace conelod {

namespace {

using vcg::Point3d;
constexpr uint32_t kNone = UINT32_MAX;

// A face normal may turn by at most acos(0.2) ~ 78 degrees in a collapse (preserveNormal; not
// the last face of a group in integrity mode: see judge()).
constexpr double kMinNormalCos = 0.2;
// New faces with quality (2 area / longest edge^2) below this are zero-area for our purposes.
constexpr double kDegenerateQuality = 1e-6;
// In a non-manifold neighbourhood a face's quality counts in the collapse priority as at least
// this (qualityThr weighs the rest): there the vertices that stay put (non-manifold ones, and the
// slivers that scans leave on non-manifold edges) force thin faces, and weighing them fully moves
// the face budget into those neighbourhoods (issue 25: stanford_dragon_vrip_res2 at 10 %).
constexpr double kNonManifoldQualityFloor = 0.1;
// Integrity mode: when a group's faces next to a collapsing edge are not connected through the
// merged vertex's fan, a search inside the group looks for a path between them through at most
// this many faces; a collapse whose path is longer (or missing) is refused.
constexpr uint32_t kIntegritySearchFaces = 256;
// With attribute seam moves: a seam vertex may leave the place its corner values belong to (its
// anchor) at this fraction of the squared distance in the tangent plane, added to the collapse's
// error; its values then follow it inside their charts (GroupQemSimplifier::seamPlace and
// collapse; chosen on the textured dragon, docs/attributes.md). Under 0.02 a seam vertex drifts
// across its seam far enough to stretch the texture (the integration tests' two-chart grid).
constexpr double kSeamDrift = 0.02;

// AnalyzeVertex counts the edge uses of a fan of at most this many faces among the fan's own
// slots; a larger fan in the neighbours' marks.
constexpr uint32_t kLocalFanFaces = 16;
// Meshes from this many faces are simplified in a spatial order (GroupQemSimplifier::SpatialOrder).
constexpr size_t kSpatialOrderFaces = 4096;

// Symmetric quadric Q(x) = x^T A x + 2 b.x + c, with the total weight w of its planes.
struct Quadric {
  double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0, b0 = 0, b1 = 0, b2 = 0, c = 0, w = 0;

  // Plane n.x + d = 0, n unit.
  void addPlane(const Point3d& n, double d, double weight) {
    a00 += weight * n[0] * n[0];
    a01 += weight * n[0] * n[1];
    a02 += weight * n[0] * n[2];
    a11 += weight * n[1] * n[1];
    a12 += weight * n[1] * n[2];
    a22 += weight * n[2] * n[2];
    b0 += weight * d * n[0];
    b1 += weight * d * n[1];
    b2 += weight * d * n[2];
    c += weight * d * d;
    w += weight;
  }
  // addPlane(n, d, weight) given that plane's terms alone (`plane`: a zero quadric after
  // addPlane(n, d, weight)): the same additions, bit for bit, without recomputing the terms.
  void addPlaneTerms(const Quadric& plane) { *this += plane; }
  Quadric& operator+=(const Quadric& q) {
    a00 += q.a00;
    a01 += q.a01;
    a02 += q.a02;
    a11 += q.a11;
    a12 += q.a12;
    a22 += q.a22;
    b0 += q.b0;
    b1 += q.b1;
    b2 += q.b2;
    c += q.c;
    w += q.w;
    return *this;
  }
  // A x (no b).
  Point3d apply(const Point3d& p) const {
    return Point3d(a00 * p[0] + a01 * p[1] + a02 * p[2], a01 * p[0] + a11 * p[1] + a12 * p[2],
                   a02 * p[0] + a12 * p[1] + a22 * p[2]);
  }
  double eval(const Point3d& p) const {
    const Point3d ap = apply(p);
    return p * ap + 2 * (b0 * p[0] + b1 * p[1] + b2 * p[2]) + c;
  }
  // Mean squared distance to the planes at p.
  double error(const Point3d& p) const { return w > 0 ? std::max(0.0, eval(p) / w) : 0.0; }
  // Solves A x = -b; false when A is near-singular (flat or crease neighbourhoods).
  bool minimum(Point3d& x) const {
    const double c00 = a11 * a22 - a12 * a12, c01 = a02 * a12 - a01 * a22, c02 = a01 * a12 - a02 * a11;
    const double det = a00 * c00 + a01 * c01 + a02 * c02;
    const double scale = (a00 + a11 + a22) / 3;
    if (!(std::fabs(det) > 1e-6 * scale * scale * scale)) return false;
    const double c11 = a00 * a22 - a02 * a02, c12 = a01 * a02 - a00 * a12, c22 = a00 * a11 - a01 * a01;
    const double inv = -1.0 / det;
    x = Point3d((c00 * b0 + c01 * b1 + c02 * b2) * inv, (c01 * b0 + c11 * b1 + c12 * b2) * inv,
                (c02 * b0 + c12 * b1 + c22 * b2) * inv);
    return std::isfinite(x[0]) && std::isfinite(x[1]) && std::isfinite(x[2]);
  }
  // Minimum on the segment p0 + t (p1 - p0), t in [0,1].
  Point3d segmentMinimum(const Point3d& p0, const Point3d& p1) const {
    const Point3d d = p1 - p0;
    const double dad = d * apply(d);
    if (!(dad > 0)) return (p0 + p1) * 0.5;
    const double t = -(d * apply(p0) + b0 * d[0] + b1 * d[1] + b2 * d[2]) / dad;
    return p0 + d * std::min(1.0, std::max(0.0, t));
  }
};

// Per-vertex fan structure and groups (primary grouping).
enum VertexFlag : uint8_t {
  kClosed = 1,         // one closed manifold fan
  kOpen = 2,           // one open manifold fan (a mesh-border vertex)
  kNonManifold = 4,    // several fans, an edge with 3+ faces, or a face using the vertex twice
  kSimpleContour = 8,  // closed fan, 2 groups, 2 sectors: a plain point of one group contour
  kIsolated = 16,      // no face
  kBorderEdge = 32,    // has an edge with one face (any fan structure)
  kNmEdge = 64,        // has an edge with 3+ faces: a point of a non-manifold line
  kNmJunction = 128,   // has 3+ such edges: where non-manifold lines meet (never removed)
};
struct VertexInfo {
  uint8_t flags = kIsolated;
  uint8_t groups = 0;  // distinct groups around, saturated at 255
};
// One closed manifold fan, all in one group (no border, contour or non-manifold flag).
inline bool IsInterior(const VertexInfo& vi) { return vi.flags == kClosed && vi.groups == 1; }

// Heap entries are 16 bytes. The top bit of `tag` says what `priority` is:
//   kLazy     a lower bound (quadric minimum, best quality): pushed without judging the collapse;
//   kJudged   the full priority, judged at the entry's epoch (the low 31 bits).
// An entry is superseded when an endpoint survived a collapse after it was pushed (that pushed
// the endpoint's edges anew), and stale when an endpoint's neighbourhood changed since (it is
// judged again when popped). A fresh judged entry is executed without judging it again.
struct HeapEntry {
  float priority;
  uint32_t a, b;
  uint32_t tag;
};
// The heap's order: priority, then the entry itself, so that entries of equal priority come out
// in one order whatever the heap's layout (the compaction below rebuilds it; the result does not
// depend on when).
inline bool Before(const HeapEntry& x, const HeapEntry& y) {
  if (x.priority != y.priority) return x.priority < y.priority;
  if (x.a != y.a) return x.a < y.a;
  if (x.b != y.b) return x.b < y.b;
  return x.tag < y.tag;
}

// 4-ary min-heap on priority: half the depth of a binary heap. The heap is the largest and most
// randomly accessed array of a run, so the four children of a node (64 bytes) are placed in one
// cache line: the array starts 16 bytes before a line boundary, so that children 4i+1..4i+4 begin
// on one.
class EntryHeap {
 public:
  void reserve(size_t n) {
    if (n > cap_) grow(n);
  }
  bool empty() const { return n_ == 0; }
  size_t size() const { return n_; }
  const HeapEntry& top() const { return h_[0]; }
  void append(const HeapEntry& e) {  // unordered; heapify() before popping
    if (n_ == cap_) grow(2 * cap_ + 64);
    h_[n_++] = e;
  }
  void push(const HeapEntry& e) {
    append(e);
    SiftUp(n_ - 1);
  }
  HeapEntry pop() {
    const HeapEntry top = h_[0];
    h_[0] = h_[--n_];
    if (n_ > 0) SiftDown(0);
    return top;
  }
  void heapify() {
    for (size_t i = n_ / 4 + 1; i-- > 0;)
      if (i < n_) SiftDown(i);
  }
  void clear() { n_ = 0; }
  void release() {
    storage_.reset();
    h_ = nullptr;
    n_ = cap_ = 0;
  }
  template <class Pred>
  void RemoveIf(Pred pred) {
    n_ = size_t(std::remove_if(h_, h_ + n_, pred) - h_);
    heapify();
  }

 private:
  // Left uninitialised: pages of the room that no entry has reached are never touched and take no
  // memory (the reserve is two entries per face; the heap holds about one per edge, 1.5 per face).
  void grow(size_t cap) {
    std::unique_ptr<HeapEntry[]> storage(new HeapEntry[cap + 4]);  // + room to align
    const uintptr_t addr = reinterpret_cast<uintptr_t>(storage.get());
    HeapEntry* h = storage.get() + ((48 - addr % 64 + 64) % 64) / sizeof(HeapEntry);
    std::copy(h_, h_ + n_, h);
    storage_.swap(storage);
    h_ = h;
    cap_ = cap;
  }
  void SiftUp(size_t i) {
    const HeapEntry x = h_[i];
    while (i > 0) {
      const size_t parent = (i - 1) / 4;
      if (!Before(x, h_[parent])) break;
      h_[i] = h_[parent];
      i = parent;
    }
    h_[i] = x;
  }
  void SiftDown(size_t i) {
    const HeapEntry x = h_[i];
    const size_t n = n_;
    for (;;) {
      const size_t first = 4 * i + 1;
      if (first >= n) break;
      size_t best = first;
      const size_t end = std::min(first + 4, n);
      for (size_t j = first + 1; j < end; ++j)
        if (Before(h_[j], h_[best])) best = j;
      if (!Before(h_[best], x)) break;
      h_[i] = h_[best];
      i = best;
    }
    h_[i] = x;
  }
  std::unique_ptr<HeapEntry[]> storage_;
  HeapEntry* h_ = nullptr;  // storage_.get() + 0..3, at 48 modulo 64 bytes
  size_t n_ = 0, cap_ = 0;
};
static_assert(sizeof(HeapEntry) == 16, "four heap entries per cache line");
constexpr uint32_t kLazy = 0, kJudged = 1u << 31, kKindMask = kJudged, kEpochMask = ~kKindMask;

struct Candidate {
  CollapseVerdict verdict = CollapseVerdict::NotAnEdge;
  uint32_t keep = kNone, remove = kNone;
  Point3d position;
  Point3d anchor;       // with attributes, keep on a seam: where its corner values hold (seamPlace)
  double error = 0;     // mean squared distance
  double priority = 0;  // error / quality penalty
};

// Dense ids 0..n-1 for group ids >= 0 (in order of first appearance); returns n. `original`, when
// given, receives the id each dense id stands for.
template <class Ids>
int DenseIds(const std::vector<int>& ids, Ids& dense, std::vector<int>* original = nullptr) {
  dense.resize(ids.size());
  if (original) original->clear();
  int n = 0;
  const int maxId = ids.empty() ? 0 : *std::max_element(ids.begin(), ids.end());
  if (size_t(maxId) <= 4 * ids.size() + 1024) {
    std::vector<int> map(size_t(maxId) + 1, -1);
    for (size_t f = 0; f < ids.size(); ++f) {
      int& m = map[size_t(ids[f])];
      if (m < 0) {
        m = n++;
        if (original) original->push_back(ids[f]);
      }
      dense[f] = m;
    }
    return n;
  }
  std::vector<int> sorted(ids);
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  for (size_t f = 0; f < ids.size(); ++f)
    dense[f] = int(std::lower_bound(sorted.begin(), sorted.end(), ids[f]) - sorted.begin());
  if (original) *original = sorted;
  return int(sorted.size());
}

inline bool Contains(const std::array<uint32_t, 3>& t, uint32_t v) { return t[0] == v || t[1] == v || t[2] == v; }
inline uint32_t Third(const std::array<uint32_t, 3>& t, uint32_t a, uint32_t b) {
  for (uint32_t v : t)
    if (v != a && v != b) return v;
  return kNone;
}
inline float ToFloat(double x) { return float(std::min(x, double(std::numeric_limits<float>::max()))); }

class GroupQemSimplifier {
 public:
  GroupQemSimplifier(const IndexedMesh& mesh, const std::vector<int>& faceGroup,
                     const std::vector<const std::vector<int>*>& coarser, const GroupQemParams& p,
                     const GroupQemRegion* region = nullptr, AttributeQuadrics* attributes = nullptr,
                     bool spatialOrder = false)
      : mesh_(mesh),
        group_(faceGroup),
        coarser_(coarser),
        p_(p),
        groupConstraints_((p.mode == GroupMode::Paper && p.condition1) || p.lockGroupBoundaries),
        integrity_(p.mode == GroupMode::Integrity && p.condition1),
        countGroups_(p.condition1),
        paperConditions_(p.mode == GroupMode::Paper),
        frozen_(region && !region->frozenVertex.empty() ? region->frozenVertex.data() : nullptr),
        regionDiagonal_(region ? region->diagonal : 0),
        separationSq_(region && region->separation > 0 ? region->separation * region->separation : 0),
        // Attributes are kept per input vertex and corner: they are renumbered with the mesh
        // (AttributeQuadrics::Renumber) and given back in the input's numbering by output().
        spatialOrder_(spatialOrder && coarser.empty() && !frozen_),
        passes_(p.passes && (!region || !(region->separation > 0))),
        attributes_(attributes && attributes->active() ? attributes : nullptr) {}

  // `owned` (optional): the input mesh itself, freed (left empty) as soon as init() has its copy.
  void init(IndexedMesh* owned = nullptr);
  Candidate evaluate(uint32_t a, uint32_t b);  // judge() + counts
  Status run(const Progress& progress, GroupQemStats& stats);
  // Frees what only run() reads (the heap, the face lists, the quadrics, the search marks), so
  // that output()'s mesh does not sit on top of them: the run's own arrays are its peak.
  void ReleaseLoop();
  void output(GroupQemResult& out) const;
  Point3d inputPosition(const Point3d& p) const { return p + center_; }

 private:
  // Face list of v: refs_[start_[v] .. start_[v] + count_[v]).
  const uint32_t* facesBegin(uint32_t v) const { return refs_.data() + start_[v]; }
  const uint32_t* facesEnd(uint32_t v) const { return refs_.data() + start_[v] + count_[v]; }
  void BuildFaceLists();
  // Whether n more entries fit in refs_ before the lists are rebuilt (refsBias_: see Compact()).
  bool listRoom(size_t n) const { return refs_.size() + refsBias_ + n <= refs_.capacity(); }
  // Renumbers the live vertices and faces densely, each in its order (a monotone renumbering:
  // every comparison of two indices, the heap's tie order and the face lists' order stay as they
  // were), in place; dead ones leave the arrays. The lists are packed at the start of refs_, and
  // refsBias_ keeps the moment of their next rebuild (which orders them by face) where it was.
  // Only where vertexInput_ and faceInput_ name the input (spatial order) and nothing else is
  // indexed by vertex or face (no attributes, coarser groupings or frozen vertices).
  bool compactable() const { return !vertexInput_.empty() && !attributes_ && coarser_.empty() && !frozen_; }
  void Compact();
  void AnalyzeVertex(uint32_t v);
  // Per face, the sides that add an edge quadric in init() (bit e: corner e to e + 1); after
  // every vertex's AnalyzeVertex.
  void SideMasks(BigVector<uint8_t>& mask);
  // The quadrics from the live faces (init(), and every memoryless step).
  void BuildQuadrics();
  // GroupQemParams::refreshRatio: at refreshAt_ live faces (0: never) the quadrics are built again
  // from the live faces (Refresh, when StepDue), and the next step is set.
  size_t refreshAt_ = 0;
  bool StepDue() const { return refreshAt_ > 0 && liveFaces_ <= refreshAt_; }
  void Refresh();
  size_t NextStep(size_t faces) const;          // the live faces of the step after one at `faces` (0: none)
  bool Folded(uint32_t fa, uint32_t fb) const;  // faces_[fa], faces_[fb]
  bool FoldAround(uint32_t u) const;
  // Twice the face's area times its unit normal (corners in order).
  template <class Tri>
  Point3d AreaNormal(const Tri& t) const {
    return (pos_[t[1]] - pos_[t[0]]) ^ (pos_[t[2]] - pos_[t[0]]);
  }
  bool interior(uint32_t v) const { return (vs_[v].info.flags & kClosed) && vs_[v].info.groups == 1; }
  bool interiorIn(uint32_t v, const std::vector<int>& layer) const;
  bool fixedVertex(uint32_t v, bool countSeams = true) const;
  bool contourVertex(uint32_t v) const {
    const VertexInfo& vi = vs_[v].info;
    return groupConstraints_ && !p_.lockGroupBoundaries && vi.groups == 2 && (vi.flags & kSimpleContour);
  }
  Candidate judge(uint32_t a, uint32_t b);
  // The faces on the edge (a, b): their count (3+ on a non-manifold edge), the first two in e
  // (kNone where there are fewer).
  uint32_t edgeFaces(uint32_t a, uint32_t b, uint32_t e[2]) const {
    e[0] = e[1] = kNone;
    uint32_t ne = 0;
    for (const uint32_t* f = facesBegin(a); f != facesEnd(a); ++f)
      if (Contains(faces_[*f], b)) {
        if (ne < 2) e[ne] = *f;
        ++ne;
      }
    return ne;
  }
  // g(f): the group of face f; layer: the coarser grouping it reads, null for the primary one.
  template <class GroupOf>
  bool condition1(const GroupOf& g, uint32_t a, uint32_t b, uint32_t e0, uint32_t e1, uint32_t n0a, uint32_t n0b,
                  uint32_t n1a, uint32_t n1b, const std::vector<int>* layer) const;
  // Condition 1 for a coarser grouping whose groups are unions of the primary ones, once the
  // primary grouping passed it (see coarserNested_).
  bool condition1Nested(const std::vector<int>& g, uint32_t a, uint32_t b, uint32_t e0, uint32_t e1) const {
    return e1 == kNone || g[e0] != g[e1] || faces_[e0].group == faces_[e1].group || interiorIn(a, g) ||
           interiorIn(b, g);
  }
  // Where the merged vertex goes (c.keep, c.position); false: both endpoints must stay.
  bool place(uint32_t a, uint32_t b, bool contourEdge, Candidate& c) const;
  // After place(): whether attribute seams let c.remove go into c.keep (AttributeQuadrics::SeamCost,
  // into seamCost), turning the collapse of two seam vertices round when that is allowed or cheaper.
  bool seamCollapse(const uint32_t e[2], Candidate& c, double& seamCost) const;
  // After seamCollapse, when c.keep is a seam vertex: its anchor (c.anchor: where its corner values
  // hold) and position. Along a seam between two plain seam points (AttributeQuadrics::SlidesAlong)
  // the anchor goes to the quadric's minimum on the anchors' segment, each side's values
  // interpolated along it (AttributeQuadrics::Slide); else it is keep's. With seam moves
  // (AttributeQuadrics::seamMoves) the position may leave the anchor, at kSeamDrift x the squared
  // distance in the tangent plane (into seamCost; collapse() then moves the values and the anchor
  // with it, AttributeQuadrics::Reparameterize); without, it is the anchor.
  void seamPlace(uint32_t a, uint32_t b, const uint32_t e[2], Candidate& c, double& seamCost) const;
  // place() again for an edge judged before (nothing changed since): seamCollapse and seamPlace as
  // judge() runs them; false when the seams no longer allow it.
  bool placeAtSeam(uint32_t a, uint32_t b, Candidate& c) const;
  double priorityOf(double error, double quality, uint32_t a, uint32_t b) const;
  float lowerBound(uint32_t a, uint32_t b) const;
  void collapse(const Candidate& c);
  bool frozen(uint32_t v) const { return frozen_ && frozen_[v]; }
  void PushLazy(uint32_t a, uint32_t b) {
    if (!frozen(a) && !frozen(b)) heap_.push({lowerBound(a, b), a, b, epoch_ | kLazy});
  }
  // Asks the cache for what judging the collapse (a, b) reads first of a and b (changes nothing else).
  void PrefetchVertices(uint32_t a, uint32_t b) const {
    for (uint32_t v : {a, b}) {
      __builtin_prefetch(&vs_[v]);
      __builtin_prefetch(&start_[v]);
      __builtin_prefetch(&count_[v]);
      __builtin_prefetch(&pos_[v]);
      __builtin_prefetch(&quadric_[v]);
      __builtin_prefetch(reinterpret_cast<const char*>(&quadric_[v]) + 64);
      __builtin_prefetch(reinterpret_cast<const char*>(&quadric_[v]) + sizeof(Quadric) - 1);  // 88 bytes: up to 3 lines
    }
  }
  void PushEdgesOf(uint32_t v);  // lazy entries for every edge of v, heap order restored
  // Stopped above `target`: removes whole components of whole groups (p_.removeComponents) and
  // counts those it may remove.
  void RemoveComponents(size_t target, GroupQemStats& stats);
  // Stopped above the target: every edge left judged once more (stats.edgesLeftBy).
  void TallyFloor(double maxErrorSq, GroupQemStats& stats);
  // v's neighbours u > v, each once, in ringScratch_ (collected first: judge() uses the marks too).
  const std::vector<uint32_t>& NeighboursAbove(uint32_t v);
  // Stopped above `target` (GroupQemParams::flipToUnblock): collapses refused by the link
  // condition, unblocked by edge flips, then the collapses that frees, in rounds.
  void UnblockByFlips(const Progress& progress, size_t target, double maxErrorSq, GroupQemStats& stats);
  // Flips the edges from a or b to their common neighbours other than the edge's opposite
  // vertices and collapses (a, b) when it is then allowed; else undoes the flips. True: collapsed.
  bool TryUnblock(uint32_t a, uint32_t b, double maxErrorSq, GroupQemStats& stats);
  // The flip of edge (u, w) (its two faces (u, w, p), (w, u, q) become (u, q, p), (w, p, q)):
  // -1 when not allowed (see flipToUnblock), else the least cosine between a new face normal and
  // the two old faces' mean normal (1: flat). apply: also flip it (undo_ records the old faces).
  double FlipEdge(uint32_t u, uint32_t w, bool apply);
  // Gives face f the corners t (same group), keeping the per-vertex face lists.
  void SetFace(uint32_t f, const std::array<uint32_t, 3>& t);
  // Integrity mode: after collapsing (a, b) (faces e0, e1 on the edge; n0a, n0b, n1a, n1b: the
  // faces across (a, opp0), (b, opp0), (a, opp1), (b, opp1), kNone where there is none), every
  // group of every grouping is still one piece, as many pieces as before, and not empty.
  bool keepsGroupsWhole(uint32_t a, uint32_t b, uint32_t e0, uint32_t e1, uint32_t n0a, uint32_t n0b, uint32_t n1a,
                        uint32_t n1b);
  bool keepsGroupsWhole(uint32_t a, uint32_t b);  // finds the faces itself
  // The same for any collapse, also along an edge with 3+ faces: a search inside each group of
  // the removed faces, on the adjacency after the collapse (bounded as keepsGroupWhole's).
  bool keepsGroupsWholeAcross(uint32_t a, uint32_t b);
  // The topology and placement of a collapse in a non-manifold neighbourhood (c.keep, c.remove,
  // c.position, c.error); false: refused (see the top of group_qem.h).
  bool nonManifoldCollapse(uint32_t a, uint32_t b, uint32_t ne, Candidate& c);
  // One grouping: layer < 0 the primary one, else coarserDense_[layer].
  bool keepsGroupWhole(int layer, uint32_t a, uint32_t b, uint32_t e0, uint32_t e1, uint32_t n0a, uint32_t n0b,
                       uint32_t n1a, uint32_t n1b);
  int groupIn(int layer, uint32_t f) const { return layer < 0 ? faces_[f].group : coarserDense_[size_t(layer)][f]; }
  // Whether f is a face of group G (in that grouping): a face that uses a vertex twice is none, and
  // joins nothing (the output leaves it out; MeasureGroupIntegrity does not count it).
  bool faceOf(int layer, uint32_t f, int G) const { return groupIn(layer, f) == G && !UsesAVertexTwice(faces_[f]); }
  // keepCones: the new normal (unnormalised, squared length lenSq) of face f stays in the cone
  // bound of its group in every grouping that has bounds.
  bool insideCones(uint32_t f, const Point3d& n, double lenSq) const {
    for (size_t l = 0; l < coneAxis_.size(); ++l) {
      const size_t g = size_t(l == 0 ? group_[inputFace(f)] : (*coarser_[l - 1])[f]);
      if (g >= coneAxis_[l].size() || !(coneCos_[l][g] > -2)) continue;
      const double dot = n * coneAxis_[l][g], c = coneCos_[l][g];
      if (!(c >= 0 ? (dot >= 0 && dot * dot >= c * c * lenSq) : (dot >= 0 || dot * dot <= c * c * lenSq))) return false;
    }
    return true;
  }

  const IndexedMesh& mesh_;  // read by init() only
  size_t facesIn_ = 0;       // mesh_'s faces
  const std::vector<int>& group_;
  const std::vector<const std::vector<int>*>& coarser_;
  // Every coarser grouping is a union of the primary groups (as the levels of a GroupHierarchy):
  // faces in one primary group are in one coarser group. Then a collapse that passes condition 1
  // for the primary groups passes its first two clauses for the coarser ones (a neighbour in f1's
  // primary group is in its coarser group), and the third wherever f1 and f2 share a primary group
  // (a fan inside one primary group is inside one coarser group): only f1 and f2 in different
  // primary groups but one coarser group remain to check.
  bool coarserNested_ = false;
  GroupQemParams p_;
  const bool groupConstraints_;  // contour-aware placement and quadrics (paper mode or the lock)
  const bool integrity_;         // the integrity test (integrity mode, condition1)
  const bool countGroups_;       // live faces per group are counted (condition1, either mode)
  int primaryGroups_ = 0;        // dense group ids are 0 .. primaryGroups_ - 1
  const bool paperConditions_;   // conditions 1 and 2 as the paper (paper mode)
  const uint8_t* frozen_;        // per vertex, or null: see GroupQemRegion
  const double regionDiagonal_;  // > 0: the whole mesh's diagonal
  const double separationSq_;    // GroupQemRegion::separation squared; 0: no check
  // GroupQemRegion::separation: false when the vertex of collapse (a, b), at p, would lie closer
  // than it to one of its neighbours or join anew two neighbours closer than it to each other.
  bool keepsApart(uint32_t a, uint32_t b, const Point3d& p);
  // Vertices and faces are numbered in a spatial order inside the simplifier (see SpatialOrder);
  // vertexInput_/faceInput_: the input index of each (empty: the input's order).
  const bool spatialOrder_;
  // GroupQemParams::passes: collapses in ranked passes (CollapseInPasses) before the queue.
  const bool passes_;
  bool ranking_ = false;  // in a ranked pass: collapse() queues nothing (the next pass ranks every edge)
  // The passes' loop: collapses until `target` faces, the error bound, or a stall or the target's
  // approach (returns true: the queue goes on from there; false: done or cancelled).
  bool CollapseInPasses(const Progress& progress, size_t target, double maxErrorSq, GroupQemStats& stats);
  // The queue's loop, from the current state: every live edge queued at its lower bound.
  void CollapseInQueue(const Progress& progress, size_t target, double maxErrorSq, GroupQemStats& stats);
  Status finish(const Progress& progress, size_t target, double maxErrorSq,
                GroupQemStats& stats);  // run()'s end, both loops
  std::vector<uint32_t> vertexInput_, faceInput_;
  uint32_t inputFace(uint32_t f) const { return faceInput_.empty() ? f : faceInput_[f]; }
  // Fills vertexInput_ and faceInput_ (box: the input's bounding box).
  void SpatialOrder(const vcg::Box3<double>& box);

  // Or null: attribute cost, seams, models merged on collapse (attribute_quadric.h).
  AttributeQuadrics* attributes_;
  const AttributeQuadrics::FaceCorners faceCorners_ = [this](uint32_t f) -> const std::array<uint32_t, 3>& {
    return faces_[f];
  };

  Point3d center_;
  double diag_ = 1;
  double floorError_ = 0;
  std::vector<Point3d> pos_;
  std::vector<Quadric> quadric_;
  // With attributes: per seam vertex, the position its corner values belong to (its input position,
  // or a point on a seam edge after a slide); pos_ may drift from it with seam moves (seamPlace).
  std::vector<Point3d> anchor_;
  // A face with its (primary) group: the judging reads both, in one 16-byte record.
  struct FaceRec : std::array<uint32_t, 3> {
    int group;
  };
  // A face that UsesAVertexTwice (input corners the weld joined) stays so until it dies, is no
  // live face (liveFaces_) nor a face of its group (groupFaces_), and is left out of the result.
  std::vector<FaceRec> faces_;                  // group: dense ids 0..n-1 (only equality and counts matter)
  std::vector<std::vector<int>> coarserDense_;  // integrity mode: the coarser groupings, dense ids
  std::vector<std::vector<int>> groupFaces_;    // integrity mode: live faces per group; [0] primary
  // keepCones, per grouping with bounds ([0] primary, then the coarser ones), per group id: the
  // bound's axis and the cosine of its half-angle (-3: no bound).
  std::vector<std::vector<Point3d>> coneAxis_;
  std::vector<std::vector<double>> coneCos_;
  std::vector<uint32_t> faceMark_;  // integrity search marks (== faceStamp_)
  uint32_t faceStamp_ = 0;
  std::vector<char> faceDead_;
  std::vector<uint32_t> start_, count_, refs_;
  size_t refsBias_ = 0;    // entries of refs_ before the last Compact() that it packed away
  size_t verticesIn_ = 0;  // mesh_'s vertices
  // What the loop reads of a vertex, in one 16-byte record (one cache miss, not six).
  struct VertexState {
    uint32_t lastSurvive = 0;  // epoch at which the vertex last survived a collapse
    uint32_t touched = 0;      // epoch at which its neighbourhood last changed
    uint32_t mark = 0;         // visit mark (== stamp_)
    VertexInfo info;
    char dead = 0;
    char dropped = 0;  // a refused collapse at it left the heap: queue its edges again when its
                       // neighbourhood changes (the collapse may have become possible)
  };
  std::vector<VertexState> vs_;
  uint32_t stamp_ = 0;
  uint32_t epoch_ = 1;
  EntryHeap heap_;
  size_t liveFaces_ = 0;  // live faces but those that use a vertex twice: the result's face count
  GroupQemStats stats_;   // evaluations and refusals counted by evaluate()
  // Scratch (no allocation in the loop).
  std::vector<uint32_t> fanOther_, ring_, fanScratch_, fanParent_, queue_, edgeFaces_, opposite_, nbScratch_,
      ringScratch_;
  std::vector<int> groupScratch_;
  std::vector<std::pair<uint32_t, std::array<uint32_t, 3>>> undo_;  // TryUnblock: faces before the flips
};

void GroupQemSimplifier::BuildFaceLists() {
  const size_t nv = pos_.size();
  start_.assign(nv, 0);
  count_.assign(nv, 0);
  for (size_t f = 0; f < faces_.size(); ++f) {
    if (faceDead_[f]) continue;
    const auto& t = faces_[f];
    ++count_[t[0]];
    if (t[1] != t[0]) ++count_[t[1]];
    if (t[2] != t[0] && t[2] != t[1]) ++count_[t[2]];
  }
  uint32_t total = 0;
  refsBias_ = 0;
  for (size_t v = 0; v < nv; ++v) {
    start_[v] = total;
    total += count_[v];
    count_[v] = 0;
  }
  // Twice the room: a collapse appends the survivor's new list at the end; we rebuild when full.
  // (reserve, not assign: the room is not written until a collapse appends to it.)
  refs_.clear();
  refs_.reserve(std::max<size_t>(size_t(total) * 2, 64));
  refs_.resize(total);
  for (uint32_t f = 0; f < faces_.size(); ++f) {
    if (faceDead_[f]) continue;
    const auto& t = faces_[f];
    refs_[start_[t[0]] + count_[t[0]]++] = f;
    if (t[1] != t[0]) refs_[start_[t[1]] + count_[t[1]]++] = f;
    if (t[2] != t[0] && t[2] != t[1]) refs_[start_[t[2]] + count_[t[2]]++] = f;
  }
}

void GroupQemSimplifier::AnalyzeVertex(uint32_t v) {
  VertexInfo& vi = vs_[v].info;
  const uint32_t k = count_[v];
  if (k == 0) {
    vi.flags = kIsolated;
    vi.groups = 0;
    return;
  }
  const uint32_t* fl = facesBegin(v);
  // Distinct groups.
  groupScratch_.clear();
  for (uint32_t i = 0; i < k; ++i) {
    const int g = faces_[fl[i]].group;
    if (std::find(groupScratch_.begin(), groupScratch_.end(), g) == groupScratch_.end()) groupScratch_.push_back(g);
  }
  vi.groups = uint8_t(std::min<size_t>(groupScratch_.size(), 255));
  // The two other vertices of each face, in slots 2i and 2i+1.
  fanOther_.resize(2 * size_t(k));
  bool nonManifold = false;
  for (uint32_t i = 0; i < k; ++i) {
    const auto& t = faces_[fl[i]];
    if (UsesAVertexTwice(t)) nonManifold = true;
    const int j = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
    fanOther_[2 * i] = t[size_t((j + 1) % 3)];
    fanOther_[2 * i + 1] = t[size_t((j + 2) % 3)];
  }
  // How many faces use each edge (v, u): 1 = border, 2 = manifold, 3+ = non-manifold; nmEdges:
  // the distinct u of 3+ uses; startFace, startVertex: the last border use.
  uint32_t borderEnds = 0, startFace = 0, startVertex = fanOther_[0], nmEdges = 0;
  const uint32_t slots = 2 * k;
  if (k <= kLocalFanFaces) {
    // Counted among the slots themselves (quadratic in k, in registers and one or two cache
    // lines): the neighbours' records, at random places in memory, are not read.
    const uint32_t* o = fanOther_.data();
    for (uint32_t s = 0; s < slots; ++s) {
      const uint32_t x = o[s];
      uint32_t uses = 0, before = 0;
      for (uint32_t t = 0; t < slots; ++t) {
        uses += o[t] == x;
        before += t < s && o[t] == x;
      }
      if (uses > 2) {
        nonManifold = true;
        nmEdges += before == 0;
      }
      if (uses == 1) {
        ++borderEnds;
        startFace = s / 2;
        startVertex = x;
      }
    }
  } else {
    // Counted in the vertices' marks, linear in k: mark = base + uses - 1 (saturated at 3+), then
    // base + 4 once a non-manifold edge is counted.
    const uint32_t base = stamp_ + 1;
    stamp_ += 5;
    for (uint32_t s = 0; s < slots; ++s) {
      uint32_t& m = vs_[fanOther_[s]].mark;
      m = (m >= base && m < base + 4) ? std::min(m + 1, base + 2) : base;
    }
    for (uint32_t s = 0; s < slots; ++s) {
      uint32_t& m = vs_[fanOther_[s]].mark;
      const uint32_t uses = m == base + 4 ? 3 : m - base + 1;
      if (uses > 2) {
        nonManifold = true;
        nmEdges += m != base + 4;
        m = base + 4;
      }
      if (uses == 1) {
        ++borderEnds;
        startFace = s / 2;
        startVertex = fanOther_[s];
      }
    }
  }
  if (borderEnds != 0 && borderEnds != 2) nonManifold = true;
  // Walk the fan from startFace entering over startVertex; count the faces reached and the group
  // changes between consecutive faces.
  uint32_t visited = 0, changes = 0;
  if (!nonManifold) {
    uint32_t cur = startFace, in = startVertex;
    for (;;) {
      ++visited;
      const uint32_t out = fanOther_[2 * cur] == in ? fanOther_[2 * cur + 1] : fanOther_[2 * cur];
      uint32_t next = kNone;
      for (uint32_t i = 0; i < k; ++i)
        if (i != cur && (fanOther_[2 * i] == out || fanOther_[2 * i + 1] == out)) {
          next = i;
          break;
        }
      if (next == kNone || next == startFace || visited > k) {
        if (next == startFace && faces_[fl[cur]].group != faces_[fl[next]].group) ++changes;
        break;
      }
      if (faces_[fl[cur]].group != faces_[fl[next]].group) ++changes;
      cur = next;
      in = out;
    }
    if (visited != k) nonManifold = true;
  }
  if (nonManifold)
    vi.flags = kNonManifold | (nmEdges > 0 ? kNmEdge : 0) | (nmEdges > 2 ? kNmJunction : 0);
  else if (borderEnds == 0)
    vi.flags = kClosed | ((vi.groups == 2 && changes == 2) ? kSimpleContour : 0);
  else
    vi.flags = kOpen;
  if (borderEnds > 0) vi.flags |= kBorderEdge;
}

// Two faces nearly back to back (normals more than 120 degrees apart: they meet at under 60
// degrees). Their shared edge is the rim of a thin sheet or blade (a scan's two layers meeting
// where a crack was welded, a fin, a collapsed slot): both faces' planes contain any move along
// the sheet, so its vertices slide into the base at no cost, and a level simplified from the one
// below (the LOD build, memoryless) eats such a sheet whole. As at a border, each face adds the
// plane through the edge orthogonal to it (SideMasks).
constexpr double kFoldCos = 0.5;

// Whether two area normals point more than 120 degrees apart (without a root: d^2 against the
// squared norms).
bool BackToBack(const Point3d& n1, const Point3d& n2) {
  const double d = n1 * n2;
  return d < 0 && d * d > kFoldCos * kFoldCos * n1.SquaredNorm() * n2.SquaredNorm();
}

bool GroupQemSimplifier::Folded(uint32_t fa, uint32_t fb) const {
  return BackToBack(AreaNormal(faces_[fa]), AreaNormal(faces_[fb]));
}

// Whether two faces around u are Folded (any two: SideMasks then checks the sides one by one).
bool GroupQemSimplifier::FoldAround(uint32_t u) const {
  const uint32_t* fl = facesBegin(u);
  const uint32_t k = count_[u];
  constexpr uint32_t kMax = 32;
  if (k > kMax) return true;  // a fan this large: let SideMasks check the sides one by one
  Point3d n[kMax];
  for (uint32_t i = 0; i < k; ++i) {
    n[i] = AreaNormal(faces_[fl[i]]);
    for (uint32_t j = 0; j < i; ++j)
      if (BackToBack(n[i], n[j])) return true;
  }
  return false;
}

void GroupQemSimplifier::SideMasks(BigVector<uint8_t>& mask) {
  const uint32_t nv = uint32_t(pos_.size());
  mask.assign(faces_.size(), 0);
  for (uint32_t u = 0; u < nv; ++u) {
    const uint32_t k = count_[u];
    if (k == 0) continue;
    // One closed manifold fan (AnalyzeVertex, run before): two faces on every edge of u, so no
    // border-like side, and without group constraints no contour side either, unless two of its
    // faces lie nearly back to back (a fold, below).
    if (!groupConstraints_ && (vs_[u].info.flags & kClosed) && !(p_.foldPlanes && FoldAround(u))) continue;
    const uint32_t* fl = facesBegin(u);
    // The faces of u holding each neighbour x, in x's mark: base + count - 1, saturated at base + 2.
    const uint32_t base = stamp_ + 1;
    stamp_ += 3;
    for (uint32_t i = 0; i < k; ++i) {
      const auto& t = faces_[fl[i]];
      for (int j = 0; j < 3; ++j) {
        const uint32_t x = t[size_t(j)];
        if (x == u || (j > 0 && t[0] == x) || (j > 1 && t[1] == x)) continue;  // each vertex of a face once
        uint32_t& m = vs_[x].mark;
        m = (m >= base && m < base + 3) ? std::min(m + 1, base + 2) : base;
      }
    }
    // Side (u, w) of face f: the other faces holding u and w are count(w) - 1. None or 2+ (a
    // border, or a non-manifold line): a border-like side; 1 (paper mode or the lock): a group
    // contour when that face is in another group.
    for (uint32_t i = 0; i < k; ++i) {
      const uint32_t f = fl[i];
      const auto& t = faces_[f];
      for (int e = 0; e < 3; ++e) {
        const uint32_t w = t[size_t((e + 1) % 3)];
        if (t[size_t(e)] != u || w == u) continue;
        const uint32_t others = vs_[w].mark - base;  // 0, 1, or 2 for 2+
        bool side = others != 1;
        if (!side && (groupConstraints_ || p_.foldPlanes))  // one other face: a group contour, or a fold
          for (uint32_t g = 0; g < k; ++g)
            if (fl[g] != f && Contains(faces_[fl[g]], w)) {
              side = (groupConstraints_ && faces_[fl[g]].group != t.group) || (p_.foldPlanes && Folded(f, fl[g]));
              break;
            }
        if (side) mask[f] |= uint8_t(1u << e);
      }
    }
  }
}

bool GroupQemSimplifier::interiorIn(uint32_t v, const std::vector<int>& layer) const {
  if (!(vs_[v].info.flags & kClosed)) return false;
  const int g = layer[*facesBegin(v)];
  for (const uint32_t* f = facesBegin(v); f != facesEnd(v); ++f)
    if (layer[*f] != g) return false;
  return true;
}

bool GroupQemSimplifier::fixedVertex(uint32_t v, bool countSeams) const {
  const VertexInfo& vi = vs_[v].info;
  if (vi.flags & kNonManifold) return true;
  if (p_.preserveBoundary && (vi.flags & kOpen)) return true;
  if (countSeams && attributes_ && attributes_->seam(v)) return true;  // attribute_quadric.h
  if (groupConstraints_ && vi.groups >= 2) {
    if (p_.lockGroupBoundaries) return true;
    if (vi.groups > 2 || !(vi.flags & kSimpleContour)) return true;  // a corner, or a contour end
  }
  return false;
}

// Spreads the low 21 bits of x to every third bit (a Morton code's axis).
uint64_t SpreadBits(uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

// The loop judges each collapse on the faces around its two vertices and their neighbours: with
// the input's numbering (a scan's, in slices) these lie thousands of entries apart in every
// array, a cache miss each. Numbered along a Morton curve of the positions (faces by their
// first vertex in that order), a neighbourhood lies in a few cache lines. The order is
// deterministic (ties by input index); the output is mapped back to the input's order.
void GroupQemSimplifier::SpatialOrder(const vcg::Box3<double>& box) {
  const size_t nv = mesh_.positions.size(), nf = mesh_.faces.size();
  const double extent = std::max({box.DimX(), box.DimY(), box.DimZ()});
  const double scale = extent > 0 ? double((1 << 21) - 1) / extent : 0;
  // (The temporaries here and in init() are mapped (BigVector): freed, they go back to the system
  // instead of leaving holes in the heap under the loop's arrays.)
  // Vertices by (code, input index): a stable LSD radix sort of the codes, 11 bits at a time, from
  // the input's order (the order a sort of the pairs gives); a digit that every code shares is
  // skipped.
  BigVector<uint64_t> code(nv), codeTmp(nv);
  BigVector<uint32_t> order(nv), orderTmp(nv);
  for (uint32_t v = 0; v < nv; ++v) {
    const Point3d p = Point3d::Construct(mesh_.positions[v]);
    uint64_t c = 0;
    if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]) && box.IsIn(p))
      for (int k = 0; k < 3; ++k) c |= SpreadBits(uint64_t((p[k] - box.min[k]) * scale)) << k;
    code[v] = c;
    order[v] = v;
  }
  std::vector<uint32_t> histogram(2048);
  for (int shift = 0; shift < 64; shift += 11) {
    std::fill(histogram.begin(), histogram.end(), 0u);
    for (uint64_t c : code) ++histogram[(c >> shift) & 2047];
    if (nv == 0 || histogram[(code[0] >> shift) & 2047] == nv) continue;  // one digit for all
    uint32_t sum = 0;
    for (uint32_t& h : histogram) {
      const uint32_t n = h;
      h = sum;
      sum += n;
    }
    for (uint32_t i = 0; i < nv; ++i) {
      const uint32_t to = histogram[(code[i] >> shift) & 2047]++;
      codeTmp[to] = code[i];
      orderTmp[to] = order[i];
    }
    code.swap(codeTmp);
    order.swap(orderTmp);
  }
  BigVector<uint64_t>().swap(code);
  BigVector<uint64_t>().swap(codeTmp);
  vertexInput_.assign(order.begin(), order.end());
  BigVector<uint32_t>().swap(order);
  BigVector<uint32_t>& internal = orderTmp;
  for (uint32_t i = 0; i < nv; ++i) internal[vertexInput_[i]] = i;
  // Faces by (first vertex in that order, input index): a counting sort on the first vertex,
  // filled in the input's order.
  BigVector<uint32_t> first(nv + 1, 0);
  for (uint32_t f = 0; f < nf; ++f) {
    const auto& t = mesh_.faces[f];
    ++first[std::min({internal[t[0]], internal[t[1]], internal[t[2]]}) + 1];
  }
  for (size_t i = 1; i <= nv; ++i) first[i] += first[i - 1];
  faceInput_.resize(nf);
  for (uint32_t f = 0; f < nf; ++f) {
    const auto& t = mesh_.faces[f];
    faceInput_[first[std::min({internal[t[0]], internal[t[1]], internal[t[2]]})]++] = f;
  }
}

void GroupQemSimplifier::init(IndexedMesh* owned) {
  const size_t nv = mesh_.positions.size(), nf = mesh_.faces.size();
  facesIn_ = nf;
  verticesIn_ = nv;
  // Work around the bounding-box centre: quadrics lose less precision near the origin.
  vcg::Box3<double> box;
  for (const auto& t : mesh_.faces)
    for (uint32_t v : t) box.Add(Point3d::Construct(mesh_.positions[v]));
  center_ = box.Center();
  diag_ = regionDiagonal_ > 0 ? regionDiagonal_ : (box.Diag() > 0 ? box.Diag() : 1.0);
  // As vcglib: errors below a floor (~1e-6 of the diagonal) are equal, and shorter edges go first.
  floorError_ = 1e-12 * diag_ * diag_;
  if (spatialOrder_ && nf >= kSpatialOrderFaces) {
    SpatialOrder(box);
    if (attributes_) attributes_->Renumber(vertexInput_, faceInput_);
  }
  pos_.resize(nv);
  faces_.resize(nf);
  BigVector<int> dense;
  const int groups = DenseIds(group_, dense);
  primaryGroups_ = groups;
  if (vertexInput_.empty()) {
    for (size_t v = 0; v < nv; ++v) pos_[v] = Point3d::Construct(mesh_.positions[v]) - center_;
    for (size_t f = 0; f < nf; ++f) {
      static_cast<std::array<uint32_t, 3>&>(faces_[f]) = mesh_.faces[f];
      faces_[f].group = dense[f];
    }
  } else {
    BigVector<uint32_t> internal(nv);
    for (uint32_t i = 0; i < nv; ++i) {
      internal[vertexInput_[i]] = i;
      pos_[i] = Point3d::Construct(mesh_.positions[vertexInput_[i]]) - center_;
    }
    for (size_t f = 0; f < nf; ++f) {
      const auto& t = mesh_.faces[faceInput_[f]];
      for (int j = 0; j < 3; ++j) faces_[f][size_t(j)] = internal[t[size_t(j)]];
      faces_[f].group = dense[faceInput_[f]];
    }
  }
  if (attributes_) anchor_ = pos_;
  if (owned) *owned = IndexedMesh();  // nothing below reads mesh_
  if (countGroups_) {
    groupFaces_.assign(1 + coarser_.size(), std::vector<int>());
    groupFaces_[0].assign(size_t(groups), 0);
    // (faces_ in the simplifier's order: its group is faces_[f].group, not dense[f], the input
    // face f's; the two differ in the spatial order)
    for (size_t f = 0; f < nf; ++f) groupFaces_[0][size_t(faces_[f].group)] += !UsesAVertexTwice(faces_[f]);
    coarserDense_.resize(coarser_.size());
    for (size_t l = 0; l < coarser_.size(); ++l) {
      const int n = DenseIds(*coarser_[l], coarserDense_[l]);
      groupFaces_[l + 1].assign(size_t(n), 0);
      for (size_t f = 0; f < nf; ++f) groupFaces_[l + 1][size_t(coarserDense_[l][f])] += !UsesAVertexTwice(faces_[f]);
    }
    faceMark_.assign(nf, 0);
  }
  if (p_.keepCones) {
    const size_t layers = 1 + std::min(coarser_.size(), p_.coarserConeBound.size());
    coneAxis_.resize(layers);
    coneCos_.resize(layers);
    for (size_t l = 0; l < layers; ++l) {
      const std::vector<NormalCone>& bounds = l == 0 ? p_.coneBound : p_.coarserConeBound[l - 1];
      coneAxis_[l].assign(bounds.size(), Point3d(0, 0, 1));
      coneCos_[l].assign(bounds.size(), -3.0);
      for (size_t id = 0; id < bounds.size(); ++id) {
        if (bounds[id].empty() || bounds[id].halfAngle >= NormalCone::kPi) continue;
        coneAxis_[l][id] = bounds[id].axis;
        coneCos_[l][id] = std::cos(bounds[id].halfAngle);
      }
    }
  }
  faceDead_.assign(nf, 0);
  vs_.assign(nv, VertexState());
  liveFaces_ = 0;  // what the result would have: faces that do not use a vertex twice
  for (const FaceRec& t : faces_) liveFaces_ += !UsesAVertexTwice(t);
  BuildFaceLists();
  for (uint32_t v = 0; v < nv; ++v) AnalyzeVertex(v);
  coarserNested_ = !coarser_.empty();
  if (coarserNested_) {
    const int maxGroup = nf > 0 ? *std::max_element(group_.begin(), group_.end()) : 0;
    std::vector<int> coarserOf(size_t(maxGroup) + 1);
    for (const auto* layer : coarser_) {
      std::fill(coarserOf.begin(), coarserOf.end(), -1);
      for (size_t f = 0; f < nf && coarserNested_; ++f) {
        int& c = coarserOf[size_t(group_[f])];
        if (c < 0)
          c = (*layer)[f];
        else if (c != (*layer)[f])
          coarserNested_ = false;
      }
    }
  }

  BuildQuadrics();
}

void GroupQemSimplifier::BuildQuadrics() {
  // Quadrics: area-weighted face planes; border (and group-contour) edges add the plane through
  // the edge orthogonal to the face, weighted by boundaryWeight * length^2.
  // A non-manifold edge (3+ faces) is a feature line like a border: each of its faces adds the
  // plane through the edge orthogonal to it, so that the line keeps its shape; with foldPlanes, so
  // does an edge whose two faces lie nearly back to back (Folded). Which sides do is
  // found vertex by vertex (SideMasks: the faces around a vertex lie together in memory) rather
  // than by a search of a corner's faces for every side (the dragon: a quarter of init()).
  BigVector<uint8_t> sideMask;
  if (p_.boundaryWeight > 0) SideMasks(sideMask);
  quadric_.assign(pos_.size(), Quadric());
  const uint32_t nf = uint32_t(faces_.size());
  for (uint32_t f = 0; f < nf; ++f) {
    if (faceDead_[f]) continue;
    const auto& t = faces_[f];
    const Point3d n = AreaNormal(t);
    const double len = n.Norm();
    if (!(len > 0)) continue;
    const Point3d un = n / len;
    const double d = -(un * pos_[t[0]]);
    Quadric plane;
    plane.addPlane(un, d, 0.5 * len);
    for (uint32_t v : t) quadric_[v].addPlaneTerms(plane);
    if (p_.boundaryWeight <= 0 || sideMask[f] == 0) continue;
    for (int e = 0; e < 3; ++e) {
      if (!(sideMask[f] & (1u << e))) continue;
      const uint32_t u = t[size_t(e)], w = t[size_t((e + 1) % 3)];
      const Point3d edge = pos_[w] - pos_[u];
      Point3d dir = un ^ edge;
      const double dl = dir.Norm();
      if (!(dl > 0)) continue;
      dir /= dl;
      const double weight = p_.boundaryWeight * edge.SquaredNorm();
      quadric_[u].addPlane(dir, -(dir * pos_[u]), weight);
      quadric_[w].addPlane(dir, -(dir * pos_[w]), weight);
    }
  }
}

template <class GroupOf>
bool GroupQemSimplifier::condition1(const GroupOf& g, uint32_t a, uint32_t b, uint32_t e0, uint32_t e1, uint32_t n0a,
                                    uint32_t n0b, uint32_t n1a, uint32_t n1b, const std::vector<int>* layer) const {
  // f1 (and f2) keep a face of their own group among their other neighbours...
  const int g0 = g(e0);
  if (!((n0a != kNone && g(n0a) == g0) || (n0b != kNone && g(n0b) == g0))) return false;
  if (e1 == kNone) return true;
  const int g1 = g(e1);
  if (!((n1a != kNone && g(n1a) == g1) || (n1b != kNone && g(n1b) == g1))) return false;
  // ...and, when both are in one group, one endpoint's whole closed fan is in it.
  if (g0 != g1) return true;
  return layer ? (interiorIn(a, *layer) || interiorIn(b, *layer)) : (interior(a) || interior(b));
}

bool GroupQemSimplifier::place(uint32_t a, uint32_t b, bool contourEdge, Candidate& c) const {
  const bool fixedA = fixedVertex(a), fixedB = fixedVertex(b);
  Quadric q = quadric_[a];
  q += quadric_[b];
  if (fixedA && fixedB) {
    // Two attribute-seam vertices may merge (seamCollapse), into the cheaper end.
    if (!attributes_ || fixedVertex(a, false) || fixedVertex(b, false)) return false;
    c.keep = q.error(pos_[a]) <= q.error(pos_[b]) ? a : b;
    c.remove = c.keep == a ? b : a;
    c.position = pos_[c.keep];
    c.error = q.error(c.position);
    return true;
  }
  const bool contourA = contourVertex(a), contourB = contourVertex(b);
  if (fixedA || (contourA && !contourB)) {
    c.keep = a;
    c.position = pos_[a];
  } else if (fixedB || (contourB && !contourA)) {
    c.keep = b;
    c.position = pos_[b];
  } else if (contourA && contourB) {
    // Two points of one contour (condition 1 allows no other case): stay on the old segment.
    if (!contourEdge) return false;
    c.keep = b;
    c.position = p_.optimalPlacement ? q.segmentMinimum(pos_[a], pos_[b])
                                     : (q.eval(pos_[a]) < q.eval(pos_[b]) ? pos_[a] : pos_[b]);
  } else if (p_.optimalPlacement) {
    c.keep = b;
    Point3d x;
    const double edgeSq = (pos_[b] - pos_[a]).SquaredNorm();
    if (q.minimum(x) && (x - (pos_[a] + pos_[b]) * 0.5).SquaredNorm() <= 4 * edgeSq)
      c.position = x;
    else
      c.position = q.segmentMinimum(pos_[a], pos_[b]);
  } else {
    c.keep = b;
    c.position = pos_[b];
    if (q.eval(pos_[a]) < q.eval(pos_[b])) c.position = pos_[a];
  }
  if (c.position == pos_[a]) c.keep = a;
  c.remove = c.keep == a ? b : a;
  c.error = q.error(c.position);
  return true;
}

double GroupQemSimplifier::priorityOf(double error, double quality, uint32_t a, uint32_t b) const {
  if (error <= floorError_) error = floorError_ * std::sqrt((pos_[b] - pos_[a]).SquaredNorm()) / diag_;
  if (p_.qualityThr > 0) error /= std::max(std::min(quality, p_.qualityThr), kDegenerateQuality);
  return error;
}

// At most the priority judge() would give: the error at the quadric's unconstrained minimum (or
// of the better endpoint), with the best quality.
float GroupQemSimplifier::lowerBound(uint32_t a, uint32_t b) const {
  Quadric q = quadric_[a];
  q += quadric_[b];
  Point3d x;
  double error;
  if (p_.optimalPlacement && q.minimum(x))
    error = q.error(x);
  else
    error = std::min({q.error(pos_[a]), q.error(pos_[b]), q.error(q.segmentMinimum(pos_[a], pos_[b]))});
  return ToFloat(priorityOf(error, 1.0, a, b));
}

Candidate GroupQemSimplifier::evaluate(uint32_t a, uint32_t b) {
  ++stats_.evaluations;
  Candidate c = judge(a, b);
  switch (c.verdict) {
    case CollapseVerdict::Topology:
      ++stats_.refusedTopology;
      break;
    case CollapseVerdict::LockedBoundary:
      ++stats_.refusedLock;
      break;
    case CollapseVerdict::Condition1:
      ++stats_.refusedCondition1;
      break;
    case CollapseVerdict::Condition2:
      ++stats_.refusedCondition2;
      break;
    case CollapseVerdict::FixedEndpoints:
      ++stats_.refusedFixed;
      break;
    case CollapseVerdict::Geometry:
      ++stats_.refusedGeometry;
      break;
    case CollapseVerdict::Cone:
      ++stats_.refusedCone;
      break;
    default:
      break;
  }
  return c;
}

Candidate GroupQemSimplifier::judge(uint32_t a, uint32_t b) {
  Candidate c;
  if (a == b || vs_[a].dead || vs_[b].dead) return c;
  // Faces on the edge.
  uint32_t e[2];
  const uint32_t ne = edgeFaces(a, b, e);
  if (ne == 0) return c;
  if (frozen(a) || frozen(b)) {  // shared with another part of the mesh
    c.verdict = CollapseVerdict::FixedEndpoints;
    return c;
  }
  c.verdict = CollapseVerdict::Topology;
  const VertexInfo ia = vs_[a].info, ib = vs_[b].info;
  uint32_t n0a = kNone, n1a = kNone, n0b = kNone, n1b = kNone, opposite[2] = {kNone, kNone};
  // A non-manifold neighbourhood (an edge with 3+ faces, several fans, a border through an
  // edge's interior) takes the general path: one end goes into the other, which stays.
  const bool nonManifold = ne > 2 || ((ia.flags | ib.flags) & kNonManifold);
  if (nonManifold) {
    if (!nonManifoldCollapse(a, b, ne, c)) return c;
    if (attributes_) c.anchor = anchor_[c.keep];  // the kept end stays: so do its values (no seamPlace)
  } else {
    if (ne == 2 && (ia.flags & kOpen) && (ib.flags & kOpen)) return c;  // would pinch the surface
    const uint32_t opp0 = Third(faces_[e[0]], a, b), opp1 = ne == 2 ? Third(faces_[e[1]], a, b) : kNone;
    if (opp0 == opp1) return c;
    // A collapse takes the faces on the edge out of the opposite vertices' lists: their bounds are
    // asked for now, the lists once allowed (below).
    opposite[0] = opp0;
    opposite[1] = opp1;
    for (uint32_t o : opposite)
      if (o != kNone) {
        __builtin_prefetch(&start_[o]);
        __builtin_prefetch(&count_[o]);
      }
    // Link condition: a and b have no common neighbour but the opposite vertices, and faces
    // (a, opp0, opp1) and (b, opp0, opp1) do not both exist (a tetrahedron: they would merge).
    // On the way, the faces across the edges (a, opp) and (b, opp), for condition 1.
    ++stamp_;
    bool oppFaceA = false;
    for (const uint32_t* f = facesBegin(a); f != facesEnd(a); ++f) {
      if (*f == e[0] || *f == e[1]) continue;
      const auto& t = faces_[*f];
      for (uint32_t u : t) vs_[u].mark = stamp_;
      const bool has0 = Contains(t, opp0), has1 = opp1 != kNone && Contains(t, opp1);
      if (has0) n0a = *f;
      if (has1) n1a = *f;
      oppFaceA |= has0 && has1;
    }
    for (const uint32_t* f = facesBegin(b); f != facesEnd(b); ++f) {
      if (*f == e[0] || *f == e[1]) continue;
      const auto& t = faces_[*f];
      for (uint32_t u : t)
        if (u != b && u != opp0 && u != opp1 && vs_[u].mark == stamp_) return c;
      const bool has0 = Contains(t, opp0), has1 = opp1 != kNone && Contains(t, opp1);
      if (has0) n0b = *f;
      if (has1) n1b = *f;
      if (has0 && has1 && oppFaceA) return c;
    }
  }

  // Group conditions.
  if (p_.lockGroupBoundaries && ia.groups >= 2 && ib.groups >= 2) {
    c.verdict = CollapseVerdict::LockedBoundary;
    return c;
  }
  if (integrity_ &&
      !(nonManifold ? keepsGroupsWholeAcross(a, b) : keepsGroupsWhole(a, b, e[0], e[1], n0a, n0b, n1a, n1b))) {
    c.verdict = CollapseVerdict::Condition1;
    return c;
  }
  if (paperConditions_ && p_.condition1 && nonManifold) {
    // In a non-manifold neighbourhood the paper's local clauses do not apply (an edge may have
    // more than two faces, and more than one face across it): ask what they guarantee.
    c.verdict = CollapseVerdict::Condition1;
    if (!keepsGroupsWholeAcross(a, b)) return c;
  } else if (paperConditions_ && p_.condition1) {
    c.verdict = CollapseVerdict::Condition1;
    const auto primaryGroup = [this](uint32_t f) { return faces_[f].group; };
    if (!condition1(primaryGroup, a, b, e[0], e[1], n0a, n0b, n1a, n1b, nullptr)) return c;
    for (const auto* layer : coarser_)
      if (coarserNested_
              ? !condition1Nested(*layer, a, b, e[0], e[1])
              : !condition1([layer](uint32_t f) { return (*layer)[f]; }, a, b, e[0], e[1], n0a, n0b, n1a, n1b, layer))
        return c;
  }
  if (paperConditions_ && p_.condition2 && ia.groups + ib.groups >= 3) {
    c.verdict = CollapseVerdict::Condition2;
    if (std::min(ia.groups, ib.groups) > 2) return c;
    // Groups around the merged vertex: those of the faces of a and b that survive.
    groupScratch_.clear();
    const size_t limit = std::max<size_t>({2, ia.groups, ib.groups});
    for (uint32_t v : {a, b})
      for (const uint32_t* f = facesBegin(v); f != facesEnd(v); ++f) {
        if (Contains(faces_[*f], v == a ? b : a)) continue;  // on the edge
        const int g = faces_[*f].group;
        if (std::find(groupScratch_.begin(), groupScratch_.end(), g) == groupScratch_.end()) {
          groupScratch_.push_back(g);
          if (groupScratch_.size() > limit) return c;
        }
      }
  }

  c.verdict = CollapseVerdict::FixedEndpoints;
  if (!nonManifold && !place(a, b, ne == 2 && faces_[e[0]].group != faces_[e[1]].group, c)) return c;
  double seamCost = 0;
  if (attributes_ && (ne > 2 ? attributes_->seam(a) || attributes_->seam(b) : !seamCollapse(e, c, seamCost))) return c;
  if (attributes_ && !nonManifold) seamPlace(a, b, e, c, seamCost);

  // Geometry of the faces that survive: no flip, no zero-area face; their worst quality
  // (2 area / longest edge^2, compared squared: no square root per face).
  c.verdict = CollapseVerdict::Geometry;
  double minQualitySq = std::numeric_limits<double>::max();
  const double minCosSq = kMinNormalCos * kMinNormalCos, degenerateSq = kDegenerateQuality * kDegenerateQuality;
  const double nmFloorSq = kNonManifoldQualityFloor * kNonManifoldQualityFloor;
  const bool nmEnd = ((ia.flags | ib.flags) & kNonManifold) != 0;
  for (uint32_t v : {a, b})
    for (const uint32_t* f = facesBegin(v); f != facesEnd(v); ++f) {
      const auto& t = faces_[*f];
      if (Contains(t, v == a ? b : a)) continue;  // on the edge: removed
      // Rotate so that the moving vertex comes first.
      const int j = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
      const Point3d& p1 = pos_[t[size_t((j + 1) % 3)]];
      const Point3d& p2 = pos_[t[size_t((j + 2) % 3)]];
      const Point3d d1 = p1 - pos_[v], d2 = p2 - pos_[v];
      const Point3d n1 = p1 - c.position, n2 = p2 - c.position;
      const Point3d nOld = d1 ^ d2, nNew = n1 ^ n2;
      const double lenNewSq = nNew.SquaredNorm();
      const double longestSq = std::max({n1.SquaredNorm(), n2.SquaredNorm(), (p2 - p1).SquaredNorm()});
      const double qualitySq = longestSq > 0 ? lenNewSq / (longestSq * longestSq) : 0;
      const double lenOldSq = nOld.SquaredNorm();
      if (qualitySq < degenerateSq) {
        if (lenOldSq > 0) return c;  // would create a zero-area face
        continue;                    // was already degenerate: leave it to the user's cleaning
      }
      // The normal test, but for the last face of a group in integrity mode: that face can never
      // go, and where a scan leaves one it is a sliver on a non-manifold edge whose normal is
      // noise (stanford_dragon_vrip_res2: 1,632 one-face groups at level 4, median quality 0.07);
      // held to the test it refuses every collapse around it and its neighbourhood keeps its faces.
      if (p_.preserveNormal && lenOldSq > 0 && !(integrity_ && groupFaces_[0][size_t(t.group)] == 1)) {
        const double dot = nOld * nNew;
        if (dot < 0 || dot * dot < minCosSq * lenOldSq * lenNewSq) return c;
      }
      if (p_.keepCones && !insideCones(*f, nNew, lenNewSq)) {
        c.verdict = CollapseVerdict::Cone;
        return c;
      }
      const bool nearNonManifold =
          nmEnd || ((vs_[t[0]].info.flags | vs_[t[1]].info.flags | vs_[t[2]].info.flags) & kNonManifold);
      minQualitySq = std::min(minQualitySq, nearNonManifold ? std::max(qualitySq, nmFloorSq) : qualitySq);
    }

  c.verdict = CollapseVerdict::Allowed;
  for (uint32_t o : opposite)
    if (o != kNone) __builtin_prefetch(facesBegin(o));
  const double attributeCost = attributes_ ? attributes_->Cost(a, b, inputPosition(c.position)) + seamCost : 0;
  c.priority = priorityOf(c.error + attributeCost, std::sqrt(minQualitySq), a, b);
  return c;
}

bool GroupQemSimplifier::seamCollapse(const uint32_t e[2], Candidate& c, double& seamCost) const {
  const auto cost = [&](uint32_t gone, uint32_t keep) {
    return attributes_->SeamCost(gone, keep, e[0], e[1], facesBegin(gone), count_[gone], faceCorners_,
                                 (pos_[gone] - pos_[keep]).SquaredNorm());
  };
  seamCost = cost(c.remove, c.keep);
  // Two seam vertices (place() kept the end of least error): the other way round when only it is
  // allowed, or it costs less with its seam move.
  if (attributes_->seamMoves() && attributes_->seam(c.keep) && attributes_->seam(c.remove) &&
      !fixedVertex(c.keep, false) && !fixedVertex(c.remove, false)) {
    const double other = cost(c.keep, c.remove);
    if (other >= 0) {
      Quadric q = quadric_[c.keep];
      q += quadric_[c.remove];
      const double otherError = q.error(pos_[c.remove]);
      if (seamCost < 0 || otherError + other < c.error + seamCost) {
        std::swap(c.keep, c.remove);
        c.position = pos_[c.keep];
        c.error = otherError;
        seamCost = other;
      }
    }
  }
  return seamCost >= 0;
}

bool GroupQemSimplifier::placeAtSeam(uint32_t a, uint32_t b, Candidate& c) const {
  uint32_t e[2];
  const uint32_t ne = edgeFaces(a, b, e);
  if (ne == 0 || ne > 2) return false;
  double seamCost = 0;
  if (!seamCollapse(e, c, seamCost)) return false;
  seamPlace(a, b, e, c, seamCost);
  return true;
}

void GroupQemSimplifier::seamPlace(uint32_t a, uint32_t b, const uint32_t e[2], Candidate& c, double& seamCost) const {
  if (!attributes_->seam(c.keep)) return;  // off the seams: place()'s position
  const uint32_t keep = c.keep, gone = c.remove;
  c.anchor = anchor_[keep];
  if (!p_.optimalPlacement) return;
  // A group contour point stays on its contour: both ends on it and the edge along it, or neither.
  const bool contourA = contourVertex(a), contourB = contourVertex(b);
  const bool alongContour = contourA && contourB && e[1] != kNone && faces_[e[0]].group != faces_[e[1]].group;
  if (contourA != contourB || (contourA && !alongContour)) return;
  Quadric q = quadric_[a];
  q += quadric_[b];
  // Along a seam between two plain seam points: the anchor anywhere on the anchors' segment.
  if (seamCost == 0 && e[1] != kNone && attributes_->seam(gone) &&
      attributes_->SlidesAlong(a, b, e[0], e[1], faceCorners_)) {
    const Point3d s = q.segmentMinimum(anchor_[keep], anchor_[gone]);
    if (!(s == anchor_[gone])) c.anchor = s;  // at gone's anchor: the other way round is the same
  }
  if (!attributes_->seamMoves() || contourA) {  // the vertex stays at its anchor
    if (c.anchor == anchor_[keep] || !(anchor_[keep] == pos_[keep])) {
      c.anchor = anchor_[keep];
      return;
    }
    const double error = q.error(c.anchor);
    if (error < c.error) {
      c.position = c.anchor;
      c.error = error;
    } else {
      c.anchor = anchor_[keep];
    }
    return;
  }
  // Off its anchor at a cost: the minimum of error(x) + kSeamDrift |x - anchor|_t^2, where |.|_t
  // is the distance in the tangent plane of the ends' faces (the area-weighted normal's
  // complement): along the normal the texture does not move on the surface, so that is free.
  // Point quadrics in the two tangent directions, added to the geometric one.
  Point3d n(0, 0, 0);
  for (uint32_t v : {a, b})
    for (const uint32_t* f = facesBegin(v); f != facesEnd(v); ++f) n += AreaNormal(faces_[*f]);
  const double len = n.Norm();
  Quadric d = q;
  const double k = kSeamDrift * (q.w > 0 ? q.w : 1.0);
  Point3d axes[3] = {Point3d(1, 0, 0), Point3d(0, 1, 0), Point3d(0, 0, 1)};
  int count = 3;  // no normal (a flat fan of degenerate faces): every direction costs
  if (len > 0 && std::isfinite(len)) {
    n /= len;
    axes[0] = std::fabs(n[0]) < 0.9 ? Point3d(1, 0, 0) ^ n : Point3d(0, 1, 0) ^ n;
    axes[0].Normalize();
    axes[1] = n ^ axes[0];
    count = 2;
  }
  for (int i = 0; i < count; ++i) d.addPlane(axes[i], -(axes[i] * c.anchor), k);
  Point3d x;
  if (!d.minimum(x)) x = c.anchor;
  c.position = x;
  c.error = q.error(x);
  double tangentSq = 0;
  for (int i = 0; i < count; ++i) tangentSq += ((x - c.anchor) * axes[i]) * ((x - c.anchor) * axes[i]);
  seamCost += kSeamDrift * tangentSq;
}

bool GroupQemSimplifier::keepsApart(uint32_t a, uint32_t b, const Point3d& p) {
  // The neighbours of a (marked sa), then those of b: one that a has too is marked sb (a common
  // one), one of b's alone is listed after a's (from onlyB).
  const uint32_t sa = ++stamp_, sb = ++stamp_;
  nbScratch_.clear();
  for (const uint32_t* f = facesBegin(a); f != facesEnd(a); ++f)
    for (uint32_t u : faces_[*f])
      if (u != a && u != b && vs_[u].mark != sa) {
        vs_[u].mark = sa;
        if ((pos_[u] - p).SquaredNorm() < separationSq_) return false;
        nbScratch_.push_back(u);
      }
  const size_t onlyB = nbScratch_.size();
  for (const uint32_t* f = facesBegin(b); f != facesEnd(b); ++f)
    for (uint32_t u : faces_[*f])
      if (u != a && u != b && vs_[u].mark != sb) {
        const bool common = vs_[u].mark == sa;
        vs_[u].mark = sb;
        if (common) continue;
        if ((pos_[u] - p).SquaredNorm() < separationSq_) return false;
        nbScratch_.push_back(u);
      }
  // Only the pairs the collapse joins anew: one of a's alone with one of b's alone. Two vertices
  // both a's neighbours (or both b's) are already joined to one vertex, which the collapse keeps
  // (its faces but those on the edge (a, b)): such a close pair is carried as it is (issue 27: refusing
  // it kept every vertex around a fine frozen border of a subdivided input from collapsing).
  for (size_t i = 0; i < onlyB; ++i) {
    if (vs_[nbScratch_[i]].mark == sb) continue;  // a common neighbour
    for (size_t j = onlyB; j < nbScratch_.size(); ++j)
      if ((pos_[nbScratch_[i]] - pos_[nbScratch_[j]]).SquaredNorm() < separationSq_) return false;
  }
  return true;
}

bool GroupQemSimplifier::nonManifoldCollapse(uint32_t a, uint32_t b, uint32_t ne, Candidate& c) {
  edgeFaces_.clear();
  opposite_.clear();
  for (const uint32_t* f = facesBegin(a); f != facesEnd(a); ++f) {
    const auto& t = faces_[*f];
    if (!Contains(t, b)) continue;
    if (UsesAVertexTwice(t)) return false;  // a degenerate face on the edge
    edgeFaces_.push_back(*f);
    const uint32_t o = Third(t, a, b);
    if (std::find(opposite_.begin(), opposite_.end(), o) == opposite_.end()) opposite_.push_back(o);
  }
  if (ne == 2 && opposite_.size() == 1) return false;  // two copies of one face, alone on the edge
  const auto isOpposite = [&](uint32_t u) {
    return std::find(opposite_.begin(), opposite_.end(), u) != opposite_.end();
  };
  // Which end may go into the other (as meshoptimizer's vertex kinds: a manifold vertex into
  // anything, a point of a non-manifold line only along the line, a junction of lines never).
  const auto removable = [&](const VertexInfo& vi) {
    if (p_.preserveBoundary && (vi.flags & kBorderEdge)) return false;
    if (groupConstraints_ && vi.groups > 1) return false;  // paper mode / lock: group boundaries stay
    if (!(vi.flags & kNonManifold)) return true;
    if (vi.flags & kNmJunction) return false;
    if (vi.flags & kNmEdge) return ne > 2;
    return ne <= 2;  // several fans but no non-manifold edge: along any edge
  };
  const VertexInfo& ia = vs_[a].info;
  const VertexInfo& ib = vs_[b].info;
  // A manifold end goes into a non-manifold one (which keeps its kind), never the reverse.
  const bool nmA = ia.flags & kNonManifold, nmB = ib.flags & kNonManifold;
  const bool goA = removable(ia) && (nmA || nmB ? nmA == nmB || !nmA : true) && !(attributes_ && attributes_->seam(a));
  const bool goB = removable(ib) && (nmA || nmB ? nmA == nmB || !nmB : true) && !(attributes_ && attributes_->seam(b));
  if (!goA && !goB) return false;
  // Link condition: the common neighbours of a and b are the opposite vertices only.
  ++stamp_;
  for (const uint32_t* f = facesBegin(a); f != facesEnd(a); ++f)
    if (!Contains(faces_[*f], b))
      for (uint32_t u : faces_[*f]) vs_[u].mark = stamp_;
  for (const uint32_t* f = facesBegin(b); f != facesEnd(b); ++f) {
    const auto& t = faces_[*f];
    if (Contains(t, a)) continue;
    for (uint32_t u : t)
      if (u != b && vs_[u].mark == stamp_ && !isOpposite(u)) return false;
    // Faces (b, x, y) and (a, x, y) would become one face twice.
    const uint32_t x = t[0] == b ? t[1] : t[0], y = t[2] == b ? t[1] : t[2];
    if (isOpposite(x) && isOpposite(y))
      for (const uint32_t* g = facesBegin(a); g != facesEnd(a); ++g)
        if (Contains(faces_[*g], x) && Contains(faces_[*g], y)) return false;
  }
  // No edge becomes non-manifold: the merged edge (m, x) has the faces of (a, x) and (b, x) but
  // those on (a, b); it may have more than 2 only where (a, x) or (b, x) had as many.
  for (uint32_t x : opposite_) {
    uint32_t k1 = 0, k2 = 0, tx = 0;
    for (const uint32_t* f = facesBegin(a); f != facesEnd(a); ++f) k1 += Contains(faces_[*f], x);
    for (const uint32_t* f = facesBegin(b); f != facesEnd(b); ++f) k2 += Contains(faces_[*f], x);
    for (uint32_t f : edgeFaces_) tx += Third(faces_[f], a, b) == x;
    const uint32_t merged = k1 + k2 - 2 * tx;
    if (merged > 2 && merged > std::max(k1, k2)) return false;
  }
  // The merged vertex stays at the end that does not go (meshoptimizer's placement: no new
  // position on a feature); of two that may go, the cheaper.
  Quadric q = quadric_[a];
  q += quadric_[b];
  c.keep = goA && goB ? (q.error(pos_[a]) <= q.error(pos_[b]) ? a : b) : (goA ? b : a);
  c.remove = c.keep == a ? b : a;
  c.position = pos_[c.keep];
  c.error = q.error(c.position);
  return true;
}

bool GroupQemSimplifier::keepsGroupsWholeAcross(uint32_t a, uint32_t b) {
  edgeFaces_.clear();
  for (const uint32_t* f = facesBegin(a); f != facesEnd(a); ++f)
    if (Contains(faces_[*f], b)) edgeFaces_.push_back(*f);
  // After the collapse b is a: faces are adjacent when they share two vertices with b read as a.
  const auto has = [&](const FaceRec& t, uint32_t v) { return Contains(t, v) || (v == a && Contains(t, b)); };
  for (int layer = -1; layer < int(coarserDense_.size()); ++layer) {
    const std::vector<int>& count = groupFaces_[size_t(layer + 1)];
    for (size_t i = 0; i < edgeFaces_.size(); ++i) {
      const int G = groupIn(layer, edgeFaces_[i]);
      bool seen = false;
      for (size_t j = 0; j < i; ++j) seen |= groupIn(layer, edgeFaces_[j]) == G;
      if (seen) continue;
      int removed = 0;
      for (uint32_t f : edgeFaces_) removed += faceOf(layer, f, G);
      if (removed > 0 && count[size_t(G)] <= removed) return false;  // its last faces
      // G's faces next to its removed ones.
      ++faceStamp_;
      for (uint32_t f : edgeFaces_) faceMark_[f] = faceStamp_;
      nbScratch_.clear();
      for (uint32_t f : edgeFaces_) {
        if (groupIn(layer, f) != G) continue;
        const uint32_t x = Third(faces_[f], a, b);
        for (uint32_t v : {a, b})
          for (const uint32_t* g = facesBegin(v); g != facesEnd(v); ++g)
            if (faceMark_[*g] != faceStamp_ && faceOf(layer, *g, G) && Contains(faces_[*g], x) &&
                std::find(nbScratch_.begin(), nbScratch_.end(), *g) == nbScratch_.end())
              nbScratch_.push_back(*g);
      }
      if (nbScratch_.size() <= 1) continue;
      queue_.assign(1, nbScratch_[0]);
      faceMark_[nbScratch_[0]] = faceStamp_;
      size_t found = 1;
      for (size_t head = 0; head < queue_.size() && found < nbScratch_.size(); ++head) {
        if (queue_.size() > kIntegritySearchFaces) return false;
        const auto& t = faces_[queue_[head]];
        for (int j = 0; j < 3; ++j) {
          uint32_t u = t[size_t(j)], w = t[size_t((j + 1) % 3)];
          if (u == b) u = a;
          if (w == b) w = a;
          if (u == w) continue;
          for (int pass = 0; pass < (u == a ? 2 : 1); ++pass)
            for (const uint32_t* g = facesBegin(pass ? b : u); g != facesEnd(pass ? b : u); ++g) {
              if (faceMark_[*g] == faceStamp_ || !faceOf(layer, *g, G) || !has(faces_[*g], w)) continue;
              faceMark_[*g] = faceStamp_;
              queue_.push_back(*g);
              found += std::find(nbScratch_.begin(), nbScratch_.end(), *g) != nbScratch_.end();
            }
        }
      }
      if (found < nbScratch_.size()) return false;
    }
  }
  return true;
}

bool GroupQemSimplifier::keepsGroupsWhole(uint32_t a, uint32_t b) {
  uint32_t e[2];
  const uint32_t ne = edgeFaces(a, b, e);
  if (ne == 0 || ne > 2) return false;
  const uint32_t opp0 = Third(faces_[e[0]], a, b), opp1 = ne == 2 ? Third(faces_[e[1]], a, b) : kNone;
  uint32_t n[4] = {kNone, kNone, kNone, kNone};  // n0a, n0b, n1a, n1b
  for (int s = 0; s < 2; ++s) {
    const uint32_t v = s == 0 ? a : b;
    for (const uint32_t* f = facesBegin(v); f != facesEnd(v); ++f) {
      if (*f == e[0] || *f == e[1]) continue;
      if (Contains(faces_[*f], opp0)) n[s] = *f;
      if (opp1 != kNone && Contains(faces_[*f], opp1)) n[2 + s] = *f;
    }
  }
  return keepsGroupsWhole(a, b, e[0], e[1], n[0], n[1], n[2], n[3]);
}

bool GroupQemSimplifier::keepsGroupsWhole(uint32_t a, uint32_t b, uint32_t e0, uint32_t e1, uint32_t n0a, uint32_t n0b,
                                          uint32_t n1a, uint32_t n1b) {
  for (int layer = -1; layer < int(coarserDense_.size()); ++layer)
    if (!keepsGroupWhole(layer, a, b, e0, e1, n0a, n0b, n1a, n1b)) return false;
  return true;
}

// With the link condition, collapsing (a, b) removes e0 and e1, keeps every other adjacency and
// adds two: n0a-n0b (they now share the edge (m, opp0)) and n1a-n1b. So only the groups of e0 and
// e1 can lose anything: such a group G vanishes when e0/e1 are its last faces, and splits when
// its faces next to e0/e1 (among n0a, n0b, n1a, n1b) are no longer connected inside G. These are
// connected when they are through the merged vertex's fan (two faces of the fan are adjacent when
// they share a vertex other than a and b), and otherwise when a bounded search inside G joins them.
bool GroupQemSimplifier::keepsGroupWhole(int layer, uint32_t a, uint32_t b, uint32_t e0, uint32_t e1, uint32_t n0a,
                                         uint32_t n0b, uint32_t n1a, uint32_t n1b) {
  const std::vector<int>& count = groupFaces_[size_t(layer + 1)];
  const int g0 = groupIn(layer, e0), g1 = e1 != kNone ? groupIn(layer, e1) : -1;
  for (int pass = 0; pass < 2; ++pass) {
    const int G = pass == 0 ? g0 : g1;
    if (G < 0 || (pass == 1 && G == g0)) continue;
    const int removed = faceOf(layer, e0, G) + (e1 != kNone && faceOf(layer, e1, G));
    if (removed > 0 && count[size_t(G)] <= removed) return false;  // its last faces
    uint32_t nb[4];
    int nn = 0;
    const auto add = [&](uint32_t f) {
      if (f != kNone && faceOf(layer, f, G) && std::find(nb, nb + nn, f) == nb + nn) nb[nn++] = f;
    };
    // Only one of e0, e1 in G: its (at most two) faces of G next to it become adjacent.
    if (g0 != g1) continue;
    // Both: the faces of a closed fan of v1 (or v2) inside G join n0a (n0b) and n1a (n1b).
    if (layer < 0 ? (interior(a) || interior(b))
                  : (interiorIn(a, coarserDense_[size_t(layer)]) || interiorIn(b, coarserDense_[size_t(layer)])))
      continue;
    add(n0a);
    add(n0b);
    add(n1a);
    add(n1b);
    if (nn <= 1) continue;
    // The fan of the merged vertex: G's faces around a and b but e0, e1; union-find.
    fanScratch_.clear();
    for (uint32_t v : {a, b})
      for (const uint32_t* f = facesBegin(v); f != facesEnd(v); ++f)
        if (*f != e0 && *f != e1 && faceOf(layer, *f, G)) fanScratch_.push_back(*f);
    const uint32_t k = uint32_t(fanScratch_.size());
    fanParent_.resize(k);
    for (uint32_t i = 0; i < k; ++i) fanParent_[i] = i;
    const auto root = [this](uint32_t i) {
      while (fanParent_[i] != i) i = fanParent_[i] = fanParent_[fanParent_[i]];
      return i;
    };
    const auto other = [&](uint32_t f, int j) {  // the j-th (0, 1) vertex of f other than a, b
      const auto& t = faces_[f];
      int seen = 0;
      for (uint32_t v : t)
        if (v != a && v != b && seen++ == j) return v;
      return kNone;
    };
    for (uint32_t i = 0; i < k; ++i) {
      const uint32_t x0 = other(fanScratch_[i], 0), x1 = other(fanScratch_[i], 1);
      for (uint32_t j = i + 1; j < k; ++j) {
        const uint32_t y0 = other(fanScratch_[j], 0), y1 = other(fanScratch_[j], 1);
        if ((x0 != kNone && (x0 == y0 || x0 == y1)) || (x1 != kNone && (x1 == y0 || x1 == y1)))
          fanParent_[root(i)] = root(j);
      }
    }
    const auto indexOf = [&](uint32_t f) {
      return uint32_t(std::find(fanScratch_.begin(), fanScratch_.end(), f) - fanScratch_.begin());
    };
    const uint32_t r0 = root(indexOf(nb[0]));
    bool local = true;
    for (int i = 1; i < nn && local; ++i) local = root(indexOf(nb[i])) == r0;
    if (local) continue;
    // Search inside G, from nb[0]'s piece of the fan, for the other pieces (edges as after the
    // collapse: e0, e1 gone, n0a-n0b and n1a-n1b adjacent).
    ++faceStamp_;
    queue_.clear();
    for (uint32_t i = 0; i < k; ++i)
      if (root(i) == r0) {
        faceMark_[fanScratch_[i]] = faceStamp_;
        queue_.push_back(fanScratch_[i]);
      }
    faceMark_[e0] = faceStamp_;
    if (e1 != kNone) faceMark_[e1] = faceStamp_;
    const auto reached = [&]() {
      for (int i = 1; i < nn; ++i)
        if (faceMark_[nb[i]] != faceStamp_) return false;
      return true;
    };
    const auto visit = [&](uint32_t f) {
      if (f == kNone || faceMark_[f] == faceStamp_ || !faceOf(layer, f, G)) return;
      faceMark_[f] = faceStamp_;
      queue_.push_back(f);
    };
    bool joined = false;
    for (size_t head = 0; head < queue_.size() && queue_.size() <= kIntegritySearchFaces; ++head) {
      const uint32_t f = queue_[head];
      const auto& t = faces_[f];
      for (int j = 0; j < 3; ++j) {
        const uint32_t u = t[size_t(j)], w = t[size_t((j + 1) % 3)];
        for (const uint32_t* g = facesBegin(u); g != facesEnd(u); ++g)
          if (*g != f && Contains(faces_[*g], w)) visit(*g);
      }
      if (f == n0a) visit(n0b);
      if (f == n0b) visit(n0a);
      if (f == n1a) visit(n1b);
      if (f == n1b) visit(n1a);
      if (reached()) {
        joined = true;
        break;
      }
    }
    if (!joined && !reached()) return false;
  }
  return true;
}

void GroupQemSimplifier::PushEdgesOf(uint32_t v) {
  ++stamp_;
  vs_[v].mark = stamp_;
  for (const uint32_t* f = facesBegin(v); f != facesEnd(v); ++f)
    for (uint32_t u : faces_[*f])
      if (vs_[u].mark != stamp_) {
        vs_[u].mark = stamp_;
        PushLazy(v, u);
      }
}

void GroupQemSimplifier::collapse(const Candidate& c) {
  const uint32_t keep = c.keep, gone = c.remove;
  // Both ends inside one group's closed manifold fan (the common case): the merged vertex is too
  // (the collapse passed the link condition), so its analysis is known without reading its fan.
  const bool interiorEnds = IsInterior(vs_[keep].info) && IsInterior(vs_[gone].info);
  if (attributes_) {
    if (attributes_->seam(keep) && attributes_->seam(gone) && !(c.anchor == anchor_[keep])) {  // a slide
      const Point3d d = anchor_[gone] - anchor_[keep];
      const double dd = d.SquaredNorm();
      const double t = dd > 0 ? std::min(1.0, std::max(0.0, ((c.anchor - anchor_[keep]) * d) / dd)) : 0.0;
      attributes_->Slide(keep, gone, t, facesBegin(keep), count_[keep], facesBegin(gone), count_[gone], faceCorners_);
    } else {
      attributes_->Collapse(keep, gone, facesBegin(gone), count_[gone], faceCorners_);
    }
    if (attributes_->seam(keep)) anchor_[keep] = c.anchor;
  }
  // The faces on the edge die and leave the lists of their opposite vertices.
  opposite_.clear();
  for (const uint32_t* f = facesBegin(gone); f != facesEnd(gone); ++f) {
    if (!Contains(faces_[*f], keep)) continue;
    faceDead_[*f] = 1;
    const bool flat = UsesAVertexTwice(faces_[*f]);
    liveFaces_ -= !flat;
    if (countGroups_ && !flat)
      for (size_t l = 0; l < groupFaces_.size(); ++l) --groupFaces_[l][size_t(groupIn(int(l) - 1, *f))];
    const uint32_t o = Third(faces_[*f], keep, gone);
    opposite_.push_back(o);
    uint32_t* ob = refs_.data() + start_[o];
    for (uint32_t i = 0; i < count_[o]; ++i)
      if (ob[i] == *f) {
        ob[i] = ob[--count_[o]];
        break;
      }
  }
  // The survivor's new list goes at the end of refs_ (rebuilt from scratch when full).
  if (!listRoom(count_[keep] + count_[gone])) {
    for (const uint32_t* f = facesBegin(gone); f != facesEnd(gone); ++f)
      if (!faceDead_[*f])
        for (auto& v : faces_[*f])
          if (v == gone) v = keep;
    count_[gone] = 0;
    BuildFaceLists();
  } else {
    const uint32_t begin = uint32_t(refs_.size());
    for (uint32_t v : {keep, gone}) {
      const uint32_t s = start_[v], n = count_[v];
      for (uint32_t i = 0; i < n; ++i) {
        const uint32_t f = refs_[s + i];
        if (faceDead_[f]) continue;
        if (v == gone)
          for (auto& x : faces_[f])
            if (x == gone) x = keep;
        refs_.push_back(f);
      }
    }
    start_[keep] = begin;
    count_[keep] = uint32_t(refs_.size()) - begin;
    count_[gone] = 0;
  }
  vs_[gone].dead = 1;
  // A seam vertex that leaves its anchor (seamPlace's drift): its corner values follow it inside
  // their charts (AttributeQuadrics::Reparameterize), and hold there.
  if (attributes_ && attributes_->seam(keep) && !(c.position == anchor_[keep])) {
    attributes_->Reparameterize(keep, anchor_[keep], c.position, facesBegin(keep), count_[keep], faceCorners_,
                                [this](uint32_t v) { return pos_[v]; });
    anchor_[keep] = c.position;
  }
  pos_[keep] = c.position;
  quadric_[keep] += quadric_[gone];
  ++epoch_;
  vs_[keep].lastSurvive = vs_[keep].touched = epoch_;
  if (!interiorEnds) AnalyzeVertex(keep);
  // An opposite vertex lost a face: its groups may have changed, and with them what its edges may do.
  // One inside one group's closed manifold fan that lost one face keeps its analysis: the two faces
  // beside the lost one now share the edge to keep (no other face holds o and an end: each edge
  // of its fan has two faces), its fan is one closed cycle of one face less, in one group.
  for (const uint32_t o : opposite_) {
    const VertexInfo before = vs_[o].info;
    if (IsInterior(before) && std::count(opposite_.begin(), opposite_.end(), o) == 1) continue;
    AnalyzeVertex(o);
    if (vs_[o].info.flags != before.flags || vs_[o].info.groups != before.groups) vs_[o].dropped = 1;
  }
  // The ring's neighbourhoods changed; those with dropped collapses get all their edges queued again.
  ring_.clear();
  ++stamp_;
  vs_[keep].mark = stamp_;
  for (const uint32_t* f = facesBegin(keep); f != facesEnd(keep); ++f)
    for (uint32_t u : faces_[*f])
      if (vs_[u].mark != stamp_) {
        vs_[u].mark = stamp_;
        vs_[u].touched = epoch_;
        if (ranking_) continue;  // every edge is ranked again by the next pass
        PushLazy(keep, u);
        if (vs_[u].dropped) ring_.push_back(u);
      }
  for (uint32_t u : ring_) {
    vs_[u].dropped = 0;
    vs_[u].lastSurvive = epoch_;
    PushEdgesOf(u);
  }
}

// GroupQemParams::passes (the idea of meshoptimizer's simplifier, not its code): each pass ranks
// every live edge at its lower bound, sorts the ranks (stable radix sort: equal ranks keep the
// edges' order, so the result is deterministic), and walks them in order. An edge is judged in
// full (the same judge() as the queue's) when neither endpoint has survived a collapse in this
// pass (its rank is then still that of its quadrics); it is collapsed when allowed, unless its
// full priority is over the pass's error goal (1.5x the rank of the collapse the pass would end
// with if every collapse removed two faces) once a sixth of the pass's goal is done. A pass ends
// at the target, or at a rank over the goal once that sixth is done. A pass without a collapse:
// no allowed collapse is left. The passes hand over to the queue (CollapseInQueue, from the state
// reached) at a quarter of GroupQemParams::queueFaces live faces (25,000 by default; a mesh of at
// most queueFaces faces from the start runs the queue alone, as before the passes), when the
// target is near (at most an eighth of the live faces left to remove: a pass would rank every edge
// for a few collapses, and the last collapses decide the most error) or when a pass stalls (under
// a sixth of its goal: the allowed collapses are dearer than their ranks, as where topology or the
// groups leave little room), so that the run ends, and stops at a floor, as the queue's.
bool GroupQemSimplifier::CollapseInPasses(const Progress& progress, size_t target, double maxErrorSq,
                                          GroupQemStats& stats) {
  // 8 bytes: the edge is named by a side of a live face (3 f + s: from corner s to s + 1), read
  // back when the walk reaches it. A face renamed or removed since (in this pass) has an endpoint
  // that survived a collapse or died, and such an edge is passed over in either reading.
  struct Ranked {
    float priority;
    uint32_t side;
  };
  // Mapped (BigVector), sized for the most edges the live faces can have (three each) and freed at
  // the end of each pass: only the pages the ranks reach take memory, and the face lists' room,
  // which the collapses fill pass after pass, does not sit beside the first pass's ranks.
  BigVector<Ranked> ranked, scratch;
  std::vector<uint32_t> histogram(3 * 2048);
  const auto key = [](const Ranked& r) {
    uint32_t k;
    std::memcpy(&k, &r.priority, 4);
    return k;
  };
  const size_t toRemove = stats.facesIn > target ? stats.facesIn - target : 1;
  size_t nextReport = 0, checked = 0;
  const auto report = [&]() {
    const size_t done = stats.facesIn - liveFaces_;
    if (!progress || done < nextReport) return true;
    nextReport = done + std::max<size_t>(toRemove / 100, 1);
    return progress(5 + int(93.0 * std::min(1.0, double(done) / double(toRemove))), "Group-preserving QEM: collapsing");
  };
  // GroupQemParams::queueFaces: the queue alone up to it, else the queue from a quarter of it.
  const size_t handOverFaces = liveFaces_ <= p_.queueFaces ? p_.queueFaces : p_.queueFaces / 4;
  ranking_ = true;
  const auto handOver = [&](bool queue) {
    ranking_ = false;
    return queue;
  };
  while (liveFaces_ > target) {
    if (liveFaces_ <= handOverFaces || (target > 0 && liveFaces_ - target <= liveFaces_ / 8)) return handOver(true);
    // Half the arrays dead: the next passes work on the live part, packed.
    if (compactable() && liveFaces_ <= faces_.size() / 2) Compact();
    // A memoryless step falls between two passes (after the packing: its sweep reads the live
    // faces only; the packing keeps every order, so the sums are the same).
    Refresh();
    const uint32_t nv = uint32_t(pos_.size());
    // Rank every live edge once, from its lower endpoint.
    ranked.reserve(3 * liveFaces_);
    for (uint32_t v = 0; v < nv; ++v) {
      if (vs_[v].dead || count_[v] == 0 || frozen(v)) continue;
      ++stamp_;
      for (const uint32_t* f = facesBegin(v); f != facesEnd(v); ++f)
        for (uint32_t k = 0; k < 3; ++k) {
          const uint32_t u = faces_[*f][k];
          if (u > v && vs_[u].mark != stamp_) {
            vs_[u].mark = stamp_;
            // the side (v, u) or (u, v): u at corner k, v before or after it
            const uint32_t side = faces_[*f][(k + 2) % 3] == v ? (k + 2) % 3 : k;
            if (!frozen(u)) ranked.push_back({lowerBound(v, u), 3 * *f + side});
          }
        }
      if (progress && (++checked & 0xffff) == 0 && !report()) {
        stats.stop = GroupQemStats::Stop::Cancelled;
        return handOver(false);
      }
    }
    if (ranked.empty()) return handOver(false);

    // The pass's goal: what is left to remove, but at least an eighth of the faces (else the last
    // passes, each ending a sixth of the way to the target, would rank every edge for a few collapses).
    const size_t faceGoal = std::max(target > 0 ? liveFaces_ - target : liveFaces_, liveFaces_ / 8);
    const size_t edgeGoal = faceGoal / 2;
    // The error goal is 1.5x the rank at position edgeGoal of the ranks in order: found by a radix
    // selection on the rank's bits (non-negative floats order as their bits), 11 bits at a time,
    // without sorting.
    float errorGoal = std::numeric_limits<float>::max();
    if (edgeGoal < ranked.size()) {
      size_t k = edgeGoal;
      uint32_t high = 0;  // the bits found so far, above `shift`
      for (int shift = 22; shift >= 0; shift -= 11) {
        std::fill(histogram.begin(), histogram.begin() + 2048, 0u);
        const uint32_t above = shift == 22 ? 0 : ~((uint32_t(1) << (shift + 11)) - 1);
        for (const Ranked& r : ranked)
          if ((key(r) & above) == high) ++histogram[(key(r) >> shift) & 2047];
        uint32_t digit = 0;
        while (k >= histogram[digit]) k -= histogram[digit++];
        high |= digit << shift;
      }
      float rank;
      std::memcpy(&rank, &high, 4);
      errorGoal = 1.5f * rank;
    }
    // The walk, in rank order, ends at the first rank over the goal (if it gets there): the least
    // such rank's bits are `stop`, and only the ranks below it are ever read. They are kept, in
    // their order, and sorted alone (the sort's second buffer is that much smaller).
    uint32_t stop = UINT32_MAX;
    bool stops = false;
    for (const Ranked& r : ranked)
      if (r.priority > errorGoal && (!stops || key(r) < stop)) {
        stop = key(r);
        stops = true;
      }
    if (stops) {
      size_t kept = 0;
      for (const Ranked& r : ranked)
        if (key(r) < stop) ranked[kept++] = r;
      ranked.resize(kept);
    }
    // Stable LSD radix sort on the rank's bits, 11 bits at a time: equal ranks keep their order.
    scratch.reserve(ranked.size());
    scratch.resize(ranked.size());
    std::fill(histogram.begin(), histogram.end(), 0u);
    for (const Ranked& r : ranked) {
      const uint32_t k = key(r);
      ++histogram[k & 2047];
      ++histogram[2048 + ((k >> 11) & 2047)];
      ++histogram[4096 + (k >> 22)];
    }
    for (int d = 0; d < 3; ++d) {
      uint32_t sum = 0;
      for (uint32_t* h = histogram.data() + 2048 * d; h != histogram.data() + 2048 * (d + 1); ++h) {
        const uint32_t n = *h;
        *h = sum;
        sum += n;
      }
      uint32_t* h = histogram.data() + 2048 * d;
      for (const Ranked& r : ranked) scratch[h[(key(r) >> (11 * d)) & 2047]++] = r;
      ranked.swap(scratch);
    }
    BigVector<Ranked>().swap(scratch);
    float over = std::numeric_limits<float>::max();  // the least priority over the goal met
    const uint32_t passStart = epoch_;
    const size_t facesAtStart = liveFaces_;
    size_t collapses = 0;
    // The walk reads each edge's neighbourhood at random (in rank order): it is fetched ahead in
    // stages, so that the cache misses overlap instead of stalling one after the other: the edge's
    // face kAhead[0] entries ahead, its vertices' states and list bounds kAhead[1] ahead (the face
    // has arrived by then), their positions, quadrics and face lists kAhead[2] ahead, their faces
    // kAhead[3] ahead, and the positions and states of the vertices around them kAhead[4] ahead
    // (judge() reads these for the link condition and the new faces' shape). The last three only
    // for an edge still live when they run: two thirds of the edges walked are passed over (an end
    // survived a collapse; the dragon at 10 %: 464 k walked, 145 k judged in the first pass), and
    // fetching their neighbourhoods too took the memory's bandwidth from the edges judged. The
    // dragon at 10 %: the live filter ~9 % faster, the ring stage ~10 % more.
    constexpr size_t kAhead[5] = {32, 24, 16, 8, 4};
    const size_t walkEnd = ranked.size();
    for (size_t i = 0; i <= walkEnd; ++i) {
      if (liveFaces_ <= target) break;
      if (i == walkEnd) {  // the first rank over the goal, if any
        if (stops) {
          float r;
          std::memcpy(&r, &stop, 4);
          over = std::min(over, r);
        }
        break;
      }
      const Ranked& r = ranked[i];
      if (r.priority > errorGoal) {
        over = std::min(over, r.priority);
        break;
      }
      if (i + kAhead[0] < walkEnd) __builtin_prefetch(&faces_[ranked[i + kAhead[0]].side / 3]);
      if (i + kAhead[1] < walkEnd) {
        const uint32_t side = ranked[i + kAhead[1]].side;
        const auto& ahead = faces_[side / 3];
        for (uint32_t v : {ahead[side % 3], ahead[(side % 3 + 1) % 3]}) {
          __builtin_prefetch(&vs_[v]);
          __builtin_prefetch(&start_[v]);
          __builtin_prefetch(&count_[v]);
        }
      }
      // An edge whose end already survived a collapse in this pass is passed over: nothing more.
      const auto live = [&](uint32_t x, uint32_t y) {
        return !vs_[x].dead && !vs_[y].dead && vs_[x].lastSurvive <= passStart && vs_[y].lastSurvive <= passStart;
      };
      if (i + kAhead[2] < walkEnd) {
        const uint32_t side = ranked[i + kAhead[2]].side;
        const auto& ahead = faces_[side / 3];
        const uint32_t x = ahead[side % 3], y = ahead[(side % 3 + 1) % 3];
        if (live(x, y))
          for (uint32_t v : {x, y}) {
            __builtin_prefetch(&pos_[v]);
            __builtin_prefetch(&quadric_[v]);
            __builtin_prefetch(reinterpret_cast<const char*>(&quadric_[v]) + 64);
            __builtin_prefetch(reinterpret_cast<const char*>(&quadric_[v]) + sizeof(Quadric) - 1);
            __builtin_prefetch(facesBegin(v));
          }
      }
      if (i + kAhead[3] < walkEnd) {
        const uint32_t side = ranked[i + kAhead[3]].side;
        const auto& ahead = faces_[side / 3];
        const uint32_t x = ahead[side % 3], y = ahead[(side % 3 + 1) % 3];
        if (live(x, y))
          for (uint32_t v : {x, y}) {
            const uint32_t* f = facesBegin(v);
            for (uint32_t j = 0; j < count_[v]; ++j) __builtin_prefetch(&faces_[f[j]]);
          }
      }
      if (i + kAhead[4] < walkEnd) {
        const uint32_t side = ranked[i + kAhead[4]].side;
        const auto& ahead = faces_[side / 3];
        const uint32_t x = ahead[side % 3], y = ahead[(side % 3 + 1) % 3];
        if (live(x, y))
          for (uint32_t v : {x, y}) {
            const uint32_t* f = facesBegin(v);
            for (uint32_t j = 0; j < count_[v]; ++j) {
              const auto& t = faces_[f[j]];
              for (uint32_t u : t)
                if (u != v) {
                  __builtin_prefetch(&pos_[u]);
                  __builtin_prefetch(&vs_[u]);
                }
            }
          }
      }
      const auto& t = faces_[r.side / 3];
      const uint32_t x = t[r.side % 3], y = t[(r.side % 3 + 1) % 3], a = std::min(x, y), b = std::max(x, y);
      if (vs_[a].dead || vs_[b].dead || vs_[a].lastSurvive > passStart || vs_[b].lastSurvive > passStart) continue;
      if (progress && (++checked & 0xfff) == 0 && !report()) {
        stats.stop = GroupQemStats::Stop::Cancelled;
        return handOver(false);
      }
      const Candidate c = evaluate(a, b);
      if (c.verdict != CollapseVerdict::Allowed) continue;
      if (float(c.priority) > errorGoal) {  // ranked again by the next pass
        over = std::min(over, float(c.priority));
        continue;
      }
      if (maxErrorSq >= 0 && c.error > maxErrorSq) continue;
      collapse(c);
      ++collapses;
      ++stats.collapses;
      ++stats.collapsesInPasses;
      stats.maxCollapseError = std::max(stats.maxCollapseError, std::sqrt(c.error) / diag_);
    }
    ++stats.passes;
    BigVector<Ranked>().swap(ranked);
    if (collapses == 0 && !(over < std::numeric_limits<float>::max())) return handOver(false);  // nothing allowed left
    // A weak pass (under a sixth of its goal): the queue goes on from here.
    if (facesAtStart - liveFaces_ <= faceGoal / 6) return handOver(true);
  }
  return handOver(false);
}

void GroupQemSimplifier::Compact() {
  const uint32_t nv = uint32_t(pos_.size()), nf = uint32_t(faces_.size());
  // Old index -> new, held meanwhile in the search marks (no array more at this point of the run:
  // a mark only means something inside one search, against a stamp above every mark; they are
  // left 0). Faces first renamed, then moved; vertices moved last.
  BigVector<uint32_t> ownFaceMap;
  if (faceMark_.empty()) ownFaceMap.resize(nf);
  uint32_t* faceMap = faceMark_.empty() ? ownFaceMap.data() : faceMark_.data();
  uint32_t liveVertices = 0, live = 0;
  for (uint32_t v = 0; v < nv; ++v) vs_[v].mark = vs_[v].dead ? kNone : liveVertices++;
  for (uint32_t f = 0; f < nf; ++f) faceMap[f] = faceDead_[f] ? kNone : live++;
  // The lists, packed in place in their order in refs_ (disjoint: each moves down or stays), faces
  // renamed. That order is found without a sort or a copy: a bit marks where each list starts,
  // and its first entry holds its vertex meanwhile (the entry itself waits in start_).
  std::vector<uint64_t> starts(refs_.size() / 64 + 1, 0);
  for (uint32_t v = 0; v < nv; ++v) {
    if (vs_[v].dead || count_[v] == 0) continue;
    const uint32_t s = start_[v];
    starts[s / 64] |= uint64_t(1) << (s % 64);
    start_[v] = refs_[s];
    refs_[s] = v;
  }
  uint32_t at = 0;
  for (size_t word = 0; word < starts.size(); ++word)
    for (uint64_t bits = starts[word]; bits != 0; bits &= bits - 1) {
      const uint32_t s = uint32_t(word * 64 + size_t(__builtin_ctzll(bits))), v = refs_[s], k = count_[v];
      refs_[at] = faceMap[start_[v]];
      for (uint32_t i = 1; i < k; ++i) refs_[at + i] = faceMap[refs_[s + i]];
      start_[v] = at;
      at += k;
    }
  std::vector<uint64_t>().swap(starts);
  refsBias_ += refs_.size() - at;
  refs_.resize(at);
  for (uint32_t f = 0; f < nf; ++f) {
    if (faceDead_[f]) continue;
    const uint32_t w = faceMap[f];  // <= f: read before any move writes it
    FaceRec r = faces_[f];
    for (uint32_t& v : r) v = vs_[v].mark;
    faces_[w] = r;
    faceMap[w] = 0;
    faceInput_[w] = faceInput_[f];
  }
  faces_.resize(live);
  if (!faceMark_.empty()) faceMark_.resize(live);
  BigVector<uint32_t>().swap(ownFaceMap);
  faceInput_.resize(live);
  faceDead_.assign(live, 0);
  for (uint32_t v = 0; v < nv; ++v) {
    if (vs_[v].dead) continue;
    const uint32_t w = vs_[v].mark;  // <= v
    pos_[w] = pos_[v];
    quadric_[w] = quadric_[v];
    vs_[w] = vs_[v];
    vs_[w].mark = 0;
    start_[w] = count_[v] > 0 ? start_[v] : 0;
    count_[w] = count_[v];
    vertexInput_[w] = vertexInput_[v];
  }
  pos_.resize(liveVertices);
  quadric_.resize(liveVertices);
  vs_.resize(liveVertices);
  start_.resize(liveVertices);
  count_.resize(liveVertices);
  vertexInput_.resize(liveVertices);
  // The dead part's memory goes back to the system (the capacity stays: the face lists grow into
  // refs_'s again), so that what the run holds from here on is the live part's.
  ReleaseUnusedCapacity(refs_);
  ReleaseUnusedCapacity(faces_);
  ReleaseUnusedCapacity(faceMark_);
  ReleaseUnusedCapacity(faceInput_);
  ReleaseUnusedCapacity(faceDead_);
  ReleaseUnusedCapacity(pos_);
  ReleaseUnusedCapacity(quadric_);
  ReleaseUnusedCapacity(vs_);
  ReleaseUnusedCapacity(start_);
  ReleaseUnusedCapacity(count_);
  ReleaseUnusedCapacity(vertexInput_);
}

void GroupQemSimplifier::Refresh() {
  if (!StepDue()) return;
  BuildQuadrics();
  if (attributes_)
    attributes_->Refresh(
        faces_.size(), faceCorners_, [this](uint32_t f) { return !faceDead_[f]; },
        [this](uint32_t v) { return inputPosition(pos_[v]); });
  refreshAt_ = NextStep(liveFaces_);
}

size_t GroupQemSimplifier::NextStep(size_t faces) const {
  // A step is taken only where a whole step follows it before the target (one for the last few
  // collapses would queue every edge again for little: the dragon at 50 %, ratio 0.8, 100 ms).
  const double at = double(faces) * p_.refreshRatio;
  return at * p_.refreshRatio >= double(p_.targetFaces) ? size_t(at) : 0;
}

Status GroupQemSimplifier::run(const Progress& progress, GroupQemStats& stats) {
  stats.facesIn = facesIn_;
  const size_t target = p_.targetFaces;
  const double maxErrorSq = p_.maxError > 0 ? (p_.maxError * diag_) * (p_.maxError * diag_) : -1;
  stats.stop = GroupQemStats::Stop::NoMoreCollapses;
  if (p_.refreshRatio > 0) refreshAt_ = NextStep(liveFaces_);
  // (the queue alone runs even at the target, as it always did: its first progress report may cancel)
  if (!passes_ || CollapseInPasses(progress, target, maxErrorSq, stats)) {
    // The passes leave most of the arrays dead: the queue works on the live part, packed.
    if (passes_ && compactable() && liveFaces_ < faces_.size()) Compact();
    CollapseInQueue(progress, target, maxErrorSq, stats);
  }
  return finish(progress, target, maxErrorSq, stats);
}

void GroupQemSimplifier::CollapseInQueue(const Progress& progress, size_t target, double maxErrorSq,
                                         GroupQemStats& stats) {
  // Every live edge once, from its lower endpoint, at its lower bound (after passes: from the
  // state they reached, every vertex's collapses queued again).
  heap_.reserve(facesIn_ * 2);
  const uint32_t nv = uint32_t(pos_.size());
  const size_t toRemove = stats.facesIn > target ? stats.facesIn - target : 1;
  for (bool step = true; step;) {
    step = false;
    Refresh();
    for (uint32_t v = 0; v < nv; ++v) {
      vs_[v].dropped = 0;
      ++stamp_;
      for (const uint32_t* f = facesBegin(v); f != facesEnd(v); ++f)
        for (uint32_t u : faces_[*f])
          if (u > v && vs_[u].mark != stamp_) {
            vs_[u].mark = stamp_;
            if (frozen(v) || frozen(u)) continue;
            heap_.append({lowerBound(v, u), v, u, epoch_ | kLazy});
          }
      // (after passes the bar stays where they left it)
      if (progress && (v & 0xffff) == 0 &&
          !progress(stats.collapses > 0
                        ? 5 + int(93.0 * std::min(1.0, double(stats.facesIn - liveFaces_) / double(toRemove)))
                        : int(5.0 * v / nv),
                    "Group-preserving QEM: queueing edges")) {
        stats.stop = GroupQemStats::Stop::Cancelled;
        return;
      }
    }
    heap_.heapify();

    size_t nextReport = 0;
    // Superseded entries (an endpoint survived a collapse since: most of those pushed) are dropped
    // in one sequential sweep whenever the heap has grown by a quarter since the last sweep: a
    // sweep costs a few nanoseconds per entry, popping one a walk from the root to a leaf, with a
    // cache miss at each deep level (the dragon at 10 %: 3.3 M pops -> 1.2 M).
    size_t compactFloor = heap_.size() + heap_.size() / 4 + 1024;
    while (!heap_.empty()) {
      if (liveFaces_ <= target) break;
      if (StepDue()) {  // a memoryless step: every edge queued again
        heap_.clear();
        step = true;
        break;
      }
      const size_t done = stats.facesIn - liveFaces_;
      if (progress && done >= nextReport) {
        if (!progress(5 + int(93.0 * std::min(1.0, double(done) / double(toRemove))),
                      "Group-preserving QEM: collapsing")) {
          stats.stop = GroupQemStats::Stop::Cancelled;
          break;
        }
        nextReport = done + std::max<size_t>(toRemove / 100, 1);
      }
      const HeapEntry top = heap_.pop();
      if (!heap_.empty()) PrefetchVertices(heap_.top().a, heap_.top().b);  // most often the next one judged
      const uint32_t a = top.a, b = top.b, kind = top.tag & kKindMask, ep = top.tag & kEpochMask;
      if (vs_[a].dead || vs_[b].dead || ep < vs_[a].lastSurvive || ep < vs_[b].lastSurvive) continue;  // superseded
      const bool fresh = ep >= vs_[a].touched && ep >= vs_[b].touched;
      Candidate c;
      if (fresh && kind == kJudged && !((vs_[a].info.flags | vs_[b].info.flags) & kNonManifold)) {
        // nothing changed since it was judged: only place it again
        // (and, in integrity mode, search again: a path found around the edge inside its group
        // may have been cut since by a collapse elsewhere that this edge's faces kept whole)
        if (integrity_ && !keepsGroupsWhole(a, b)) {
          ++stats_.refusedCondition1;
          vs_[a].dropped = vs_[b].dropped = 1;
          continue;
        }
        c.verdict = CollapseVerdict::Allowed;
        place(a, b, true, c);
        if (attributes_ && (attributes_->seam(a) || attributes_->seam(b)) && !placeAtSeam(a, b, c)) {
          vs_[a].dropped = vs_[b].dropped = 1;
          continue;
        }
      } else {
        c = evaluate(a, b);
        if (c.verdict == CollapseVerdict::NotAnEdge) continue;
        if (c.verdict != CollapseVerdict::Allowed) {  // queued again if a's or b's neighbourhood changes
          vs_[a].dropped = vs_[b].dropped = 1;
          continue;
        }
        // Costs change as the neighbourhood does: re-queue a collapse dearer than the next one.
        if (!heap_.empty() && float(c.priority) > heap_.top().priority) {
          heap_.push({ToFloat(c.priority), a, b, epoch_ | kJudged});
          continue;
        }
      }
      if (maxErrorSq >= 0 && c.error > maxErrorSq) {
        vs_[a].dropped = vs_[b].dropped = 1;
        continue;
      }
      // GroupQemRegion::separation, checked here rather than in judge(): only for the collapses
      // about to be made (the dragon's LOD build: 10 % of its CPU time in judge(), 2-3 % here).
      if (separationSq_ > 0 && !keepsApart(a, b, c.position)) {
        vs_[a].dropped = vs_[b].dropped = 1;
        continue;
      }
      collapse(c);
      ++stats.collapses;
      stats.maxCollapseError = std::max(stats.maxCollapseError, std::sqrt(c.error) / diag_);
      if (heap_.size() > compactFloor) {
        heap_.RemoveIf([&](const HeapEntry& h) {
          const uint32_t e = h.tag & kEpochMask;
          return vs_[h.a].dead || vs_[h.b].dead || e < vs_[h.a].lastSurvive || e < vs_[h.b].lastSurvive;
        });
        compactFloor = heap_.size() + heap_.size() / 4 + 1024;
      }
    }
  }
}

Status GroupQemSimplifier::finish(const Progress& progress, size_t target, double maxErrorSq, GroupQemStats& stats) {
  if (stats.stop != GroupQemStats::Stop::Cancelled && liveFaces_ > target && target > 0) {
    RemoveComponents(target, stats);
    if (liveFaces_ > target) UnblockByFlips(progress, target, maxErrorSq, stats);
    if (liveFaces_ > target && stats.stop != GroupQemStats::Stop::Cancelled) TallyFloor(maxErrorSq, stats);
  }
  if (liveFaces_ <= target && stats.stop != GroupQemStats::Stop::Cancelled)
    stats.stop = GroupQemStats::Stop::TargetReached;
  stats.facesOut = liveFaces_;
  stats.evaluations = stats_.evaluations;
  stats.refusedTopology = stats_.refusedTopology;
  stats.refusedLock = stats_.refusedLock;
  stats.refusedCondition1 = stats_.refusedCondition1;
  stats.refusedCondition2 = stats_.refusedCondition2;
  stats.refusedFixed = stats_.refusedFixed;
  stats.refusedGeometry = stats_.refusedGeometry;
  stats.refusedCone = stats_.refusedCone;
  return stats.stop == GroupQemStats::Stop::Cancelled ? Status::Cancelled() : Status::Ok();
}

void GroupQemSimplifier::RemoveComponents(size_t target, GroupQemStats& stats) {
  // Components (faces joined through vertices) of the live faces: union-find on vertices.
  const uint32_t nv = uint32_t(pos_.size()), nf = uint32_t(faces_.size());
  std::vector<uint32_t> parent(nv);
  for (uint32_t v = 0; v < nv; ++v) parent[v] = v;
  const auto root = [&](uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (uint32_t f = 0; f < nf; ++f) {
    if (faceDead_[f]) continue;
    for (int j = 1; j < 3; ++j) {
      const uint32_t r0 = root(faces_[f][0]), r = root(faces_[f][size_t(j)]);
      if (r != r0) parent[std::max(r, r0)] = std::min(r, r0);
    }
  }
  struct Component {
    uint32_t faces = 0;
    bool removable = true;
    vcg::Box3<double> box;
  };
  std::vector<uint32_t> compOf(nv, kNone);
  std::vector<Component> comps;
  for (uint32_t v = 0; v < nv; ++v) {
    if (vs_[v].dead || count_[v] == 0) continue;
    const uint32_t r = root(v);
    if (compOf[r] == kNone) {
      compOf[r] = uint32_t(comps.size());
      comps.emplace_back();
    }
    compOf[v] = compOf[r];
    Component& c = comps[compOf[v]];
    c.box.Add(pos_[v]);
    if (frozen(v)) c.removable = false;  // joined to another part of the mesh
  }
  if (comps.size() <= 1) return;  // never remove the whole mesh
  // A component may go when every group of every grouping that it touches lies inside it.
  std::vector<uint32_t> compOfGroup;
  for (size_t l = 0; l < groupFaces_.size(); ++l) {
    compOfGroup.assign(groupFaces_[l].size(), kNone);
    for (uint32_t f = 0; f < nf; ++f) {
      if (faceDead_[f]) continue;
      const uint32_t c = compOf[faces_[f][0]];
      uint32_t& owner = compOfGroup[size_t(groupIn(int(l) - 1, f))];
      if (owner == kNone)
        owner = c;
      else if (owner != c)
        owner = kNone - 1;  // in two components
    }
    for (uint32_t f = 0; f < nf; ++f)
      if (!faceDead_[f] && compOfGroup[size_t(groupIn(int(l) - 1, f))] != compOf[faces_[f][0]])
        comps[compOf[faces_[f][0]]].removable = false;
  }
  for (uint32_t f = 0; f < nf; ++f)
    if (!faceDead_[f]) ++comps[compOf[faces_[f][0]]].faces;
  std::vector<uint32_t> order;
  for (uint32_t c = 0; c < comps.size(); ++c)
    if (comps[c].removable) order.push_back(c);
  // Smallest first: by extent, then by faces; and never all of them.
  std::sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) {
    const double dx = comps[x].box.Diag(), dy = comps[y].box.Diag();
    return dx != dy ? dx < dy : (comps[x].faces != comps[y].faces ? comps[x].faces < comps[y].faces : x < y);
  });
  if (order.size() == comps.size()) order.pop_back();
  stats.componentsRemovable = order.size();
  if (!p_.removeComponents) return;
  // Smallest first, passing over one that would land below the target while others may still
  // land on it; if none does, the one that lands closest.
  std::vector<char> removeComp(comps.size(), 0);
  size_t excess = liveFaces_ - target;
  uint32_t closest = kNone;
  for (uint32_t c : order) {
    if (excess == 0) break;
    if (comps[c].faces > excess) {
      if (closest == kNone || comps[c].faces < comps[closest].faces) closest = c;
      continue;
    }
    removeComp[c] = 1;
    excess -= comps[c].faces;
  }
  if (excess > 0 && closest != kNone) {
    // Below the target by `over`: take back removed ones that fit in it, largest first.
    removeComp[closest] = 1;
    size_t over = comps[closest].faces - excess;
    for (size_t i = order.size(); i-- > 0 && over > 0;) {
      const uint32_t c = order[i];
      if (c != closest && removeComp[c] && comps[c].faces <= over) {
        removeComp[c] = 0;
        over -= comps[c].faces;
      }
    }
  }
  for (uint32_t c : order)
    if (removeComp[c]) {
      ++stats.componentsRemoved;
      --stats.componentsRemovable;
    }
  std::vector<char> groupGone(size_t(primaryGroups_), 0);
  for (uint32_t f = 0; f < nf; ++f) {
    if (faceDead_[f] || !removeComp[compOf[faces_[f][0]]]) continue;
    faceDead_[f] = 1;
    const bool flat = UsesAVertexTwice(faces_[f]);
    liveFaces_ -= !flat;
    ++stats.facesRemovedWithComponents;
    for (size_t l = 0; l < groupFaces_.size() && !flat; ++l) --groupFaces_[l][size_t(groupIn(int(l) - 1, f))];
    if (!groupGone[size_t(faces_[f].group)]) {
      groupGone[size_t(faces_[f].group)] = 1;
      ++stats.groupsRemoved;
    }
  }
  for (uint32_t v = 0; v < nv; ++v)
    if (compOf[v] != kNone && removeComp[compOf[v]]) {
      vs_[v].dead = 1;
      count_[v] = 0;
    }
}

void GroupQemSimplifier::SetFace(uint32_t f, const std::array<uint32_t, 3>& t) {
  const std::array<uint32_t, 3> old = faces_[f];
  static_cast<std::array<uint32_t, 3>&>(faces_[f]) = t;
  for (uint32_t v : old)
    if (!Contains(t, v)) {
      uint32_t* vb = refs_.data() + start_[v];
      for (uint32_t i = 0; i < count_[v]; ++i)
        if (vb[i] == f) {
          vb[i] = vb[--count_[v]];
          break;
        }
    }
  for (uint32_t v : t)
    if (!Contains(old, v)) {
      if (!listRoom(count_[v] + 1)) {
        BuildFaceLists();  // from faces_, which already hold t
        return;
      }
      // v's list moves to the end of refs_, with f.
      const uint32_t begin = uint32_t(refs_.size()), s = start_[v], n = count_[v];
      for (uint32_t i = 0; i < n; ++i) refs_.push_back(refs_[s + i]);
      refs_.push_back(f);
      start_[v] = begin;
      count_[v] = n + 1;
    }
}

double GroupQemSimplifier::FlipEdge(uint32_t u, uint32_t w, bool apply) {
  uint32_t f[2] = {kNone, kNone}, n = 0;
  for (const uint32_t* g = facesBegin(u); g != facesEnd(u); ++g)
    if (Contains(faces_[*g], w)) {
      if (n < 2) f[n] = *g;
      ++n;
    }
  if (n != 2) return -1;
  // f[0] = (u, w, p) and f[1] = (w, u, q) in this orientation.
  const auto follows = [](const std::array<uint32_t, 3>& t, uint32_t x, uint32_t y) {
    return (t[0] == x && t[1] == y) || (t[1] == x && t[2] == y) || (t[2] == x && t[0] == y);
  };
  if (!follows(faces_[f[0]], u, w)) std::swap(f[0], f[1]);
  if (!follows(faces_[f[0]], u, w) || !follows(faces_[f[1]], w, u)) return -1;  // inconsistent orientation
  const uint32_t p = Third(faces_[f[0]], u, w), q = Third(faces_[f[1]], u, w);
  if (p == q || p == u || p == w || q == u || q == w) return -1;
  for (const uint32_t* g = facesBegin(p); g != facesEnd(p); ++g)
    if (Contains(faces_[*g], q)) return -1;  // the new edge exists
  if (integrity_)
    for (int layer = -1; layer < int(coarserDense_.size()); ++layer)
      if (groupIn(layer, f[0]) != groupIn(layer, f[1])) return -1;
  // No fold: each new normal within acos(kMinNormalCos) of the two faces' (area-weighted) mean
  // normal; no zero-area face.
  const Point3d &pu = pos_[u], &pw = pos_[w], &pp = pos_[p], &pq = pos_[q];
  const Point3d mean = ((pw - pu) ^ (pp - pu)) + ((pu - pw) ^ (pq - pw));
  const double meanSq = mean.SquaredNorm();
  if (!(meanSq > 0)) return -1;
  const Point3d m[2] = {(pq - pu) ^ (pp - pu), (pp - pw) ^ (pq - pw)};
  const std::array<uint32_t, 3> t[2] = {{u, q, p}, {w, p, q}};
  double least = 1;
  for (int i = 0; i < 2; ++i) {
    const double lenSq = m[i].SquaredNorm();
    const auto& c = t[i];
    const double longestSq = std::max({(pos_[c[1]] - pos_[c[0]]).SquaredNorm(), (pos_[c[2]] - pos_[c[1]]).SquaredNorm(),
                                       (pos_[c[0]] - pos_[c[2]]).SquaredNorm()});
    if (!(longestSq > 0) || lenSq / (longestSq * longestSq) < kDegenerateQuality * kDegenerateQuality) return -1;
    const double cosine = (m[i] * mean) / std::sqrt(lenSq * meanSq);
    if (!(cosine >= kMinNormalCos)) return -1;
    least = std::min(least, cosine);
    if (p_.keepCones && !insideCones(f[i], m[i], lenSq)) return -1;
  }
  if (!apply) return least;
  undo_.push_back({f[0], faces_[f[0]]});
  undo_.push_back({f[1], faces_[f[1]]});
  SetFace(f[0], t[0]);
  SetFace(f[1], t[1]);
  ++epoch_;
  for (uint32_t v : {u, w, p, q}) {
    AnalyzeVertex(v);
    vs_[v].touched = epoch_;
  }
  return least;
}

bool GroupQemSimplifier::TryUnblock(uint32_t a, uint32_t b, double maxErrorSq, GroupQemStats& stats) {
  // The common neighbours of a and b that are not opposite the edge.
  opposite_.clear();
  for (const uint32_t* f = facesBegin(a); f != facesEnd(a); ++f)
    if (Contains(faces_[*f], b)) opposite_.push_back(Third(faces_[*f], a, b));
  if (opposite_.empty()) return false;
  ++stamp_;
  for (const uint32_t* f = facesBegin(a); f != facesEnd(a); ++f)
    for (uint32_t u : faces_[*f]) vs_[u].mark = stamp_;
  std::vector<uint32_t> extra;  // (rare: only at a floor)
  for (const uint32_t* f = facesBegin(b); f != facesEnd(b); ++f)
    for (uint32_t u : faces_[*f])
      if (u != a && u != b && vs_[u].mark == stamp_ &&
          std::find(opposite_.begin(), opposite_.end(), u) == opposite_.end() &&
          std::find(extra.begin(), extra.end(), u) == extra.end())
        extra.push_back(u);
  if (extra.empty() || extra.size() > 2) return false;
  undo_.clear();
  bool flipped = true;
  for (uint32_t x : extra) {
    // The flatter of the two flips that part x from a or from b.
    const double viaA = FlipEdge(a, x, false), viaB = FlipEdge(b, x, false);
    if (viaA < 0 && viaB < 0) {
      flipped = false;
      break;
    }
    if (viaA >= viaB)
      FlipEdge(a, x, true);
    else
      FlipEdge(b, x, true);
  }
  if (flipped) {
    const Candidate c = judge(a, b);
    if (c.verdict == CollapseVerdict::Allowed && !(maxErrorSq >= 0 && c.error > maxErrorSq)) {
      stats.edgeFlips += undo_.size() / 2;
      ++stats.collapsesUnblocked;
      collapse(c);
      ++stats.collapses;
      stats.maxCollapseError = std::max(stats.maxCollapseError, std::sqrt(c.error) / diag_);
      undo_.clear();
      return true;
    }
  }
  // Undo, last flip first.
  ++epoch_;
  for (size_t i = undo_.size(); i-- > 0;) {
    const std::array<uint32_t, 3> now = faces_[undo_[i].first];
    SetFace(undo_[i].first, undo_[i].second);
    for (uint32_t v : now) {
      AnalyzeVertex(v);
      vs_[v].touched = epoch_;
    }
    for (uint32_t v : undo_[i].second) AnalyzeVertex(v);
  }
  undo_.clear();
  return false;
}

void GroupQemSimplifier::UnblockByFlips(const Progress& progress, size_t target, double maxErrorSq,
                                        GroupQemStats& stats) {
  if (!p_.flipToUnblock || p_.mode != GroupMode::Integrity || attributes_ || frozen_) return;
  struct Blocked {
    float rank;
    uint32_t a, b;
  };
  std::vector<Blocked> blocked;
  const uint32_t nv = uint32_t(pos_.size());
  while (liveFaces_ > target) {
    // Every live edge refused on topology, cheapest first.
    blocked.clear();
    for (uint32_t v = 0; v < nv; ++v) {
      if (vs_[v].dead || count_[v] == 0) continue;
      for (uint32_t u : NeighboursAbove(v))
        if (judge(v, u).verdict == CollapseVerdict::Topology) blocked.push_back({lowerBound(v, u), v, u});
    }
    std::stable_sort(blocked.begin(), blocked.end(),
                     [](const Blocked& x, const Blocked& y) { return x.rank < y.rank; });
    size_t unblocked = 0;
    for (const Blocked& e : blocked) {
      if (liveFaces_ <= target) break;
      if (vs_[e.a].dead || vs_[e.b].dead) continue;
      unblocked += TryUnblock(e.a, e.b, maxErrorSq, stats);
    }
    if (unblocked == 0) return;
    if (progress && !progress(98, "Group-preserving QEM: unblocking by edge flips")) {
      stats.stop = GroupQemStats::Stop::Cancelled;
      return;
    }
    CollapseInQueue(progress, target, maxErrorSq, stats);  // the collapses the flips freed, and theirs
    if (stats.stop == GroupQemStats::Stop::Cancelled) return;
  }
}

const std::vector<uint32_t>& GroupQemSimplifier::NeighboursAbove(uint32_t v) {
  ++stamp_;
  ringScratch_.clear();
  for (const uint32_t* f = facesBegin(v); f != facesEnd(v); ++f)
    for (uint32_t u : faces_[*f])
      if (u > v && vs_[u].mark != stamp_) {
        vs_[u].mark = stamp_;
        ringScratch_.push_back(u);
      }
  return ringScratch_;
}

void GroupQemSimplifier::TallyFloor(double maxErrorSq, GroupQemStats& stats) {
  const uint32_t nv = uint32_t(pos_.size());
  for (uint32_t v = 0; v < nv; ++v) {
    if (vs_[v].dead) continue;
    for (uint32_t u : NeighboursAbove(v)) {
      const Candidate c = judge(v, u);
      ++stats.edgesLeft;
      if (c.verdict == CollapseVerdict::Allowed && maxErrorSq >= 0 && c.error > maxErrorSq)
        ++stats.edgesOverMaxError;
      else
        ++stats.edgesLeftBy[int(c.verdict)];
    }
  }
}

void GroupQemSimplifier::ReleaseLoop() {
  heap_.release();
  std::vector<uint32_t>().swap(refs_);
  std::vector<uint32_t>().swap(start_);
  std::vector<uint32_t>().swap(count_);
  std::vector<Quadric>().swap(quadric_);
  std::vector<uint32_t>().swap(faceMark_);
}

void GroupQemSimplifier::output(GroupQemResult& out) const {
  out.mesh.positions.clear();
  out.mesh.faces.clear();
  out.sourceFace.clear();
  out.sourceVertex.clear();
  if (attributes_) attributes_->RestoreInputOrder();  // Evaluate reads the input's numbering
  // In the input's order: internal index of each input vertex and face.
  // (kNone: left the arrays in Compact())
  const auto inverse = [](const std::vector<uint32_t>& input, size_t internalCount, size_t n) {
    std::vector<uint32_t> of(n, kNone);
    for (uint32_t i = 0; i < internalCount; ++i) of[input.empty() ? i : input[i]] = i;
    return of;
  };
  std::vector<uint32_t> remap(pos_.size(), kNone);
  {
    const std::vector<uint32_t> internal = inverse(vertexInput_, pos_.size(), verticesIn_);
    for (uint32_t v = 0; v < verticesIn_; ++v) {
      const uint32_t i = internal[v];
      if (i == kNone || vs_[i].dead) continue;
      remap[i] = uint32_t(out.mesh.positions.size());
      const Point3d p = inputPosition(pos_[i]);
      out.mesh.positions.emplace_back(float(p[0]), float(p[1]), float(p[2]));
      out.sourceVertex.push_back(v);
    }
  }
  out.mesh.faces.reserve(liveFaces_);
  out.sourceFace.reserve(liveFaces_);
  const std::vector<uint32_t> internal = inverse(faceInput_, faces_.size(), facesIn_);
  for (uint32_t f = 0; f < facesIn_; ++f) {
    const uint32_t i = internal[f];
    if (i == kNone || faceDead_[i]) continue;
    const auto& t = faces_[i];
    if (UsesAVertexTwice(t)) continue;  // no surface; MeshLab's filters assume there is no such face
    out.mesh.faces.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
    out.sourceFace.push_back(f);
  }
}

Status CheckInput(const IndexedMesh& mesh, const std::vector<int>& faceGroup,
                  const std::vector<const std::vector<int>*>& coarser) {
  Status s = RequireValidForFaces(mesh);
  if (!s.ok()) return s;
  if (faceGroup.size() != mesh.faces.size())
    return Status::Invalid("the group ids are " + std::to_string(faceGroup.size()) + " for " +
                           std::to_string(mesh.faces.size()) + " faces");
  for (int g : faceGroup)
    if (g < 0) return Status::Invalid("group ids must be >= 0 (found " + std::to_string(g) + ")");
  for (const auto* layer : coarser)
    if (!layer || layer->size() != mesh.faces.size())
      return Status::Invalid("a coarser grouping does not have one id per face");
  if (mesh.faces.size() >= size_t(kEpochMask) / 2)
    return Status::Invalid("the mesh has too many faces for this simplifier (2^29 at most)");
  return Status::Ok();
}

}  // namespace

GroupQemParams OneTargetParams(size_t targetFaces) {
  GroupQemParams p;
  p.targetFaces = targetFaces;
  p.passes = true;
  p.refreshRatio = kRefreshRatio;
  p.removeComponents = true;
  p.flipToUnblock = true;
  return p;
}

Status ValidateParams(const GroupQemParams& p) {
  if (p.targetFaces == 0 && !(p.maxError > 0))
    return Status::Invalid("give a target: TargetFaceNum/TargetPerc (a face count) or a maximum error");
  if (!(p.maxError >= 0) || !std::isfinite(p.maxError)) return Status::Invalid("the maximum error must be >= 0");
  if (!(p.qualityThr >= 0 && p.qualityThr <= 1)) return Status::Invalid("QualityThr must be between 0 and 1");
  if (!(p.refreshRatio >= 0 && p.refreshRatio < 1))
    return Status::Invalid("the refresh ratio must be at least 0 and under 1 (0: the input's quadrics throughout)");
  if (!(p.boundaryWeight >= 0) || !std::isfinite(p.boundaryWeight))
    return Status::Invalid("BoundaryWeight must be >= 0");
  return Status::Ok();
}

const char* ToString(GroupMode m) { return m == GroupMode::Paper ? "paper" : "integrity"; }

std::string DescribeFloor(const GroupQemStats& s, const GroupQemParams& p) {
  if (s.stop != GroupQemStats::Stop::NoMoreCollapses || p.targetFaces == 0 || s.facesOut <= p.targetFaces) return "";
  std::string why = "stopped at " + std::to_string(s.facesOut) + " faces for a target of " +
                    std::to_string(p.targetFaces) + ": no allowed collapse left; of the " +
                    std::to_string(s.edgesLeft) + " edges left, ";
  const auto n = [&](CollapseVerdict v) { return s.edgesLeftBy[int(v)]; };
  struct Reason {
    size_t count;
    const char* text;
  };
  const Reason reasons[] = {
      {n(CollapseVerdict::Topology),
       "would make an edge non-manifold, pinch the surface or move a non-manifold "
       "junction (topology)"},
      {n(CollapseVerdict::Condition1), p.mode == GroupMode::Paper ? "would break condition 1 (split or remove a group)"
                                                                  : "would split or remove a group"},
      {n(CollapseVerdict::Condition2), "would break condition 2 (a new vertex where 3+ groups meet)"},
      {n(CollapseVerdict::LockedBoundary), "would move a locked group boundary"},
      {n(CollapseVerdict::FixedEndpoints), "join two vertices that must both stay"},
      {n(CollapseVerdict::Geometry), "would flip a face or make one of zero area"},
      {n(CollapseVerdict::Cone), "would widen a normal cone past its bound (keep cones)"},
      {s.edgesOverMaxError, "exceed the maximum error"},
  };
  bool first = true;
  for (const Reason& r : reasons) {
    if (r.count == 0) continue;
    why += (first ? "" : ", ") + std::to_string(r.count) + " " + r.text;
    first = false;
  }
  if (first) why += "none is left";
  if (s.componentsRemovable > 0)
    why += "; " + std::to_string(s.componentsRemovable) + " component(s) made of whole groups could be removed" +
           (p.removeComponents ? "" : " (component removal is off: keep components)");
  return why;
}

const char* ToString(GroupQemStats::Stop s) {
  switch (s) {
    case GroupQemStats::Stop::TargetReached:
      return "target reached";
    case GroupQemStats::Stop::NoMoreCollapses:
      return "no allowed collapse left";
    case GroupQemStats::Stop::Cancelled:
      return "cancelled";
  }
  return "?";
}

const char* ToString(CollapseVerdict v) {
  switch (v) {
    case CollapseVerdict::Allowed:
      return "allowed";
    case CollapseVerdict::NotAnEdge:
      return "not an edge";
    case CollapseVerdict::Topology:
      return "topology";
    case CollapseVerdict::LockedBoundary:
      return "locked group boundary";
    case CollapseVerdict::Condition1:
      return "condition 1";
    case CollapseVerdict::Condition2:
      return "condition 2";
    case CollapseVerdict::FixedEndpoints:
      return "both endpoints fixed";
    case CollapseVerdict::Geometry:
      return "geometry";
    case CollapseVerdict::Cone:
      return "normal cone";
  }
  return "?";
}

namespace {

// Both forms of SimplifyPreservingGroups; `owned`: the input, freed once init() has copied it.
Status Simplify(const IndexedMesh& mesh, IndexedMesh* owned, const std::vector<int>& faceGroup,
                const GroupQemParams& params, GroupQemResult& out, const Progress& progress,
                const std::vector<const std::vector<int>*>& coarserGroups, const GroupQemRegion* region,
                AttributeQuadrics* attributes) {
  out = GroupQemResult();
  Status s = ValidateParams(params);
  if (!s.ok()) return s;
  s = CheckInput(mesh, faceGroup, coarserGroups);
  if (!s.ok()) return s;
  if (region && !region->frozenVertex.empty() && region->frozenVertex.size() != mesh.positions.size())
    return Status::Invalid("the frozen-vertex flags are " + std::to_string(region->frozenVertex.size()) + " for " +
                           std::to_string(mesh.positions.size()) + " vertices");
  if (region && !(region->diagonal >= 0 && std::isfinite(region->diagonal)))
    return Status::Invalid("the region's diagonal must be finite and >= 0");
  if (region && !(region->separation >= 0 && std::isfinite(region->separation)))
    return Status::Invalid("the region's separation must be finite and >= 0");
  GroupQemSimplifier simplifier(mesh, faceGroup, coarserGroups, params, region, attributes, true);
  simplifier.init(owned);
  s = simplifier.run(progress, out.stats);
  simplifier.ReleaseLoop();
  if (s.ok() || s.code == Status::Code::Cancelled) {
    simplifier.output(out);
  }
  if (s.ok() && progress) progress(100, "Group-preserving QEM: done");
  return s;
}

}  // namespace

Status SimplifyPreservingGroups(const IndexedMesh& mesh, const std::vector<int>& faceGroup,
                                const GroupQemParams& params, GroupQemResult& out, const Progress& progress,
                                const std::vector<const std::vector<int>*>& coarserGroups, const GroupQemRegion* region,
                                AttributeQuadrics* attributes) {
  return Simplify(mesh, nullptr, faceGroup, params, out, progress, coarserGroups, region, attributes);
}

Status SimplifyPreservingGroups(IndexedMesh&& mesh, const std::vector<int>& faceGroup, const GroupQemParams& params,
                                GroupQemResult& out, const Progress& progress) {
  IndexedMesh owned = std::move(mesh);
  mesh = IndexedMesh();
  return Simplify(owned, &owned, faceGroup, params, out, progress, {}, nullptr, nullptr);
}

CollapseVerdict EvaluateCollapse(const IndexedMesh& mesh, const std::vector<int>& faceGroup,
                                 const GroupQemParams& params, uint32_t v1, uint32_t v2, vcg::Point3f* newPosition) {
  const std::vector<const std::vector<int>*> none;
  if (!CheckInput(mesh, faceGroup, none).ok() || v1 >= mesh.positions.size() || v2 >= mesh.positions.size())
    return CollapseVerdict::NotAnEdge;
  GroupQemSimplifier simplifier(mesh, faceGroup, none, params);
  simplifier.init();
  const Candidate c = simplifier.evaluate(v1, v2);
  if (newPosition && c.verdict == CollapseVerdict::Allowed) {
    const Point3d p = simplifier.inputPosition(c.position);
    *newPosition = vcg::Point3f(float(p[0]), float(p[1]), float(p[2]));
  }
  return c.verdict;
}

}  // namespace conelod
