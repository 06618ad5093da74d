// ConeLOD — hierarchical face grouping by an evaluation function (see cone_grouping.h).
//
// Implementation notes. The greedy loop keeps, for every live unit, its best partner and that
// pair's score; an indexed max-heap over units (not over pairs) gives the global best pair. A
// merge only changes pairs that involve the merged unit, so only its neighbours are revisited:
// a neighbour whose best partner was one of the merged units rescans its own neighbours, the
// others compare their pair with the new unit against their best. Neighbour lists live in one
// append-only arena (no allocation per unit), compacted when it grows past a few times the live
// size.
#include "conelod/cone_grouping.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>

#include "conelod/mesh_check.h"

namespace conelod {

namespace {

constexpr double kPi = NormalCone::kPi;
constexpr double kDeg = kPi / 180.0;

struct Sphere {
  vcg::Point3d c;
  double r = 0;
};

Sphere UnionSphere(const Sphere& a, const Sphere& b) {
  const vcg::Point3d d = b.c - a.c;
  const double dist = d.Norm();
  if (dist + b.r <= a.r) return a;
  if (dist + a.r <= b.r) return b;
  Sphere s;
  s.r = 0.5 * (dist + a.r + b.r);
  s.c = a.c + d * ((s.r - a.r) / dist);
  return s;
}

// The smallest sphere around a triangle: the circumsphere if acute, else the longest edge's.
Sphere TriangleSphere(const vcg::Point3d& a, const vcg::Point3d& b, const vcg::Point3d& c) {
  const vcg::Point3d ab = b - a, ac = c - a, bc = c - b;
  const double lab = ab.SquaredNorm(), lac = ac.SquaredNorm(), lbc = bc.SquaredNorm();
  Sphere s;
  auto edgeSphere = [&](const vcg::Point3d& p, const vcg::Point3d& q, double l2) {
    s.c = (p + q) * 0.5;
    s.r = 0.5 * std::sqrt(l2);
  };
  if (ab * ac <= 0) { edgeSphere(b, c, lbc); return s; }           // obtuse or right at a
  if ((a - b) * bc <= 0) { edgeSphere(a, c, lac); return s; }      // at b
  if ((a - c) * (b - c) <= 0) { edgeSphere(a, b, lab); return s; } // at c
  const vcg::Point3d n = ab ^ ac;
  const double n2 = n.SquaredNorm();
  if (n2 <= 0) { edgeSphere(b, c, lbc); return s; }
  const vcg::Point3d off = ((n ^ ab) * lac + (ac ^ n) * lab) / (2 * n2);
  s.c = a + off;
  s.r = std::max({Distance(s.c, a), Distance(s.c, b), Distance(s.c, c)});
  return s;
}

// One unit of the greedy merge (a face at level 1, a group above): the data every candidate
// evaluation reads, packed in one cache line.
struct alignas(64) Unit {
  vcg::Point3d axis;     // cone axis (unit)
  double half;           // cone half-angle: < 0 empty, >= pi/2 cannot be culled
  float vecArea[3];      // sum of area * unit normal
  float center[3];       // bounding sphere
  float radius;
  int faceCount;

  NormalCone cone() const { NormalCone c; c.axis = axis; c.halfAngle = half; return c; }
  void setCone(const NormalCone& c) { axis = c.axis; half = c.halfAngle; }
  Sphere sphere() const {
    Sphere s; s.c = vcg::Point3d(center[0], center[1], center[2]); s.r = radius; return s;
  }
  void setSphere(const Sphere& s) {
    double magnitude = 0;
    for (int k = 0; k < 3; ++k) {
      center[k] = float(s.c[k]);
      magnitude = std::max(magnitude, std::abs(s.c[k]));
    }
    // Rounding the centre and radius to float must not let a vertex out: pad by a few float
    // ulps of the coordinates.
    radius = float(s.r * (1 + 1e-6) + 1e-6 * magnitude);
  }
};

// Data touched only when a unit merges.
struct UnitFaces {
  int exactSize = 0;         // faceCount when the cone was last computed exactly
  int head = -1, tail = -1;  // the unit's faces, a list through faceNext_
};

// A neighbour in a unit's adjacency list, with the score of the pair (-inf: not mergeable).
// Lists are kept resolved: they only ever name live units.
struct Neighbour {
  int id;
  float score;
};

constexpr float kNoPair = -std::numeric_limits<float>::infinity();

// Indexed binary max-heap of units keyed by the score of their best pair.
class UnitHeap {
 public:
  void reset(size_t n) { heap_.clear(); pos_.assign(n, -1); }
  bool empty() const { return heap_.empty(); }
  int top() const { return heap_[0].unit; }
  void set(int u, float key) {
    int i = pos_[size_t(u)];
    if (i < 0) {
      i = int(heap_.size());
      heap_.push_back({key, u});
      pos_[size_t(u)] = i;
      up(size_t(i));
      return;
    }
    const float old = heap_[size_t(i)].key;
    heap_[size_t(i)].key = key;
    if (key > old) up(size_t(i));
    else down(size_t(i));
  }
  void remove(int u) {
    const int i = pos_[size_t(u)];
    if (i < 0) return;
    pos_[size_t(u)] = -1;
    const Entry last = heap_.back();
    heap_.pop_back();
    if (last.unit == u) return;
    heap_[size_t(i)] = last;
    pos_[size_t(last.unit)] = i;
    up(size_t(i));
    down(size_t(pos_[size_t(last.unit)]));
  }

 private:
  struct Entry {
    float key;
    int unit;
  };
  static bool better(const Entry& a, const Entry& b) {
    return a.key > b.key || (a.key == b.key && a.unit < b.unit);  // deterministic ties
  }
  void up(size_t i) {
    const Entry e = heap_[i];
    while (i > 0) {
      const size_t p = (i - 1) / 2;
      if (!better(e, heap_[p])) break;
      heap_[i] = heap_[p];
      pos_[size_t(heap_[i].unit)] = int(i);
      i = p;
    }
    heap_[i] = e;
    pos_[size_t(e.unit)] = int(i);
  }
  void down(size_t i) {
    const Entry e = heap_[i];
    const size_t n = heap_.size();
    for (;;) {
      size_t c = 2 * i + 1;
      if (c >= n) break;
      if (c + 1 < n && better(heap_[c + 1], heap_[c])) ++c;
      if (!better(heap_[c], e)) break;
      heap_[i] = heap_[c];
      pos_[size_t(heap_[i].unit)] = int(i);
      i = c;
    }
    heap_[i] = e;
    pos_[size_t(e.unit)] = int(i);
  }
  std::vector<Entry> heap_;
  std::vector<int> pos_;
};

class HierarchyBuilder {
 public:
  HierarchyBuilder(const IndexedMesh& m, const ConeGroupingParams& p, const Progress& cb)
      : mesh_(m), params_(p), progress_(cb), faceCount_(int(m.faces.size())) {}

  Status run(GroupHierarchy& out);

 private:
  float evaluate(const Unit& a, const Unit& b) const;
  void setBest(int u);  // from the cached scores of u's list
  void mergeUnits(int u, int p);
  bool runLevel(double thresholdDeg, long& mergesSoFar);
  void emitLevel(double thresholdDeg, GroupHierarchy& out, bool firstLevel);
  void makeConeExact(int u);
  Neighbour* nbBegin(int u) { return arena_.data() + nbOffset_[size_t(u)]; }
  Neighbour* nbEnd(int u) { return nbBegin(u) + nbCount_[size_t(u)]; }
  void compactArena();

  const IndexedMesh& mesh_;
  const ConeGroupingParams& params_;
  const Progress& progress_;
  const int faceCount_;

  std::vector<vcg::Point3d> faceNormal_;
  std::vector<int> faceNext_;

  std::vector<Unit> units_;
  std::vector<UnitFaces> unitFaces_;
  std::vector<int> mergedInto_;  // the unit a dead unit merged into (resolves the previous level)
  std::vector<char> alive_;
  std::vector<float> bestScore_;
  std::vector<int> bestPartner_;
  UnitHeap heap_;
  std::vector<Neighbour> arena_;
  std::vector<size_t> nbOffset_;
  std::vector<int> nbCount_;
  std::vector<unsigned> stamp_;
  unsigned stampCounter_ = 0;
  std::vector<vcg::Point3d> scratchNormals_;
  double thresholdRad_ = kPi;
  bool thresholdOn_ = false;
  int aliveCount_ = 0;
  bool cancelled_ = false;

  int find(int u) {  // with path halving: merge chains can be long
    while (mergedInto_[size_t(u)] != u) {
      mergedInto_[size_t(u)] = mergedInto_[size_t(mergedInto_[size_t(u)])];
      u = mergedInto_[size_t(u)];
    }
    return u;
  }
};

float HierarchyBuilder::evaluate(const Unit& a, const Unit& b) const {
  double half;
  if (a.half < 0 || b.half < 0) {
    half = std::max(0.0, std::max(a.half, b.half));  // an empty cone adds nothing
  } else if (a.half >= kPi / 2 || b.half >= kPi / 2) {
    half = kPi;
  } else {
    half = UnionHalfAngle(a.cone(), b.cone());
  }
  // The margin covers FastAcos's error, so a merged cone never exceeds the threshold.
  if (thresholdOn_ && half >= thresholdRad_ - 1e-7) return kNoPair;
  const double vc = (kPi - std::min(half, kPi)) / kPi;
  // Enclosing sphere of both spheres: radius only.
  const float dx = b.center[0] - a.center[0], dy = b.center[1] - a.center[1], dz = b.center[2] - a.center[2];
  const float dist = std::sqrt(dx * dx + dy * dy + dz * dz);
  const float r = std::max({a.radius, b.radius, 0.5f * (dist + a.radius + b.radius)});
  const float vx = a.vecArea[0] + b.vecArea[0], vy = a.vecArea[1] + b.vecArea[1], vz = a.vecArea[2] + b.vecArea[2];
  const float sc = float(kPi) * r * r;
  const float vs = sc > 0 ? std::min(1.0f, std::sqrt(vx * vx + vy * vy + vz * vz) / sc) : 0.0f;
  const double vn = double(faceCount_ - (a.faceCount + b.faceCount)) / faceCount_;
  return float(params_.coneWeight * vc + params_.shapeWeight * vs + params_.sizeWeight * vn);
}

void HierarchyBuilder::setBest(int u) {
  float best = kNoPair;
  int partner = -1;
  for (const Neighbour* n = nbBegin(u); n != nbEnd(u); ++n)
    if (n->score > best || (n->score == best && n->score != kNoPair && n->id < partner)) {
      best = n->score;
      partner = n->id;
    }
  bestScore_[size_t(u)] = best;
  bestPartner_[size_t(u)] = partner;
  if (partner >= 0) heap_.set(u, best);
  else heap_.remove(u);
}

void HierarchyBuilder::makeConeExact(int u) {
  UnitFaces& uf = unitFaces_[size_t(u)];
  scratchNormals_.clear();
  for (int f = uf.head; f >= 0; f = faceNext_[size_t(f)]) scratchNormals_.push_back(faceNormal_[size_t(f)]);
  units_[size_t(u)].setCone(MinimalCone(scratchNormals_));
  uf.exactSize = units_[size_t(u)].faceCount;
}

void HierarchyBuilder::mergeUnits(int u, int p) {
  Unit& a = units_[size_t(u)];
  const Unit& b = units_[size_t(p)];
  UnitFaces& af = unitFaces_[size_t(u)];
  UnitFaces& bf = unitFaces_[size_t(p)];

  const NormalCone ca = a.cone(), cb = b.cone();
  const NormalCone merged = UnionCone(ca, cb);
  // The union is still the exact minimal cone when it is one of two exact inputs unchanged.
  const bool grew = !(merged.halfAngle == ca.halfAngle && merged.axis == ca.axis) &&
                    !(merged.halfAngle == cb.halfAngle && merged.axis == cb.axis);
  const bool bothExact = af.exactSize == a.faceCount && bf.exactSize == b.faceCount;
  a.setCone(merged);
  for (int k = 0; k < 3; ++k) a.vecArea[k] += b.vecArea[k];
  a.setSphere(UnionSphere(a.sphere(), b.sphere()));
  a.faceCount += b.faceCount;
  faceNext_[size_t(af.tail)] = bf.head;
  af.tail = bf.tail;
  if (!grew && bothExact) af.exactSize = a.faceCount;
  else if (a.faceCount >= 2 * af.exactSize) makeConeExact(u);  // amortized: each face O(log N) times

  // The merged unit's list: both lists without u and p, deduplicated, each pair re-scored.
  if (arena_.size() > 32 * size_t(aliveCount_) + (1u << 20)) compactArena();  // p still alive here
  alive_[size_t(p)] = 0;
  mergedInto_[size_t(p)] = u;
  heap_.remove(p);
  --aliveCount_;
  const size_t offset = arena_.size();
  const unsigned st = ++stampCounter_;
  stamp_[size_t(u)] = st;
  stamp_[size_t(p)] = st;
  for (const int src : {u, p}) {
    const size_t begin = nbOffset_[size_t(src)];
    const int count = nbCount_[size_t(src)];
    for (int i = 0; i < count; ++i) {
      const int w = arena_[begin + size_t(i)].id;  // index, not pointer: arena_ grows here
      if (stamp_[size_t(w)] == st) continue;
      stamp_[size_t(w)] = st;
      arena_.push_back({w, evaluate(units_[size_t(u)], units_[size_t(w)])});
    }
  }
  nbOffset_[size_t(u)] = offset;
  nbCount_[size_t(u)] = int(arena_.size() - offset);
  nbCount_[size_t(p)] = 0;
  setBest(u);

  // Each neighbour: its entries for u and p become one entry for u with the new score; pairs not
  // involving u are unchanged, so its best is either kept, replaced by u, or rescanned (cached).
  for (size_t i = offset; i < offset + size_t(nbCount_[size_t(u)]); ++i) {
    const int w = arena_[i].id;
    const float s = arena_[i].score;
    Neighbour* nb = nbBegin(w);
    int n = nbCount_[size_t(w)];
    bool seen = false;
    for (int k = 0; k < n;) {
      if (nb[k].id == u || nb[k].id == p) {
        if (!seen) { nb[k] = {u, s}; seen = true; ++k; }
        else nb[k] = nb[--n];
      } else {
        ++k;
      }
    }
    nbCount_[size_t(w)] = n;
    const int bp = bestPartner_[size_t(w)];
    if (bp == u || bp == p) {
      setBest(w);
    } else if (s != kNoPair && (s > bestScore_[size_t(w)] || (s == bestScore_[size_t(w)] && u < bp))) {
      bestScore_[size_t(w)] = s;
      bestPartner_[size_t(w)] = u;
      heap_.set(w, s);
    }
  }
}

void HierarchyBuilder::compactArena() {
  std::vector<Neighbour> fresh;
  fresh.reserve(size_t(aliveCount_) * 8);
  for (size_t u = 0; u < units_.size(); ++u) {
    if (!alive_[u]) continue;
    const size_t begin = nbOffset_[u];
    nbOffset_[u] = fresh.size();
    fresh.insert(fresh.end(), arena_.begin() + long(begin), arena_.begin() + long(begin) + nbCount_[u]);
  }
  arena_.swap(fresh);
}

bool HierarchyBuilder::runLevel(double thresholdDeg, long& mergesSoFar) {
  thresholdOn_ = thresholdDeg < 180.0;
  thresholdRad_ = thresholdDeg * kDeg;
  const size_t n = units_.size();
  mergedInto_.resize(n);
  for (size_t i = 0; i < n; ++i) mergedInto_[i] = int(i);
  alive_.assign(n, 1);
  aliveCount_ = int(n);
  bestScore_.assign(n, kNoPair);
  bestPartner_.assign(n, -1);
  stamp_.assign(n, 0);
  stampCounter_ = 0;
  heap_.reset(n);
  for (size_t u = 0; u < n; ++u) {
    for (Neighbour* nb = nbBegin(int(u)); nb != nbEnd(int(u)); ++nb)
      nb->score = evaluate(units_[u], units_[size_t(nb->id)]);
    setBest(int(u));
  }

  const int minGroups = std::max(1, params_.minTopGroups);
  long merges = 0;
  while (!heap_.empty() && aliveCount_ > minGroups) {
    const int u = heap_.top();
    mergeUnits(u, bestPartner_[size_t(u)]);
    ++merges;
    if ((merges & 0x3FFF) == 0 && progress_) {
      const int pct = int(95.0 * double(mergesSoFar + merges) / std::max(1, faceCount_ - 1));
      if (!progress_(std::min(95, pct), "grouping faces by normal cones")) { cancelled_ = true; return false; }
    }
  }
  mergesSoFar += merges;
  return merges > 0;
}

void HierarchyBuilder::emitLevel(double thresholdDeg, GroupHierarchy& out, bool firstLevel) {
  const size_t n = units_.size();
  GroupLevel level;
  level.thresholdDeg = thresholdDeg;
  // Ids in order of first appearance over faces: deterministic and cache-friendly.
  std::vector<int> idOfUnit(n, -1);
  level.faceGroup.resize(size_t(faceCount_));
  std::vector<int> rootOfGroup;
  // Faces are reached through the previous level's group of each face.
  const std::vector<int>* prevFaceGroup = firstLevel ? nullptr : &out.levels.back().faceGroup;
  for (int f = 0; f < faceCount_; ++f) {
    const int unit = find(prevFaceGroup ? (*prevFaceGroup)[size_t(f)] : f);
    int& id = idOfUnit[size_t(unit)];
    if (id < 0) { id = int(rootOfGroup.size()); rootOfGroup.push_back(unit); }
    level.faceGroup[size_t(f)] = id;
  }
  const size_t groupCount = rootOfGroup.size();
  level.groups.resize(groupCount);

  // Children: faces (level 1) or previous groups, bucketed by new group.
  std::vector<int> childCount(groupCount, 0);
  const size_t childTotal = firstLevel ? size_t(faceCount_) : n;
  std::vector<int> childGroup(childTotal);
  for (size_t c = 0; c < childTotal; ++c) {
    childGroup[c] = firstLevel ? level.faceGroup[c] : idOfUnit[size_t(find(int(c)))];
    ++childCount[size_t(childGroup[c])];
  }
  int running = 0;
  for (size_t g = 0; g < groupCount; ++g) {
    level.groups[g].firstChild = running;
    level.groups[g].childCount = childCount[g];
    running += childCount[g];
  }
  level.children.resize(childTotal);
  {
    std::vector<int> fill(groupCount);
    for (size_t g = 0; g < groupCount; ++g) fill[g] = level.groups[g].firstChild;
    for (size_t c = 0; c < childTotal; ++c) level.children[size_t(fill[size_t(childGroup[c])]++)] = int(c);
  }
  if (!firstLevel) {
    auto& prev = out.levels.back().groups;
    for (size_t c = 0; c < childTotal; ++c) prev[c].parent = childGroup[c];
  }

  // Exact cones, boxes and tight spheres.
  for (size_t g = 0; g < groupCount; ++g) {
    const int u = rootOfGroup[g];
    Unit& unit = units_[size_t(u)];
    const UnitFaces& uf = unitFaces_[size_t(u)];
    if (uf.exactSize != unit.faceCount) makeConeExact(u);
    Group& grp = level.groups[g];
    grp.cone = unit.cone();
    grp.faceCount = unit.faceCount;
    grp.box.SetNull();
    for (int f = uf.head; f >= 0; f = faceNext_[size_t(f)])
      for (uint32_t v : mesh_.faces[size_t(f)]) grp.box.Add(mesh_.positions[v]);
    // A second sphere around the box centre; keep the smaller of it and the merged bound.
    const vcg::Point3d bc = vcg::Point3d::Construct(grp.box.Center());
    double r2 = 0;
    for (int f = uf.head; f >= 0; f = faceNext_[size_t(f)])
      for (uint32_t v : mesh_.faces[size_t(f)])
        r2 = std::max(r2, (vcg::Point3d::Construct(mesh_.positions[v]) - bc).SquaredNorm());
    if (std::sqrt(r2) < unit.radius) unit.setSphere(Sphere{bc, std::sqrt(r2)});
    grp.center = vcg::Point3f(unit.center[0], unit.center[1], unit.center[2]);
    grp.radius = unit.radius;
  }
  out.levels.push_back(std::move(level));
}

Status HierarchyBuilder::run(GroupHierarchy& out) {
  const int nf = faceCount_;
  std::vector<double> areas;
  ComputeFaceNormalsAndAreas(mesh_, faceNormal_, areas);
  faceNext_.assign(size_t(nf), -1);

  // Level-1 units: one per face.
  units_.resize(size_t(nf));
  unitFaces_.resize(size_t(nf));
  for (int f = 0; f < nf; ++f) {
    Unit& u = units_[size_t(f)];
    const auto& t = mesh_.faces[size_t(f)];
    const vcg::Point3d& n = faceNormal_[size_t(f)];
    u.setCone(n.SquaredNorm() > 0.5 ? NormalCone::Of(n) : NormalCone::Empty());
    for (int k = 0; k < 3; ++k) u.vecArea[k] = float(n[k] * areas[size_t(f)]);
    u.setSphere(TriangleSphere(vcg::Point3d::Construct(mesh_.positions[t[0]]),
                               vcg::Point3d::Construct(mesh_.positions[t[1]]),
                               vcg::Point3d::Construct(mesh_.positions[t[2]])));
    u.faceCount = 1;
    unitFaces_[size_t(f)] = UnitFaces{1, f, f};
  }
  {
    const FaceAdjacency adj = BuildFaceAdjacency(mesh_);
    arena_.resize(adj.neighbours.size());
    for (size_t i = 0; i < adj.neighbours.size(); ++i) arena_[i] = {int(adj.neighbours[i]), kNoPair};
    nbOffset_.resize(size_t(nf));
    nbCount_.resize(size_t(nf));
    for (int f = 0; f < nf; ++f) {
      nbOffset_[size_t(f)] = adj.offsets[size_t(f)];
      nbCount_[size_t(f)] = int(adj.degree(uint32_t(f)));
    }
  }
  if (progress_ && !progress_(0, "grouping faces by normal cones")) return Status::Cancelled();

  long merges = 0;
  double threshold = params_.coneThresholdDeg;
  for (int level = 1; level <= params_.maxLevels; ++level) {
    const bool merged = runLevel(std::min(threshold, 180.0), merges);
    if (cancelled_) { out = GroupHierarchy(); return Status::Cancelled(); }
    if (!merged && level > 1) break;  // nothing changed: the previous level is the top
    emitLevel(std::min(threshold, 180.0), out, level == 1);
    if (int(out.levels.back().groups.size()) <= std::max(1, params_.minTopGroups)) break;
    if (level == params_.maxLevels) break;

    // The groups become the units of the next level (their lists already name live units only).
    const GroupLevel& lv = out.levels.back();
    const size_t g = lv.groups.size();
    std::vector<Unit> next(g);
    std::vector<UnitFaces> nextFaces(g);
    std::vector<Neighbour> fresh;
    std::vector<size_t> offs(g);
    std::vector<int> counts(g);
    std::vector<int> rootOf(g);
    for (size_t u = 0; u < units_.size(); ++u)
      if (alive_[u]) rootOf[size_t(lv.faceGroup[size_t(unitFaces_[u].head)])] = int(u);
    for (size_t id = 0; id < g; ++id) {
      const int u = rootOf[id];
      next[id] = units_[size_t(u)];
      nextFaces[id] = unitFaces_[size_t(u)];
      offs[id] = fresh.size();
      for (const Neighbour* w = nbBegin(u); w != nbEnd(u); ++w)
        fresh.push_back({lv.faceGroup[size_t(unitFaces_[size_t(w->id)].head)], kNoPair});
      counts[id] = int(fresh.size() - offs[id]);
    }
    units_.swap(next);
    unitFaces_.swap(nextFaces);
    arena_.swap(fresh);
    nbOffset_.swap(offs);
    nbCount_.swap(counts);
    threshold *= params_.thresholdGrowth;
  }

  // Areas per group, from the faces.
  for (auto& lv : out.levels)
    for (int f = 0; f < nf; ++f) lv.groups[size_t(lv.faceGroup[size_t(f)])].area += areas[size_t(f)];
  out.faceCount = nf;
  if (progress_ && !progress_(100, "grouping done")) { out = GroupHierarchy(); return Status::Cancelled(); }
  return Status::Ok();
}

}  // namespace

double GroupLevel::maxConeDeg() const {
  double m = 0;
  for (const auto& g : groups) m = std::max(m, g.cone.cullable() ? std::max(0.0, g.cone.halfAngle) / kDeg : 180.0);
  return m;
}

double GroupLevel::meanConeDeg() const {
  if (groups.empty()) return 0;
  double s = 0;
  for (const auto& g : groups) s += g.cone.cullable() ? std::max(0.0, g.cone.halfAngle) / kDeg : 180.0;
  return s / double(groups.size());
}

int GroupLevel::uncullableGroups() const {
  int n = 0;
  for (const auto& g : groups) n += g.cone.cullable() ? 0 : 1;
  return n;
}

Status ValidateParams(const ConeGroupingParams& p) {
  auto finiteNonNeg = [](double x) { return std::isfinite(x) && x >= 0; };
  if (!finiteNonNeg(p.coneWeight) || !finiteNonNeg(p.shapeWeight) || !finiteNonNeg(p.sizeWeight))
    return Status::Invalid("ConeWeight, ShapeWeight and SizeWeight must be finite and >= 0");
  if (p.coneWeight + p.shapeWeight + p.sizeWeight <= 0)
    return Status::Invalid("at least one of ConeWeight, ShapeWeight, SizeWeight must be > 0");
  if (!(p.coneThresholdDeg > 0) || !std::isfinite(p.coneThresholdDeg))
    return Status::Invalid("ConeThresholdDeg must be > 0 degrees (180 or more: no limit)");
  if (!(p.thresholdGrowth >= 1.0) || !std::isfinite(p.thresholdGrowth))
    return Status::Invalid("ThresholdGrowth must be >= 1 (the limit never shrinks from one level to the next)");
  if (p.maxLevels < 1 || p.maxLevels > 64) return Status::Invalid("MaxLevels must be between 1 and 64");
  if (p.minTopGroups < 1) return Status::Invalid("MinTopGroups must be >= 1");
  return Status::Ok();
}

Status BuildConeHierarchy(const IndexedMesh& mesh, const ConeGroupingParams& params, GroupHierarchy& out,
                          const Progress& progress) {
  out = GroupHierarchy();
  Status s = ValidateParams(params);
  if (!s.ok()) return s;
  s = RequireValidForFaces(CheckMesh(mesh, /*withTopology=*/false));
  if (!s.ok()) return s;
  if (mesh.faces.size() >= size_t(std::numeric_limits<int>::max()) / 4)
    return Status::Invalid("the mesh has too many faces for 32-bit group ids");
  try {
    HierarchyBuilder builder(mesh, params, progress);
    return builder.run(out);
  } catch (const std::bad_alloc&) {
    out = GroupHierarchy();
    return Status::OutOfMemory("not enough memory to group " + std::to_string(mesh.faces.size()) + " faces");
  }
}

}  // namespace conelod
