// ConeLOD — hierarchical face grouping by an evaluation function (see cone_grouping.h).
//
// Implementation notes. The greedy loop keeps, for every live unit, its best partner and that
// pair's score; a tournament tree over units (not over pairs) gives the global best pair. A
// merge only changes pairs that involve the merged unit, so only its neighbours are revisited:
// a neighbour whose best partner was one of the merged units rescans its own neighbours, the
// others compare their pair with the new unit against their best. At level 1, sweeps in unit
// order first merge the mutual best pairs (RunLevel; the tree is built after them), first
// within chunks of consecutive units on the threads (MergeChunks), each with its own MergeState.
//
// The loop is bound by memory latency (each merge touches ~20 units scattered over the mesh), so
// the per-unit state is split by access pattern and packed: the geometry every evaluation reads
// (one cache line), the greedy state read for every neighbour (a quarter line), the face chain
// touched only by the merging units; and a merge prefetches all its neighbours' data before it
// uses any of it. Neighbour lists live in one arena: a merged list goes back into its unit's
// slot when it fits, else to the end; the arena is compacted in place when full. When an exact
// cone needs face normals during level 1's merges, the default mode reads them from an array of
// float normals (widening the cone for their rounding) and the strict mode recomputes them from
// the mesh, rather than keeping them in double: the build's peak memory stays under twice the
// loaded mesh's.
// Once level 1's merges are done and its arrays freed, the faces are renumbered group by group
// (RenumberFaces, which keeps their normals and areas), so level 1's final exact cones and the
// upper levels read normals in order; each level-1 group's distinct vertices are collected in the
// same pass, and every level's spheres read those rather than the faces. Exact cones rarely run
// Welzl's algorithm in the default mode:
// above level 1 they start from the support of the merged units' cones (TrySupportCone), at
// level 1 (no supports kept) from the cap of two far normals (seededCone); either guess is
// checked against every normal. With strictGreedy none of this changes a bit of the
// output of the paper's best-first order: the same pairs are scored with the same arithmetic and
// MinimalCone sees the same normals in the same order (bench/check_grouping prints digests to
// compare two builds of the code; its "strict-greedy" set is the former default).
#include "conelod/common.h"
#include "conelod/grouping/cone_grouping.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <utility>

#include "conelod/big_alloc.h"
#include "conelod/mesh/face_adjacency.h"
#include "conelod/mesh/mesh_check.h"
#include "conelod/parallel.h"
#include "conelod/stage_log.h"

namespace conelod {

namespace {

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
  if (ab * ac <= 0) {
    edgeSphere(b, c, lbc);
    return s;
  }  // obtuse or right at a
  if ((a - b) * bc <= 0) {
    edgeSphere(a, c, lac);
    return s;
  }  // at b
  if ((a - c) * (b - c) <= 0) {
    edgeSphere(a, b, lab);
    return s;
  }  // at c
  const vcg::Point3d n = ab ^ ac;
  const double n2 = n.SquaredNorm();
  if (n2 <= 0) {
    edgeSphere(b, c, lbc);
    return s;
  }
  const vcg::Point3d off = ((n ^ ab) * lac + (ac ^ n) * lab) / (2 * n2);
  s.c = a + off;
  // max(sqrt x, sqrt y) == sqrt(max(x, y)) (a correctly rounded sqrt is monotone): one root.
  s.r = std::sqrt(std::max({(s.c - a).SquaredNorm(), (s.c - b).SquaredNorm(), (s.c - c).SquaredNorm()}));
  return s;
}

// One unit of the greedy merge (a face at level 1, a group above): the data every candidate
// evaluation reads, packed in one cache line.
struct alignas(64) Unit {
  vcg::Point3d axis;  // cone axis (unit)
  double half;        // cone half-angle: < 0 empty, >= pi/2 cannot be culled
  float vecArea[3];   // sum of area * unit normal
  float center[3];    // bounding sphere
  float radius;
  int faceCount;

  NormalCone cone() const {
    NormalCone c;
    c.axis = axis;
    c.halfAngle = half;
    return c;
  }
  void setCone(const NormalCone& c) {
    axis = c.axis;
    half = c.halfAngle;
  }
  Sphere sphere() const {
    Sphere s;
    s.c = vcg::Point3d(center[0], center[1], center[2]);
    s.r = radius;
    return s;
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

// The greedy state of a unit that a merge reads and writes for every neighbour of the merged
// unit: a quarter of a cache line. (The best pair's score is the unit's key in BestTree.)
struct Link {
  int bestPartner;    // -1: no mergeable pair
  uint32_t nbOffset;  // the neighbour list is arena_[nbOffset, nbOffset + nbCount)
  int nbCount;
  uint32_t stamp;  // deduplicates neighbours while two lists are joined
};

// The state of a unit touched only when the unit itself merges.
struct Chain {
  int tail;       // last face of the unit's circular face list (faceNext_); -1: dead unit
  int exactSize;  // faceCount when the cone was last computed exactly
  int capacity;   // room of the unit's list slot in the arena (>= Link::nbCount)
};

// A neighbour in a unit's adjacency list, with the score of the pair (-inf: not mergeable).
// Lists are kept resolved: they only ever name live units.
struct Neighbour {
  int id;
  float score;
};

// The neighbour lists' storage: a vector without initialisation (lists are written in bulk, and
// reserved pages never written cost no memory).
class Arena {
 public:
  Arena() = default;
  Arena(const Arena&) = delete;
  Arena& operator=(const Arena&) = delete;
  ~Arena() { release(); }
  Neighbour* data() { return data_; }
  size_t size() const { return size_; }
  size_t capacity() const { return capacity_; }
  // Appends n entries (capacity permitting) and returns the offset of the first.
  size_t grow(size_t n) {
    const size_t at = size_;
    size_ += n;
    return at;
  }
  void resize(size_t n) { size_ = n; }  // (within the capacity)
  void reserve(size_t n) {
    if (n <= capacity_) return;
    Neighbour* fresh = BigAlloc<Neighbour>().allocate(n);
    if (size_) std::memcpy(fresh, data_, size_ * sizeof(Neighbour));
    release();
    data_ = fresh;
    capacity_ = n;
  }
  void swap(Arena& o) {
    std::swap(data_, o.data_);
    std::swap(size_, o.size_);
    std::swap(capacity_, o.capacity_);
  }

 private:
  void release() {
    if (data_) BigAlloc<Neighbour>().deallocate(data_, capacity_);
    data_ = nullptr;
    size_ = capacity_ = 0;
  }
  Neighbour* data_ = nullptr;
  size_t size_ = 0, capacity_ = 0;
};

constexpr float kNoPair = -std::numeric_limits<float>::infinity();
constexpr float kUnscored = std::numeric_limits<float>::quiet_NaN();  // a list entry not scored yet

// A scored list entry as one integer ordered like (higher score, lower id), so that a unit's best
// pair is the largest entry of its list: one integer maximum per entry and no branch, where the
// comparisons of scores branched unpredictably. Scores are kNoPair or >= +0 (sums of
// non-negative terms): their bits as signed integers are in the same order, kNoPair below 0.
inline int64_t PairEntry(const Neighbour& n) {
  uint32_t bits;
  std::memcpy(&bits, &n.score, sizeof bits);
  return int64_t((uint64_t(bits) << 32) | (0xFFFFFFFFu - uint32_t(n.id)));
}
constexpr int64_t kNoEntry = std::numeric_limits<int64_t>::min();  // the maximum of an empty list
// The pair of the largest entry: its score and id, or kNoPair and -1 when no entry is a pair.
inline void BestPair(int64_t top, float& best, int& partner) {
  best = kNoPair;
  partner = -1;
  if (top < 0) return;
  const uint32_t bits = uint32_t(uint64_t(top) >> 32);
  std::memcpy(&best, &bits, sizeof best);
  partner = int(0xFFFFFFFFu - uint32_t(top));
}

// The unit with the best pair: an 8-ary tournament tree over the units' keys (the score of each
// unit's best pair; kNoPair: none). A unit's leaf sits at its own index, so the neighbours of a
// merged unit, close in index, share the lower nodes of their paths, and an update that does
// not change a node's winner stops there: cheaper on memory than a heap, where positions are
// scattered. Ties go to the lower unit id (deterministic output). A node holds its winner as
// one integer, key then unit, ordered like (higher key, lower unit): one comparison per child.
class BestTree {
 public:
  // n units, none with a pair yet; setKey then build, or set.
  void reset(size_t n) {
    deferred_ = false;
    key_.assign(RoundUp(std::max<size_t>(n, 1)), kNoPair);
    levelBegin_.clear();
    levelCount_.clear();
    size_t below = key_.size(), total = 0;
    for (;;) {
      const size_t count = below / kArity;
      levelBegin_.push_back(total);
      levelCount_.push_back(count);
      if (count == 1) {
        total += 1;
        break;
      }
      below = RoundUp(count);
      total += below;
    }
    nodes_.assign(total, 0);  // padding: below every real entry, kNoPair included
  }
  float key(int u) const { return key_[size_t(u)]; }
  void prefetch(int u) const {  // the leaf and its parent (level 1 starts nodes_)
    Prefetch(&key_[size_t(u)]);
    Prefetch(&nodes_[size_t(u) / kArity]);
  }
  void setKey(int u, float k) { key_[size_t(u)] = k; }
  void build() {
    for (size_t level = 1; level <= levelBegin_.size(); ++level)
      for (size_t i = 0; i < levelCount_[level - 1]; ++i) node(level, i) = winner(level, i);
  }
  void release() {
    BigVector<float>().swap(key_);
    BigVector<uint64_t>().swap(nodes_);
  }
  bool empty() const { return (nodes_.back() >> 32) == OrderedKey(kNoPair); }
  int top() const { return UnitOf(nodes_.back()); }
  // While deferred, set() only records the key: build() makes the tree whole again.
  void setDeferred(bool d) { deferred_ = d; }
  void set(int u, float k) {
    const float old = key_[size_t(u)];
    key_[size_t(u)] = k;
    if (deferred_) return;
    size_t i = size_t(u);
    if (k > old) {  // u can only win more nodes
      const uint64_t e = Entry(k, u);
      for (size_t level = 1; level <= levelBegin_.size(); ++level) {
        i /= kArity;
        uint64_t& n = node(level, i);
        if (UnitOf(n) != u && e < n) return;
        n = e;
      }
    } else if (k < old) {  // only the nodes u was winning change
      for (size_t level = 1; level <= levelBegin_.size(); ++level) {
        i /= kArity;
        uint64_t& n = node(level, i);
        if (UnitOf(n) != u) return;
        n = winner(level, i);
      }
    }
  }

 private:
  static constexpr size_t kArity = 8;  // 8 nodes = one cache line
  static size_t RoundUp(size_t n) { return (n + kArity - 1) / kArity * kArity; }
  // Keys as unsigned integers in the same order (no NaN here; -0 counts as +0, as in floats).
  static uint32_t OrderedKey(float k) {
    k += 0.0f;
    uint32_t bits;
    std::memcpy(&bits, &k, sizeof bits);
    return (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
  }
  static uint64_t Entry(float k, int u) { return (uint64_t(OrderedKey(k)) << 32) | (0xFFFFFFFFu - uint32_t(u)); }
  static int UnitOf(uint64_t e) { return int(0xFFFFFFFFu - uint32_t(e)); }
  uint64_t& node(size_t level, size_t i) { return nodes_[levelBegin_[level - 1] + i]; }
  // The best of the children of node i at `level`.
  uint64_t winner(size_t level, size_t i) {
    if (level == 1) {  // leaves in index order: ties to the first
      const float* k = &key_[i * kArity];
      size_t best = 0;
      for (size_t j = 1; j < kArity; ++j)
        if (k[j] > k[best]) best = j;
      return Entry(k[best], int(i * kArity + best));
    }
    const uint64_t* c = &node(level - 1, i * kArity);
    uint64_t best = c[0];
    for (size_t j = 1; j < kArity; ++j) best = std::max(best, c[j]);
    return best;
  }

  BigVector<float> key_;            // leaves, padded to a multiple of kArity
  BigVector<uint64_t> nodes_;       // levels 1.. (each padded to a multiple of kArity), root last
  std::vector<size_t> levelBegin_;  // first node of level 1, 2, ... in nodes_
  std::vector<size_t> levelCount_;  // live nodes per level
  bool deferred_ = false;
};

// The working memory of one exact cone computation (MakeConeExact): one per thread.
struct ConeScratch {
  std::vector<int> faces;
  std::vector<vcg::Point3d> normals;
  std::vector<vcg::Point3d> support, trial;
  // The normals of the unit whose exact cone is being made, in the order of its face list, as
  // runs: of faceNormal_ from level 2 on (read in place: the scans above need no copy), of
  // `normals` at level 1 (from the mesh). Copied only for Welzl's algorithm.
  std::vector<std::pair<const vcg::Point3d*, const vcg::Point3d*>> runs;
  // Calls f on each of those normals in order while it returns true; false: f stopped it.
  template <class F>
  bool eachNormal(F f) const {
    for (const auto& run : runs)
      for (const vcg::Point3d* n = run.first; n != run.second; ++n)
        if (!f(*n)) return false;
    return true;
  }
};

class HierarchyBuilder {
 public:
  HierarchyBuilder(const IndexedMesh& m, const ConeGroupingParams& p, const Progress& cb,
                   const FaceAdjacency* adjacency)
      : mesh_(m),
        params_(p),
        progress_(cb),
        adjacency_(adjacency),
        faceCount_(int(m.faces.size())),
        threads_(p.threads > 0 ? unsigned(p.threads) : CoreCount()),
        scale_(NormalizingScale(m)) {}

  Status run(GroupHierarchy& out);

 private:
  // Inlined into the first scores and the merges (no call per evaluation).
  __attribute__((always_inline)) inline float evaluate(const Unit& a, const Unit& b) const;
  // What a run of merges changes besides the units it merges (and the lists of their neighbours):
  // the merges on one thread use serial_; at level 1 each chunk (MergeChunks) has its own.
  struct MergeState {
    int begin = 0, end = 0;  // the units it may mark dirty (dirty_): [begin, end)
    ConeScratch scratch;
    std::vector<Neighbour> list;  // the merged unit's list being made
    uint32_t stamp = 0;           // the last stamp used (Link::stamp)
    // pool_'s slots it hands out (the last first); when none is left, a block of fresh ones
    // (freshSlots_).
    std::vector<int> freeSlots;
    // A chunk appends lists to its own region of the arena, [arenaBegin, arenaEnd) (arenaNext:
    // the first free entry), and compacts its own lists (CompactChunk); its units' first lists
    // are [listBegin, listEnd). Not a chunk: appends go to the end of arena_ (CompactArena).
    bool chunk = false;
    size_t arenaBegin = 0, arenaNext = 0, arenaEnd = 0, listBegin = 0, listEnd = 0;
    std::vector<std::pair<int, uint32_t>> appendLog;  // (unit, offset) of its region's lists
    long merges = 0;                                  // a chunk's, once done
    // A chunk's faces alone, made once when it starts (MakeSingles; singles[u - begin], valid
    // while u is not stored): every unit its merges read lies in the chunk, and SingleUnit was a
    // fifth of the build when made again at each read. Null: none (units are made when read).
    const Unit* singles = nullptr;
    // u's unit as made there, or null (no singles, or u outside [begin, end)).
    const Unit* single(int u) const { return singles && u >= begin && u < end ? singles + (u - begin) : nullptr; }
  };
  // From the cached scores of u's list. Inlined: it is the core of a merge's neighbour updates.
  __attribute__((always_inline)) inline void setBest(int u, const MergeState& ms);
  // False (nothing changed): a chunk's arena region has no room for the merged list.
  bool MergeUnits(int u, int p, MergeState& ms);
  bool RunLevel(double thresholdDeg, bool localMaximaFirst, long& mergesSoFar);
  int MinTopGroups() const { return std::max(1, params_.minTopGroups); }
  bool MergeChunks(int round, int minGroups, long mergesSoFar, long& merges);
  void CompactChunk(MergeState& ms);
  void setThreshold(double thresholdDeg) {
    thresholdOn_ = thresholdDeg < 180.0;
    // A cone of pi/2 or more cannot be culled and is stored as pi, above any threshold under 180
    // degrees: below 180 the limit is never above pi/2. (Without this, a pair whose bound came out
    // just under pi/2 could merge into a group whose exact cone is uncullable.)
    thresholdRad_ = std::min(thresholdDeg * kDeg, kPi / 2);
  }
  bool ReportProgress(long mergesSoFar);
  void EmitLevel(double thresholdDeg, GroupHierarchy& out, bool firstLevel);
  void nextLevelUnits();
  void MakeConeExact(int u, ConeScratch& cs);
  void MakeCone(int u, ConeScratch& cs);  // MakeConeExact without the widening for l1Rounded_
  bool alive(int u) const { return chains_[size_t(u)].tail >= 0; }
  Neighbour* nbBegin(int u) { return arena_.data() + links_[size_t(u)].nbOffset; }
  Neighbour* nbEnd(int u) { return nbBegin(u) + links_[size_t(u)].nbCount; }
  // u's list entry for w takes the score of the pair (w's entry for u was scored: lists are symmetric).
  void setEntryScore(int u, int w, float score) {
    for (Neighbour* e = nbBegin(u); e != nbEnd(u); ++e)
      if (e->id == w) {
        e->score = score;
        return;
      }
  }
  void CompactArena(size_t room);

  const IndexedMesh& mesh_;
  const ConeGroupingParams& params_;
  const Progress& progress_;
  const FaceAdjacency* const adjacency_;  // the caller's (BuildConeHierarchy), or null: built here
  const int faceCount_;
  // Threads of the parallel parts (ConeGroupingParams::threads, 0 resolved), >= 1.
  const unsigned threads_;
  // Units, groups or faces per piece of parallel work.
  static constexpr size_t kGroupChunk = 256, kFaceChunk = 1 << 14;
  // The units' spheres and area vectors are in coordinates times scale_ (NormalizingScale), so
  // that their float squares neither overflow nor vanish whatever the model's size: the scores
  // and so the groups do not depend on it. The groups' boxes, spheres and areas are given back in
  // the mesh's coordinates (exactly: scale_ is a power of two).
  const double scale_;

  // Circular face lists, one per unit (Chain::tail). From level 2 on the faces are renumbered
  // (meshFace_), each level-1 group's faces contiguous in the order of its list: the lists above
  // are runs of consecutive faces, walked in memory order.
  BigVector<int> faceNext_;
  BigVector<int> meshFace_;  // from level 2 on: the mesh face of each renumbered face
  // Face normals of the renumbered faces, from level 2 on. Level 1's arrays leave no room for
  // these under the memory target (its cone refreshes compute them from the mesh); above it,
  // with far fewer units, there is.
  BigVector<vcg::Point3d> faceNormal_;
  // Level 1, default mode, during the merges only: the cone refreshes take every face's unit
  // normal rounded to float (as the array of them that this replaces held, 12 bytes a face that
  // issue 25's memory target leaves no room for), and widen the cone for the rounding.
  bool l1Rounded_ = false;
  BigVector<double> faceArea_;  // from level 2 on: every mesh face's area (FaceNormalAndArea), by mesh face
  int meshFace(int f) const { return meshFace_.empty() ? f : meshFace_[size_t(f)]; }
  void RenumberFaces();
  // From level 1's emission on: the distinct vertices of every level-1 group, group by group
  // (group g's are l1Verts_[l1VertBegin_[g], l1VertBegin_[g + 1])), and each level-1 group's group
  // at the level last emitted. A group's tight sphere (and level 1's box) is a maximum (minimum)
  // over its vertices, which neither their order nor repeats change: read from these lists, each
  // level reads about a third of the vertices that its faces name, in order.
  BigVector<vcg::Point3f> l1Verts_;
  BigVector<uint32_t> l1VertBegin_;
  BigVector<int> l1Group_;
  // Above level 1: the unit that absorbed each dead unit of the level (MergeUnits).
  BigVector<int> absorbedBy_;
  // From level 2 on, unless strictGreedy: per unit, up to three normals of its faces whose
  // minimal cone is the unit's exact cone, or (after a merge) a guess of it: the support of the
  // minimal cone of both units' supports. An exact recomputation first tries that guess: when
  // every normal of the unit lies in it, it is the minimal cone (the minimal cone of a subset
  // that holds them all), found with one scan instead of Welzl's algorithm.
  BigVector<ConeSupport> support_;
  bool TrySupportCone(int u, ConeScratch& cs);
  bool seededCone(int u, ConeScratch& cs);
  bool RefineCone(int u, ConeScratch& cs);  // on cs.support and cs.runs
  // The state of the merges on one thread (its scratch included); EmitLevel's exact cones take
  // a scratch per thread.
  MergeState serial_;

  // Units: units_[u] from level 2 on (and at level 1 in strict mode). Level 1 in the default mode
  // (sparse_) stores only the units that have merged, in pool_ at slot_[u] (-1: u is still its
  // face alone): a face's own unit is made from the mesh when read (SingleUnit, bit for bit what
  // storing it held), so that level 1 does not hold a 64-byte unit per face (issue 25's memory
  // target: the pool holds at most one unit per two faces, and its slots are reused).
  BigVector<Unit> units_;
  bool sparse_ = false;
  BigVector<int> slot_;
  // Sized once (mapped: only the slots used take memory). Never used: [freshSlots_, end), handed
  // out in blocks of kSlotBlock, lowest first, to whichever MergeState needs them: the slots in use
  // stay packed at the start whatever the chunks (the slot a unit gets changes no output).
  BigVector<Unit> pool_;
  std::atomic<size_t> freshSlots_{0};
  static constexpr size_t kSlotBlock = 256;
  size_t unitCount() const { return chains_.size(); }
  void SingleUnit(int f, Unit& u) const;
  // Unit u as stored, or a face alone at level 1: as `ms` made it (a chunk's), else made into `tmp`.
  const Unit& unitOf(int u, Unit& tmp, const MergeState* ms = nullptr) const {
    if (!sparse_) return units_[size_t(u)];
    const int s = slot_[size_t(u)];
    if (s >= 0) return pool_[size_t(s)];
    if (const Unit* made = ms ? ms->single(u) : nullptr) return *made;
    SingleUnit(u, tmp);
    return tmp;
  }
  // The faces alone among the live units of [begin, end) into out[u - begin] (out grown to fit).
  void MakeSingles(int begin, int end, BigVector<Unit>& out) const {
    if (out.size() < size_t(end - begin)) out.resize(size_t(end - begin));
    for (int u = begin; u < end; ++u)
      if (alive(u) && slot_[size_t(u)] < 0) SingleUnit(u, out[size_t(u - begin)]);
  }
  // Unit u, stored first if it was not, in a slot that `ms` hands out.
  Unit& unit(int u, MergeState& ms) {
    if (!sparse_) return units_[size_t(u)];
    int& s = slot_[size_t(u)];
    if (s < 0) {
      if (ms.freeSlots.empty()) {
        const size_t block = freshSlots_.fetch_add(kSlotBlock);
        assert(block + kSlotBlock <= pool_.size());
        for (size_t k = kSlotBlock; k-- > 0;) ms.freeSlots.push_back(int(block + k));
      }
      s = ms.freeSlots.back();
      ms.freeSlots.pop_back();
      if (const Unit* made = ms.single(u))
        pool_[size_t(s)] = *made;
      else
        SingleUnit(u, pool_[size_t(s)]);
    }
    return pool_[size_t(s)];
  }
  // (Called on stored units only while chunks merge: MergeUnits stores its unit first.)
  Unit& unit(int u) { return unit(u, serial_); }
  void PrefetchUnit(int u) const {
    if (!sparse_)
      Prefetch(&units_[size_t(u)]);
    else
      Prefetch(&slot_[size_t(u)]);
  }
  BigVector<Link> links_;
  BigVector<Chain> chains_;
  BestTree tree_;
  // Neighbour lists. The lists at [0, prefixEnd_) are those of arenaOrder_'s units (in that
  // order; empty: every unit in index order), those after were appended in appendLog_'s order.
  Arena arena_;
  size_t prefixEnd_ = 0;
  std::vector<int> arenaOrder_;
  std::vector<std::pair<int, uint32_t>> appendLog_;  // (unit, offset)
  // Found by EmitLevel: the level's group of each unit, the unit of each group.
  std::vector<int> idOfUnit_, rootOfGroup_;
  double thresholdRad_ = kPi;
  // A unit's cone is recomputed exactly once its face count reaches this many times the count at
  // its last exact computation (see ConeGroupingParams::strictGreedy).
  int exactGrowth_ = 2;
  bool thresholdOn_ = false;
  bool prescored_ = false;  // level 1, default mode: run() scored every pair with the units
  int aliveCount_ = 0;
  // Level 1, default mode: the chunks of consecutive units that merge on their own first
  // (MergeChunks); fewer than 2: none.
  size_t chunkCount_ = 0;
  // During level 1's sweeps: per unit, whether it was marked since its last visit (RunLevel).
  uint8_t* dirty_ = nullptr;
  bool cancelled_ = false;
};

void HierarchyBuilder::SingleUnit(int f, Unit& u) const {
  const auto& t = mesh_.faces[size_t(f)];
  vcg::Point3d n;
  double area;
  FaceNormalAndArea(mesh_, size_t(f), n, area);
  u.setCone(n.SquaredNorm() > 0.5 ? NormalCone::Of(n) : NormalCone::Empty());
  const double scaledArea = area * scale_ * scale_;
  for (int k = 0; k < 3; ++k) u.vecArea[k] = float(n[k] * scaledArea);
  u.setSphere(TriangleSphere(vcg::Point3d::Construct(mesh_.positions[t[0]]) * scale_,
                             vcg::Point3d::Construct(mesh_.positions[t[1]]) * scale_,
                             vcg::Point3d::Construct(mesh_.positions[t[2]]) * scale_));
  u.faceCount = 1;
}

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

void HierarchyBuilder::setBest(int u, const MergeState& ms) {
  int64_t top = kNoEntry;
  for (const Neighbour* n = nbBegin(u); n != nbEnd(u); ++n) top = std::max(top, PairEntry(*n));
  float best;
  int partner;
  BestPair(top, best, partner);
  links_[size_t(u)].bestPartner = partner;
  tree_.set(u, best);
  if (dirty_) {
    dirty_[size_t(u)] = 1;
    // (A chunk marks its own units only: the others belong to other threads and get their
    // visit in the sweeps after the chunks anyway.)
    if (partner >= ms.begin && partner < ms.end) dirty_[size_t(partner)] = 1;
  }
}

void HierarchyBuilder::MakeConeExact(int u, ConeScratch& cs) {
  MakeCone(u, cs);
  if (l1Rounded_) {
    // From normals rounded to float (each off its direction by ~1e-7 rad): widened by 1e-6 rad to
    // stay a bound of the true normals' cone. Emission recomputes every level-1 cone exactly.
    Unit& unit = this->unit(u);
    if (unit.half >= 0 && unit.half < kPi / 2) {
      unit.half += 1e-6;
      if (unit.half >= kPi / 2) unit.half = kPi;  // uncullable: stored as pi (setThreshold)
    }
  }
}

void HierarchyBuilder::MakeCone(int u, ConeScratch& cs) {
  const int tail = chains_[size_t(u)].tail;
  int f = tail;
  if (!faceNormal_.empty()) {
    // The list is made of runs of consecutive faces (RenumberFaces): their normals are runs of
    // faceNormal_, in the list's order.
    cs.runs.clear();
    int head = faceNext_[size_t(tail)];
    for (;;) {
      int last = head;
      while (last != tail && faceNext_[size_t(last)] == last + 1) ++last;
      cs.runs.emplace_back(faceNormal_.data() + head, faceNormal_.data() + last + 1);
      if (last == tail) break;
      head = faceNext_[size_t(last)];
    }
    if (!support_.empty() && TrySupportCone(u, cs)) return;
  } else {
    // Walk the list first, then compute the normals: the walk is a chain of dependent loads, the
    // normals are independent of each other and their misses overlap (prefetched ahead).
    cs.faces.clear();
    do {
      f = faceNext_[size_t(f)];
      cs.faces.push_back(f);
    } while (f != tail);
    const size_t n = cs.faces.size();
    cs.normals.resize(n);
    double area;
    for (size_t i = 0; i < n; ++i) {
      if (i + 8 < n) Prefetch(&mesh_.faces[size_t(cs.faces[i + 8])]);
      if (i + 4 < n)
        for (const uint32_t v : mesh_.faces[size_t(cs.faces[i + 4])]) Prefetch(&mesh_.positions[v]);
      FaceNormalAndArea(mesh_, size_t(cs.faces[i]), cs.normals[i], area);
      if (l1Rounded_) {  // rounded to float and made unit again (see l1Rounded_)
        vcg::Point3d& r = cs.normals[i];
        r = vcg::Point3d::Construct(vcg::Point3f::Construct(r));
        const double len2 = r.SquaredNorm();
        if (len2 > 0) r /= std::sqrt(len2);
      }
    }
    cs.runs.assign(1, {cs.normals.data(), cs.normals.data() + n});
  }
  if (!params_.strictGreedy && seededCone(u, cs)) return;
  if (!faceNormal_.empty()) {  // Welzl's algorithm shuffles its input: a copy
    cs.normals.clear();
    for (const auto& run : cs.runs) cs.normals.insert(cs.normals.end(), run.first, run.second);
  }
  ConeSupport support;
  unit(u).setCone(MinimalCone(cs.normals, support));
  if (!support_.empty()) support_[size_t(u)] = support;
  chains_[size_t(u)].exactSize = unit(u).faceCount;
}

// MakeConeExact's shortcut (see support_), on the normals in cs.runs: true when the
// unit's cone was set. The guess is the minimal cone of a few normals; the normals outside it
// join them and the guess is made again (the cone only grows towards the true one), a few times
// at most before leaving the work to Welzl's algorithm on all the normals.
bool HierarchyBuilder::TrySupportCone(int u, ConeScratch& cs) {
  ConeSupport& support = support_[size_t(u)];
  if (support.count == 0) return false;
  cs.support.assign(support.normal, support.normal + support.count);
  return RefineCone(u, cs);
}

// Level 1, default mode (no support known): the first guess comes from the normals themselves,
// the one farthest from the unit's current axis (the union bound's, or the exact cone's) and the
// one farthest from that. Their cap, checked here against every normal, holds them all for most
// groups: that is the minimal cone; else the normals outside join the two in RefineCone. Empty
// or uncullable units are left to Welzl. (Before, Welzl ran on all the normals of every level-1
// exact cone: the bunny's build took 516 M instructions, 485 M since; MinimalCone's share of
// the dragon's profile went from 6.8% to 1.6%.)
bool HierarchyBuilder::seededCone(int u, ConeScratch& cs) {
  const Unit& unit = this->unit(u);
  if (!(unit.half >= 0 && unit.half < kPi / 2)) return false;
  const vcg::Point3d axis = unit.axis;
  const vcg::Point3d* first = nullptr;
  double lowest = 2;
  cs.eachNormal([&](const vcg::Point3d& n) {
    // The cheap test first: the zero normals of degenerate faces (dot 0) are rarely the lowest.
    if (n * axis < lowest && n.SquaredNorm() >= 0.5) {
      lowest = n * axis;
      first = &n;
    }
    return true;
  });
  if (!first) return false;
  const vcg::Point3d far1 = *first;
  const vcg::Point3d* second = first;
  lowest = 2;
  cs.eachNormal([&](const vcg::Point3d& n) {
    if (n * far1 < lowest && n.SquaredNorm() >= 0.5) {
      lowest = n * far1;
      second = &n;
    }
    return true;
  });
  const vcg::Point3d far2 = *second;
  // The minimal cone of the two as MinimalCone makes it (one normal's cap when the other lies in
  // it to the slack of 1e-10 on cosines, else the two-point cap), checked against every normal
  // here: most groups need no more.
  vcg::Point3d axis2 = far1;
  double cosHalf = 1;
  if (!(far2 * far1 >= 1 - 1e-10)) {
    axis2 = far1 + far2;
    const double len = axis2.Norm();
    if (len < 1e-12) return false;
    axis2 /= len;
    cosHalf = std::min(axis2 * far1, axis2 * far2);
    if (!(cosHalf > 1e-9)) return false;
  }
  cs.support.assign({far1, far2});
  const double minCos = cosHalf - 1e-10;
  size_t outside = 0;
  const bool few = cs.eachNormal([&](const vcg::Point3d& n) {
    if (!(n * axis2 >= minCos) && n.SquaredNorm() >= 0.5) {
      if (++outside > 256) return false;
      cs.support.push_back(n);
    }
    return true;
  });
  if (!few) return false;
  if (outside > 0) return RefineCone(u, cs);
  NormalCone cone;
  cone.axis = axis2;
  cone.halfAngle = std::acos(std::min(1.0, cosHalf));
  this->unit(u).setCone(cone);
  if (!support_.empty()) {
    ConeSupport& support = support_[size_t(u)];
    support.normal[0] = far1;
    support.normal[1] = far2;
    support.count = cosHalf == 1 ? 1 : 2;
  }
  chains_[size_t(u)].exactSize = this->unit(u).faceCount;
  return true;
}

// The guess is the minimal cone of the normals in cs.support; the normals of
// cs.runs outside it join them and the guess is made again (the cone only grows towards
// the true one), a few times at most before leaving the work to Welzl's algorithm on all the
// normals (false). True: the unit's cone (and support, where kept) was set.
bool HierarchyBuilder::RefineCone(int u, ConeScratch& cs) {
  std::vector<vcg::Point3d>& chosen = cs.support;
  ConeSupport found;
  for (int round = 0; round < 4; ++round) {
    cs.trial.assign(chosen.begin(), chosen.end());  // MinimalCone shuffles its input
    const NormalCone guess = MinimalCone(cs.trial, found);
    if (guess.empty()) return false;
    size_t outside = 0;
    if (guess.cullable()) {
      // The inside test of MinimalCone (normal_cone.cpp): a cosine slack of 1e-10.
      const double minCos = std::cos(guess.halfAngle) - 1e-10;
      const bool few = cs.eachNormal([&](const vcg::Point3d& n) {
        if (!(n * guess.axis >= minCos) && n.SquaredNorm() >= 0.5) {
          if (++outside > 256) return false;
          chosen.push_back(n);
        }
        return true;
      });
      if (!few) return false;
    }  // else some of the normals fit in no hemisphere: neither do all of them
    if (outside == 0) {
      unit(u).setCone(guess);
      if (!support_.empty()) support_[size_t(u)] = found;
      chains_[size_t(u)].exactSize = unit(u).faceCount;
      return true;
    }
  }
  return false;
}

bool HierarchyBuilder::MergeUnits(int u, int p, MergeState& ms) {
  ConeScratch& cs = ms.scratch;
  Link& lu = links_[size_t(u)];
  Link& lp = links_[size_t(p)];
  // Room for the merged list with its slack, should it not fit u's slot; made while p is alive.
  const size_t room = 2 * (size_t(lu.nbCount) + size_t(lp.nbCount));
  if (ms.chunk) {
    if (ms.arenaNext + room > ms.arenaEnd) CompactChunk(ms);
    if (ms.arenaNext + room > ms.arenaEnd) return false;
  } else if (arena_.size() + room > arena_.capacity()) {
    CompactArena(room);
  }
  // A merge is bound by memory latency: ask for every neighbour's state and geometry now, so
  // that the misses overlap each other and the cone arithmetic below.
  PrefetchUnit(p);
  Prefetch(&chains_[size_t(u)]);
  Prefetch(&chains_[size_t(p)]);
  for (const Link* src : {&lu, &lp}) {
    const Neighbour* list = arena_.data() + src->nbOffset;
    for (int i = 0; i < src->nbCount; ++i) {
      Prefetch(&links_[size_t(list[i].id)]);
      PrefetchUnit(list[i].id);
    }
  }

  Unit& a = unit(u, ms);
  Unit bAlone;
  const Unit& b = unitOf(p, bAlone, &ms);
  Chain& ac = chains_[size_t(u)];
  Chain& bc = chains_[size_t(p)];
  const NormalCone ca = a.cone(), cb = b.cone();
  // The strict order keeps UnionCone's bits; the default takes the cheaper bound (same level-1
  // partitions on the bunny and the dragon, 6% less time: docs/cone_grouping.md).
  const NormalCone merged = params_.strictGreedy ? UnionCone(ca, cb) : FastUnionCone(ca, cb);
  const bool exactA = ac.exactSize == a.faceCount, exactB = bc.exactSize == b.faceCount;
  // The union is still the exact minimal cone when it is one of two exact inputs unchanged, or
  // when an exact input cannot be culled: then neither can the union, and MinimalCone would
  // return the very same Uncullable() cone that UnionCone did.
  const bool grew = !(merged.halfAngle == ca.halfAngle && merged.axis == ca.axis) &&
                    !(merged.halfAngle == cb.halfAngle && merged.axis == cb.axis);
  const bool stillExact = (!grew && exactA && exactB) || (exactA && !ca.cullable()) || (exactB && !cb.cullable());
  a.setCone(merged);
  for (int k = 0; k < 3; ++k) a.vecArea[k] += b.vecArea[k];
  a.setSphere(UnionSphere(a.sphere(), b.sphere()));
  a.faceCount += b.faceCount;
  if (sparse_ && slot_[size_t(p)] >= 0) {  // p is dead: its slot goes to the next unit stored
    ms.freeSlots.push_back(slot_[size_t(p)]);
    slot_[size_t(p)] = -1;
  }
  // Splice the circular face lists: u's faces, then p's.
  const int headA = faceNext_[size_t(ac.tail)];
  faceNext_[size_t(ac.tail)] = faceNext_[size_t(bc.tail)];
  faceNext_[size_t(bc.tail)] = headA;
  ac.tail = bc.tail;
  bc.tail = -1;
  if (!absorbedBy_.empty()) absorbedBy_[size_t(p)] = u;
  if (!support_.empty()) {  // the support of both supports: the guess at u's next exact cone
    ConeSupport& sa = support_[size_t(u)];
    const ConeSupport& sb = support_[size_t(p)];
    cs.support.assign(sa.normal, sa.normal + sa.count);
    cs.support.insert(cs.support.end(), sb.normal, sb.normal + sb.count);
    MinimalCone(cs.support, sa);
  }
  if (stillExact)
    ac.exactSize = a.faceCount;
  else if (a.faceCount >= int64_t(exactGrowth_) * ac.exactSize)
    MakeConeExact(u, cs);  // amortized: each face O(log N) times

  // The merged unit's list: both lists without u and p, deduplicated, each pair re-scored. It
  // goes back into u's slot when it fits (a unit absorbing a small neighbour rarely gains
  // neighbours), else to the end of the arena with room to grow.
  tree_.set(p, kNoPair);
  if (!ms.chunk) --aliveCount_;  // (MergeChunks counts the chunks' merges)
  // Stamps of this merge: st, or st + 1 for a neighbour of both u and p (whose list then names
  // both: the lists are symmetric).
  ms.stamp += 2;
  const uint32_t st = ms.stamp, both = st + 1;
  lu.stamp = st;
  lp.stamp = st;
  std::vector<Neighbour>& mergedList = ms.list;
  mergedList.clear();
  for (const Link* src : {&lu, &lp}) {
    const Neighbour* list = arena_.data() + src->nbOffset;
    for (int i = 0; i < src->nbCount; ++i) {
      const int w = list[i].id;
      Link& lw = links_[size_t(w)];
      if (lw.stamp >= st) {
        if (src == &lp) lw.stamp = both;
        continue;
      }
      lw.stamp = st;
      Prefetch(arena_.data() + lw.nbOffset);  // for the update below, now that its offset is here
      tree_.prefetch(w);
      Unit wAlone;
      mergedList.push_back({w, evaluate(a, unitOf(w, wAlone, &ms))});
    }
  }
  const int count = int(mergedList.size());
  if (count > ac.capacity) {
    ac.capacity = count + count / 2;
    if (ms.chunk) {
      lu.nbOffset = uint32_t(ms.arenaNext);
      ms.arenaNext += size_t(ac.capacity);
      ms.appendLog.emplace_back(u, lu.nbOffset);
    } else {
      lu.nbOffset = uint32_t(arena_.grow(size_t(ac.capacity)));
      appendLog_.emplace_back(u, lu.nbOffset);
    }
  }
  lu.nbCount = count;
  lp.nbCount = 0;
  if (count > 0)  // an empty list may have no storage: memcpy from null is undefined even for 0 bytes
    std::memcpy(arena_.data() + lu.nbOffset, mergedList.data(), size_t(count) * sizeof(Neighbour));
  setBest(u, ms);

  // Each neighbour: its entries for u and p become one entry for u with the new score; pairs not
  // involving u are unchanged, so its best is either kept, replaced by u, or rescanned (cached).
  for (const Neighbour& e : mergedList) {
    const int w = e.id;
    const float s = e.score;
    Link& lw = links_[size_t(w)];
    Neighbour* nb = arena_.data() + lw.nbOffset;
    int n = lw.nbCount;
    // The list names u, p or both, once each: the first becomes u's entry, the second (if any)
    // gives its place to the last entry; the scan stops there.
    int k = 0;
    while (k < n && nb[k].id != u && nb[k].id != p) ++k;
    if (k < n) {
      nb[k] = {u, s};
      if (lw.stamp == both) {
        ++k;
        while (k < n && nb[k].id != u && nb[k].id != p) ++k;
        if (k < n) nb[k] = nb[--n];
      }
    }
    lw.nbCount = n;
    const int bp = lw.bestPartner;
    if (bp == u || bp == p) {
      setBest(w, ms);
    } else if (s != kNoPair && (s > tree_.key(w) || (s == tree_.key(w) && u < bp))) {
      lw.bestPartner = u;
      if (dirty_) dirty_[size_t(w)] = 1;  // (u is marked by its setBest)
      tree_.set(w, s);
    }
  }
  return true;
}

// A chunk's arena region is full: its live lists go back to its first lists' room, packed in unit
// order (they never hold more entries than the chunk's first lists did: a merge drops at least
// the pair's two entries), which leaves the region empty. The lists of the whole level stay where
// CompactArena expects them: those in the first lists' room in unit order, the others in
// appendLog_'s order.
void HierarchyBuilder::CompactChunk(MergeState& ms) {
  std::vector<Neighbour>& packed = ms.list;  // (free between merges)
  packed.clear();
  for (int u = ms.begin; u < ms.end; ++u)
    if (alive(u)) packed.insert(packed.end(), nbBegin(u), nbEnd(u));
  assert(packed.size() <= ms.listEnd - ms.listBegin);
  size_t write = ms.listBegin;
  for (int u = ms.begin; u < ms.end; ++u) {
    if (!alive(u)) continue;
    Link& l = links_[size_t(u)];
    l.nbOffset = uint32_t(write);
    chains_[size_t(u)].capacity = l.nbCount;
    write += size_t(l.nbCount);
  }
  if (!packed.empty()) std::memcpy(arena_.data() + ms.listBegin, packed.data(), packed.size() * sizeof(Neighbour));
  ms.arenaNext = ms.arenaBegin;
  ms.appendLog.clear();
}

// Level 1 before its sweeps over the whole level: the units are cut into chunks of consecutive
// units (a fixed count, from the face count: the same chunks for every thread count), and each
// chunk runs the same sweeps on its own, on the threads, merging only pairs whose units have all
// their neighbours in the chunk (inner units). Such a merge reads and writes the state of its
// chunk's units only, and the units that a neighbouring chunk could change (its units next to this
// chunk) never merge here: each chunk's merges are the same whatever ran beside it. Round 0 cuts
// at multiples of n / chunkCount_; round 1 at the middles of round 0's chunks, where the units
// that round 0 left at its cuts lie inside a chunk. What is left waits for the sweeps over the
// whole level (RunLevel), which see every unit again. Neighbouring faces of a scanned mesh have
// neighbouring indices: few units lie at a cut (docs/cone_grouping.md).
bool HierarchyBuilder::MergeChunks(int round, int minGroups, long mergesSoFar, long& merges) {
  const size_t n = unitCount();
  // Chunk c is [cut[c], cut[c + 1]): cuts at k n / (2 chunkCount_), k even in round 0, odd in 1.
  std::vector<int> cut(1, 0);
  for (size_t k = 2 - size_t(round); k < 2 * chunkCount_; k += 2) cut.push_back(int(k * n / (2 * chunkCount_)));
  cut.push_back(int(n));
  const size_t chunks = cut.size() - 1;
  std::vector<MergeState> state(chunks);
  // Per chunk: its live lists' entries.
  std::vector<size_t> entries(chunks, 0);
  ParallelChunks(chunks, threads_, 1, [&](size_t c, size_t, unsigned) {
    for (int u = cut[c]; u < cut[c + 1]; ++u)
      if (alive(u)) entries[c] += size_t(links_[size_t(u)].nbCount);
  });
  size_t total = 0;
  for (size_t c = 0; c < chunks; ++c) {
    MergeState& ms = state[c];
    ms.begin = cut[c];
    ms.end = cut[c + 1];
    ms.chunk = true;
    ms.stamp = serial_.stamp;
    ms.listBegin = total;
    total += entries[c];
    ms.listEnd = total;
  }
  // The slots freed so far go to the chunks in turn (a block each at most), the lowest first.
  for (size_t c = 0; c < chunks && !serial_.freeSlots.empty(); ++c) {
    std::vector<int>& mine = state[c].freeSlots;
    while (mine.size() < kSlotBlock && !serial_.freeSlots.empty()) {
      mine.push_back(serial_.freeSlots.back());
      serial_.freeSlots.pop_back();
    }
    std::reverse(mine.begin(), mine.end());
  }
  if (round > 0) {
    // Every list into the order of the units, each chunk's in its room [listBegin, listEnd), by
    // way of a copy: as run() made them, and as CompactArena and CompactChunk expect them.
    BigVector<Neighbour> packed(total);
    ParallelChunks(chunks, threads_, 1, [&](size_t c, size_t, unsigned) {
      size_t write = state[c].listBegin;
      for (int u = cut[c]; u < cut[c + 1]; ++u) {
        Link& l = links_[size_t(u)];
        if (!alive(u)) {
          l.nbCount = 0;
          continue;
        }
        if (l.nbCount > 0) std::memcpy(packed.data() + write, nbBegin(u), size_t(l.nbCount) * sizeof(Neighbour));
        l.nbOffset = uint32_t(write);
        chains_[size_t(u)].capacity = l.nbCount;
        write += size_t(l.nbCount);
      }
    });
    ParallelChunks(chunks, threads_, 1, [&](size_t c, size_t, unsigned) {
      const MergeState& ms = state[c];
      if (ms.listEnd > ms.listBegin)
        std::memcpy(arena_.data() + ms.listBegin, packed.data() + ms.listBegin,
                    (ms.listEnd - ms.listBegin) * sizeof(Neighbour));
    });
    prefixEnd_ = total;
    std::vector<int>().swap(arenaOrder_);
    appendLog_.clear();
  }
  assert(arenaOrder_.empty() && appendLog_.empty() && prefixEnd_ == total);
  // Each chunk's region for the lists it appends: a quarter of its lists (in the slack that run()
  // reserved).
  size_t region = total;
  for (MergeState& ms : state) {
    ms.arenaBegin = ms.arenaNext = region;
    region += (ms.listEnd - ms.listBegin) / 4 + 16;
    ms.arenaEnd = region;
  }
  assert(region <= arena_.capacity());
  BigVector<uint8_t> outer(n);  // per unit: a neighbour in another chunk
  std::atomic<long> done(0);
  std::atomic<bool> stop(false);
  std::atomic<size_t> nextChunk(0);
  auto work = [&](unsigned) {
    BigVector<Unit> singles;  // this thread's chunk's faces alone (MergeState::singles)
    for (size_t c; !stop.load(std::memory_order_relaxed) && (c = nextChunk.fetch_add(1)) < chunks;) {
      MergeState& ms = state[c];
      if (sparse_) {
        MakeSingles(ms.begin, ms.end, singles);
        ms.singles = singles.data();
      }
      int units = 0;  // alive in the chunk
      for (int u = ms.begin; u < ms.end; ++u) {
        if (!alive(u)) continue;
        ++units;
        outer[size_t(u)] = 0;
        for (const Neighbour* nb = nbBegin(u); nb != nbEnd(u); ++nb)
          if (nb->id < ms.begin || nb->id >= ms.end) {
            outer[size_t(u)] = 1;
            break;
          }
      }
      long merges = 0;
      bool room = true;
      // As RunLevel's visit, on the chunk's inner units.
      auto visit = [&](int u) {
        dirty_[size_t(u)] = 0;
        while (room && alive(u) && !outer[size_t(u)] && units > minGroups) {
          const int b = links_[size_t(u)].bestPartner;
          if (b < 0 || links_[size_t(b)].bestPartner != u || outer[size_t(b)]) break;
          room = MergeUnits(u, b, ms);
          if (!room) break;
          --units;
          if ((++merges & 0xFFF) == 0) {
            done.fetch_add(0x1000, std::memory_order_relaxed);
            if (stop.load(std::memory_order_relaxed)) room = false;
          }
        }
      };
      for (long before = -1; room && before != merges;) {
        const bool first = before < 0;
        before = merges;
        for (int u = ms.begin; room && u < ms.end; ++u) {
          if (first && u + 8 < ms.end) {
            const int ahead = links_[size_t(u) + 8].bestPartner;
            if (ahead >= 0) {
              Prefetch(&links_[size_t(ahead)]);
              PrefetchUnit(ahead);
            }
          }
          if (first || dirty_[size_t(u)]) visit(u);
        }
      }
      done.fetch_add(merges & 0xFFF, std::memory_order_relaxed);
      ms.merges = merges;
      ms.singles = nullptr;
      ms.scratch = ConeScratch();
      ms.list = std::vector<Neighbour>();
    }
  };
  if (progress_) {
    RunThreadsWhile(threads_, work, [&] {
      if (!stop.load() && !ReportProgress((mergesSoFar + merges + done.load()) & ~0x3FFFL)) stop = true;
    });
  } else {
    RunThreads(threads_, work);
  }
  if (stop.load()) return false;
  // The level goes on from here on one thread: the chunks' slots, stamps and appended lists
  // become the serial state's.
  long chunkMerges = 0;
  for (MergeState& ms : state) {
    chunkMerges += ms.merges;
    serial_.stamp = std::max(serial_.stamp, ms.stamp);
    serial_.freeSlots.insert(serial_.freeSlots.end(), ms.freeSlots.rbegin(), ms.freeSlots.rend());
    appendLog_.insert(appendLog_.end(), ms.appendLog.begin(), ms.appendLog.end());
  }
  arena_.resize(region);
  aliveCount_ -= int(chunkMerges);
  merges += chunkMerges;
  return true;
}

// Slides the live lists down over the dead ones, in arena order (no copy of the arena), and makes
// sure `room` more entries fit. The new order overwrites the old one as it is read.
void HierarchyBuilder::CompactArena(size_t room) {
  const bool identity = arenaOrder_.empty();
  if (identity) arenaOrder_.reserve(size_t(aliveCount_));
  size_t write = 0, kept = 0;
  auto slide = [&](int u) {
    Link& l = links_[size_t(u)];
    if (l.nbCount == 0) return;
    if (l.nbOffset != write)
      std::memmove(arena_.data() + write, arena_.data() + l.nbOffset, size_t(l.nbCount) * sizeof(Neighbour));
    l.nbOffset = uint32_t(write);
    chains_[size_t(u)].capacity = l.nbCount;
    write += size_t(l.nbCount);
    if (kept < arenaOrder_.size())
      arenaOrder_[kept] = u;
    else
      arenaOrder_.push_back(u);
    ++kept;
  };
  auto inPrefix = [&](int u) { return alive(u) && links_[size_t(u)].nbOffset < prefixEnd_; };
  if (identity) {
    for (int u = 0; u < int(unitCount()); ++u)
      if (inPrefix(u)) slide(u);
  } else {
    const size_t oldCount = arenaOrder_.size();
    for (size_t i = 0; i < oldCount; ++i)
      if (inPrefix(arenaOrder_[i])) slide(arenaOrder_[i]);
  }
  for (const auto& e : appendLog_)
    if (alive(e.first) && links_[size_t(e.first)].nbOffset == e.second) slide(e.first);
  arenaOrder_.resize(kept);
  arena_.resize(write);
  prefixEnd_ = write;
  appendLog_.clear();
  if (write + room > arena_.capacity()) arena_.reserve(write + room + write / 2);
}

bool HierarchyBuilder::ReportProgress(long mergesSoFar) {
  if ((mergesSoFar & 0x3FFF) != 0 || !progress_) return true;
  const int pct = int(95.0 * double(mergesSoFar) / std::max(1, faceCount_ - 1));
  if (progress_(std::min(95, pct), "grouping faces by normal cones")) return true;
  cancelled_ = true;
  return false;
}

bool HierarchyBuilder::RunLevel(double thresholdDeg, bool localMaximaFirst, long& mergesSoFar) {
  setThreshold(thresholdDeg);
  const size_t n = unitCount();
  aliveCount_ = int(n);
  serial_.stamp = 0;
  serial_.begin = 0;
  serial_.end = int(n);
  tree_.reset(n);
  // Every pair is scored from both of its units in strict mode (the former arithmetic, bit for
  // bit); else once, from its lower unit, which writes the score into the higher unit's entry
  // too (kUnscored marks the entries still to score).
  const bool scoreOnce = !params_.strictGreedy;
  constexpr size_t kAhead = 16;       // units ahead whose neighbours' data is asked for (then lists at half)
  const bool prefetch = !prescored_;  // nothing to evaluate when run() scored the pairs already
  if (prescored_) {                   // each unit reads its own list and writes its own state: on the threads
    ParallelChunks(n, threads_, kFaceChunk, [&](size_t begin, size_t end, unsigned) {
      for (size_t u = begin; u < end; ++u) {
        links_[u].stamp = 0;
        int64_t top = kNoEntry;
        for (const Neighbour* nb = nbBegin(int(u)); nb != nbEnd(int(u)); ++nb) top = std::max(top, PairEntry(*nb));
        float best;
        BestPair(top, best, links_[u].bestPartner);
        tree_.setKey(int(u), best);
      }
    });
  }
  for (size_t u = 0; !prescored_ && u < n; ++u) {
    if (prefetch && u + kAhead < n)
      for (const Neighbour* nb = nbBegin(int(u + kAhead)); nb != nbEnd(int(u + kAhead)); ++nb) {
        PrefetchUnit(nb->id);
        Prefetch(&links_[size_t(nb->id)]);
      }
    if (prefetch && scoreOnce && u + kAhead / 2 < n)
      for (const Neighbour* nb = nbBegin(int(u + kAhead / 2)); nb != nbEnd(int(u + kAhead / 2)); ++nb)
        if (size_t(nb->id) > u) Prefetch(nbBegin(nb->id));
    Link& l = links_[u];
    l.stamp = 0;
    float best = kNoPair;
    int partner = -1;
    for (Neighbour* nb = nbBegin(int(u)); nb != nbEnd(int(u)); ++nb) {
      Unit uAlone, wAlone;
      if (!scoreOnce) {
        nb->score = evaluate(unitOf(int(u), uAlone), unitOf(nb->id, wAlone));
      } else if (std::isnan(nb->score)) {
        nb->score = evaluate(unitOf(int(u), uAlone), unitOf(nb->id, wAlone));
        // The higher unit has not chosen its best yet: its entry takes the score too.
        if (size_t(nb->id) > u) setEntryScore(nb->id, int(u), nb->score);
      }
      if (nb->score > best || (nb->score == best && nb->score != kNoPair && nb->id < partner)) {
        best = nb->score;
        partner = nb->id;
      }
    }
    l.bestPartner = partner;
    tree_.setKey(int(u), best);
  }
  const int minGroups = MinTopGroups();
  long merges = 0;
  if (localMaximaFirst) {
    // Sweeps in unit order merge every pair that is the best pair of both its units (a local
    // maximum of v: the global order would merge it too, unless a better pair next to it changed
    // first), the merged unit going on while its best pair stays mutual; until a sweep merges
    // nothing. Neighbouring units have neighbouring indices, so a sweep walks the mesh's memory
    // in order where the global order jumps all over it. The tree is not kept meanwhile.
    //
    // After the first sweep, a sweep visits only the units marked since their last visit (dirty_):
    // a unit whose best partner was set, and that partner. A unit left without a mutual pair by
    // its visit only gets one when its best partner or its partner's becomes the other, which
    // marks both; so every unit that a full sweep would find mutual is marked when the sweep
    // reaches it (a mark ahead of the sweep is seen in the same sweep, one behind in the next),
    // and the merges, in the same order, are the same as a full sweep's.
    tree_.setDeferred(true);
    const size_t padded = (n + 7) / 8 * 8;
    BigVector<uint8_t> dirty(padded, 0);
    dirty_ = dirty.data();
    StageLog::Laps stages;
    if (chunkCount_ >= 2 && sparse_ &&
        !(MergeChunks(0, minGroups, mergesSoFar, merges) && MergeChunks(1, minGroups, mergesSoFar, merges))) {
      dirty_ = nullptr;
      return false;
    }
    if (chunkCount_ >= 2 && sparse_) stages.Mark("grouping: level 1's chunks");
    // Merges u while its best pair is mutual; false: cancelled.
    auto visit = [&](int u) {
      dirty_[size_t(u)] = 0;
      while (alive(u) && aliveCount_ > minGroups) {
        const int b = links_[size_t(u)].bestPartner;
        if (b < 0 || links_[size_t(b)].bestPartner != u) break;
        MergeUnits(u, b, serial_);
        ++merges;
        if (!ReportProgress(mergesSoFar + merges)) return false;
      }
      return true;
    };
    bool ok = true;
    for (long before = -1; ok && before != merges && aliveCount_ > minGroups;) {
      const bool first = before < 0;
      before = merges;
      if (first) {
        for (int u = 0; ok && u < int(n) && aliveCount_ > minGroups; ++u) {
          // Whether u's best pair is mutual reads its partner's link, scattered: asked for 8 units
          // ahead (with the partner's unit, which the merge reads first).
          if (u + 8 < int(n)) {
            const int ahead = links_[size_t(u) + 8].bestPartner;
            if (ahead >= 0) {
              Prefetch(&links_[size_t(ahead)]);
              PrefetchUnit(ahead);
            }
          }
          ok = visit(u);
        }
      } else {
        for (size_t w = 0; ok && w < padded && aliveCount_ > minGroups; w += 8) {
          uint64_t word;
          std::memcpy(&word, dirty_ + w, sizeof word);
          if (word == 0) continue;
          for (size_t u = w; ok && u < w + 8 && aliveCount_ > minGroups; ++u)
            if (dirty_[u]) ok = visit(int(u));
        }
      }
    }
    dirty_ = nullptr;
    if (!ok) return false;
    tree_.setDeferred(false);
    stages.Mark("grouping: sweeps");
  }
  // Best pair first over the whole level: all of it in strict mode, else what the sweeps leave
  // (pairs whose exact ties form cycles, so that none is mutual).
  tree_.build();
  while (!tree_.empty() && aliveCount_ > minGroups) {
    const int u = tree_.top();
    MergeUnits(u, links_[size_t(u)].bestPartner, serial_);
    ++merges;
    if (!ReportProgress(mergesSoFar + merges)) return false;
  }
  mergesSoFar += merges;
  return merges > 0;
}

void HierarchyBuilder::EmitLevel(double thresholdDeg, GroupHierarchy& out, bool firstLevel) {
  const size_t n = unitCount();
  GroupLevel level;
  level.thresholdDeg = thresholdDeg;
  level.faceGroup.resize(size_t(faceCount_));
  std::vector<int>& faceGroup = level.faceGroup;
  // Ids in order of first appearance over faces: deterministic and cache-friendly.
  idOfUnit_.assign(n, -1);
  rootOfGroup_.clear();
  // Above level 1: the group of every previous group (the units this level started with).
  std::vector<int> childGroupAbove;
  if (firstLevel) {
    // The unit of every face, from the live units' face lists.
    for (int u = 0; u < int(n); ++u) {
      if (!alive(u)) continue;
      const int tail = chains_[size_t(u)].tail;
      int f = tail;
      do {
        f = faceNext_[size_t(f)];
        faceGroup[size_t(meshFace(f))] = u;
      } while (f != tail);
    }
    for (int& g : faceGroup) {
      int& id = idOfUnit_[size_t(g)];
      if (id < 0) {
        id = int(rootOfGroup_.size());
        rootOfGroup_.push_back(g);
      }
      g = id;
    }
  } else {
    // Every face lies in one level-1 group, and level 1's ids follow the faces' order: a unit's
    // first face is the first face of its lowest level-1 group, so taking the level-1 groups in
    // order gives the same ids as the faces would, with one lookup per level-1 group. A unit
    // (a previous group) is found through the units that absorbed it (absorbedBy_).
    for (int u = 0; u < int(n); ++u) {
      int r = u;
      while (!alive(r)) r = absorbedBy_[size_t(r)];
      absorbedBy_[size_t(u)] = r;  // from now on: u's live unit (followed by the units after u)
    }
    childGroupAbove.resize(n);
    for (int& g : l1Group_) {  // the previous level's group -> this level's
      const int u = absorbedBy_[size_t(g)];
      int& id = idOfUnit_[size_t(u)];
      if (id < 0) {
        id = int(rootOfGroup_.size());
        rootOfGroup_.push_back(u);
      }
      childGroupAbove[size_t(g)] = id;
      g = id;
    }
    const std::vector<int>& level1Group = out.levels.front().faceGroup;
    for (size_t f = 0; f < size_t(faceCount_); ++f) faceGroup[f] = l1Group_[size_t(level1Group[f])];
  }
  const size_t groupCount = rootOfGroup_.size();
  {
    // Level 1's arrays, freed by nextLevelUnits, become the renumbered faces' arrays below instead
    // of fresh memory (BigRecycler); the rest is unmapped at the end of this scope.
    std::unique_ptr<BigRecycler> recycler(firstLevel ? new BigRecycler : nullptr);
    // The groups become the units of the next level now, indexed by group: the arrays of this
    // level go before the level's output grows.
    nextLevelUnits();
    // Renumbered now, the exact cones below read the normals in memory order, computed once for
    // this level and the next ones (the level-1 merges read them rounded, or from the mesh).
    if (firstLevel) RenumberFaces();
  }
  if (firstLevel && !params_.strictGreedy) support_.assign(groupCount, ConeSupport());
  level.groups.resize(groupCount);

  // Children: faces (level 1) or previous groups, bucketed by new group. A previous group's new
  // group is that of any of its faces.
  const size_t childTotal = firstLevel ? size_t(faceCount_) : n;
  const std::vector<int>& childGroup = firstLevel ? faceGroup : childGroupAbove;
  std::vector<int> childCount(groupCount, 0);
  for (size_t c = 0; c < childTotal; ++c) ++childCount[size_t(childGroup[c])];
  int running = 0;
  for (size_t g = 0; g < groupCount; ++g) {
    level.groups[g].firstChild = running;
    level.groups[g].childCount = childCount[g];
    running += childCount[g];
  }
  level.children.resize(childTotal);
  {
    std::vector<int>& fill = childCount;
    for (size_t g = 0; g < groupCount; ++g) fill[g] = level.groups[g].firstChild;
    for (size_t c = 0; c < childTotal; ++c) level.children[size_t(fill[size_t(childGroup[c])]++)] = int(c);
  }
  if (!firstLevel) {
    auto& prev = out.levels.back().groups;
    for (size_t c = 0; c < childTotal; ++c) prev[c].parent = childGroup[c];
  }

  // Exact cones; boxes from the vertices at level 1, from the children's boxes above (min and
  // max do not depend on the order, but for the sign of a zero); tight spheres from the
  // vertices, in face order (which reads the mesh sequentially).
  // Each group's cone depends on its own faces only, and each group writes only its own unit,
  // chain and support: the groups are shared among the threads, each with its scratch.
  std::vector<ConeScratch> threadScratch(threads_);
  ParallelChunks(groupCount, threads_, kGroupChunk, [&](size_t begin, size_t end, unsigned thread) {
    ConeScratch& cs = threadScratch[thread];
    for (size_t g = begin; g < end; ++g) {
      if (chains_[g].exactSize != units_[g].faceCount || (firstLevel && !support_.empty())) MakeConeExact(int(g), cs);
      Group& grp = level.groups[g];
      grp.cone = units_[g].cone();
      grp.faceCount = units_[g].faceCount;
      grp.box.SetNull();
      if (firstLevel)
        for (uint32_t i = l1VertBegin_[g]; i < l1VertBegin_[g + 1]; ++i) grp.box.Add(l1Verts_[i]);
    }
  });
  std::vector<ConeScratch>().swap(threadScratch);
  if (!firstLevel) {
    const auto& prev = out.levels.back().groups;
    for (size_t c = 0; c < childTotal; ++c) level.groups[size_t(childGroup[c])].box.Add(prev[c].box);
  }
  // Where a bound is zero, +0 or -0 is whichever came first: take the vertices in the order of the
  // group's face list then, the order that defines the result.
  for (size_t g = 0; g < groupCount; ++g) {
    vcg::Box3f& box = level.groups[g].box;
    bool zero = false;
    for (int k = 0; k < 3; ++k) zero = zero || box.min[k] == 0 || box.max[k] == 0;
    if (!zero) continue;
    box.SetNull();
    const int tail = chains_[g].tail;
    int f = tail;
    do {
      f = faceNext_[size_t(f)];
      for (uint32_t v : mesh_.faces[size_t(meshFace(f))]) box.Add(mesh_.positions[v]);
    } while (f != tail);
  }
  // A second sphere around the box centre; keep the smaller of it and the merged bound.
  std::vector<vcg::Point3d> boxCenter(groupCount);
  for (size_t g = 0; g < groupCount; ++g) boxCenter[g] = vcg::Point3d::Construct(level.groups[g].box.Center());
  // The largest squared distance from the centre to a vertex: over each level-1 group's distinct
  // vertices (a maximum of non-negative numbers: the same whatever the order).
  std::vector<double> r2(groupCount, 0.0);
  for (size_t g1 = 0; g1 < l1Group_.size(); ++g1) {
    const size_t g = size_t(l1Group_[g1]);
    const vcg::Point3d c = boxCenter[g];
    double m = r2[g];
    for (uint32_t i = l1VertBegin_[g1]; i < l1VertBegin_[g1 + 1]; ++i)
      m = std::max(m, (vcg::Point3d::Construct(l1Verts_[i]) - c).SquaredNorm());
    r2[g] = m;
  }
  for (size_t g = 0; g < groupCount; ++g) {
    Unit& unit = units_[g];
    const double r = std::sqrt(r2[g]) * scale_;
    if (r < unit.radius) unit.setSphere(Sphere{boxCenter[g] * scale_, r});
    const double inv = 1 / scale_;
    level.groups[g].center =
        vcg::Point3f(float(unit.center[0] * inv), float(unit.center[1] * inv), float(unit.center[2] * inv));
    level.groups[g].radius = float(unit.radius * inv);
  }
  out.levels.push_back(std::move(level));
}

// After level 1: faces renumbered group by group, each group's in the order of its list (so the
// normals' order, which MinimalCone's last bits depend on, is unchanged), with their normals and
// areas; and, in the same pass over the faces, each level-1 group's distinct vertices (l1Verts_).
void HierarchyBuilder::RenumberFaces() {
  const size_t nf = size_t(faceCount_);
  const size_t groups = units_.size();  // the units are the level's groups, all alive
  meshFace_.resize(nf);
  size_t next = 0;
  for (size_t g = 0; g < groups; ++g) {
    const int tail = chains_[g].tail;
    int f = tail;
    do {
      f = faceNext_[size_t(f)];
      meshFace_[next++] = f;
    } while (f != tail);
  }
  assert(next == nf);
  next = 0;
  for (size_t g = 0; g < groups; ++g) {
    const size_t first = next, end = next + size_t(units_[g].faceCount);
    for (; next + 1 < end; ++next) faceNext_[next] = int(next + 1);
    faceNext_[next] = int(first);
    chains_[g].tail = int(next++);
  }
  faceNormal_.resize(nf);
  faceArea_.resize(nf);
  // The normals and areas first, on every thread (face f writes its own normal and the area of
  // its own mesh face); then the vertices, in group order, on one.
  ParallelChunks(nf, threads_, kFaceChunk, [&](size_t begin, size_t end, unsigned) {
    double faceArea;
    for (size_t f = begin; f < end; ++f) {
      if (f + 8 < end) Prefetch(&mesh_.faces[size_t(meshFace_[f + 8])]);
      if (f + 4 < end)
        for (const uint32_t v : mesh_.faces[size_t(meshFace_[f + 4])]) Prefetch(&mesh_.positions[v]);
      const size_t mf = size_t(meshFace_[f]);
      FaceNormalAndArea(mesh_, mf, faceNormal_[f], faceArea);
      faceArea_[mf] = faceArea;
    }
  });
  BigVector<int> seen(mesh_.positions.size(), -1);  // the last group that took the vertex
  l1VertBegin_.resize(groups + 1);
  l1Group_.resize(groups);
  l1Verts_.clear();
  l1Verts_.reserve(mesh_.positions.size() + mesh_.positions.size() / 2);
  size_t f = 0;  // group g's faces are the run of its faceCount faces after group g-1's
  for (size_t g = 0; g < groups; ++g) {
    l1VertBegin_[g] = uint32_t(l1Verts_.size());
    l1Group_[g] = int(g);
    for (const size_t end = f + size_t(units_[g].faceCount); f < end; ++f) {
      // The mesh is read in group order, scattered: its faces and vertices asked for ahead.
      if (f + 8 < nf) Prefetch(&mesh_.faces[size_t(meshFace_[f + 8])]);
      if (f + 4 < nf)
        for (const uint32_t v : mesh_.faces[size_t(meshFace_[f + 4])]) {
          Prefetch(&mesh_.positions[v]);
          Prefetch(&seen[v]);
        }
      const size_t mf = size_t(meshFace_[f]);
      for (const uint32_t v : mesh_.faces[mf])
        if (seen[v] != int(g)) {
          seen[v] = int(g);
          l1Verts_.push_back(mesh_.positions[v]);
        }
    }
  }
  l1VertBegin_[groups] = uint32_t(l1Verts_.size());
}

// The groups found by EmitLevel (rootOfGroup_, idOfUnit_) become the units of the next level
// (their lists already name live units only); this level's arrays are released.
void HierarchyBuilder::nextLevelUnits() {
  const size_t g = rootOfGroup_.size();
  BigVector<Unit> units(g);
  BigVector<Link> links(g);
  BigVector<Chain> chains(g);
  size_t entries = 0;
  for (size_t id = 0; id < g; ++id) entries += size_t(links_[size_t(rootOfGroup_[id])].nbCount);
  Arena arena;
  arena.reserve(2 * entries + 16);
  for (size_t id = 0; id < g; ++id) {
    const int u = rootOfGroup_[id];
    Unit alone;
    units[id] = unitOf(u, alone);
    chains[id] = chains_[size_t(u)];
    const int count = links_[size_t(u)].nbCount;
    links[id] = Link{-1, uint32_t(arena.grow(size_t(count))), count, 0};
    chains[id].capacity = count;
    Neighbour* list = arena.data() + links[id].nbOffset;
    for (const Neighbour* w = nbBegin(u); w != nbEnd(u); ++w) *list++ = {idOfUnit_[size_t(w->id)], kUnscored};
  }
  if (!support_.empty()) {
    BigVector<ConeSupport> support(g);
    for (size_t id = 0; id < g; ++id) support[id] = support_[size_t(rootOfGroup_[id])];
    support_.swap(support);
  }
  units_.swap(units);
  sparse_ = false;
  BigVector<int>().swap(slot_);
  BigVector<Unit>().swap(pool_);
  serial_.freeSlots = std::vector<int>();
  links_.swap(links);
  chains_.swap(chains);
  absorbedBy_.resize(g);
  arena_.swap(arena);
  prefixEnd_ = arena_.size();
  std::vector<int>().swap(arenaOrder_);
  std::vector<std::pair<int, uint32_t>>().swap(appendLog_);
  std::vector<int>().swap(idOfUnit_);
  tree_.release();
}

Status HierarchyBuilder::run(GroupHierarchy& out) {
  StageLog::Laps stages;  // CONELOD_STAGES: one line per stage on stderr
  const int nf = faceCount_;
  // At most kMaxChunks chunks: a chunk of consecutive faces is a strip of the scan, and on a big
  // one a thin strip, most of whose units touch another chunk and are left to the serial sweeps
  // (13.94 M faces in chunks of 50,000: 3.2 s of chunks, then 11.5 s of sweeps on one thread).
  constexpr size_t kMaxChunks = 64;  // enough for 16 threads
  chunkCount_ = 0;
  if (!params_.strictGreedy && params_.chunkFaces > 0)
    chunkCount_ = size_t(nf) / std::max(size_t(params_.chunkFaces), size_t(nf) / kMaxChunks);
  if (chunkCount_ < 2) chunkCount_ = 0;
  // Adjacency first, while nothing else is allocated: it is the largest temporary. Its arrays,
  // freed once level 1's lists are made, become level 1's arena, face lists and chains instead of
  // fresh memory (BigRecycler); what is left is unmapped before the merges.
  {
    BigRecycler recycler;
    // The lists, from the caller's adjacency or from one built here (the same lists).
    auto makeLists = [&](const uint32_t* offsets, const uint32_t* neighbours, size_t count) {
      if (count > size_t(std::numeric_limits<uint32_t>::max() / 2)) throw std::bad_alloc();  // list offsets are 32-bit
      // The arena's high-water mark is what it costs in memory: a quarter of slack, no more.
      // (The chunks' regions, MergeChunks, fit in the slack.)
      arena_.reserve(count + count / 4 + 16 * (chunkCount_ + 2));
      Neighbour* list = arena_.data() + arena_.grow(count);
      for (size_t i = 0; i < count; ++i) *list++ = {int(neighbours[i]), kUnscored};
      links_.resize(size_t(nf));
      for (int f = 0; f < nf; ++f)
        links_[size_t(f)] = Link{-1, offsets[size_t(f)], int(offsets[size_t(f) + 1] - offsets[size_t(f)]), 0};
      prefixEnd_ = arena_.size();
    };
    if (adjacency_) {
      makeLists(adjacency_->offsets.data(), adjacency_->neighbours.data(), adjacency_->neighbours.size());
    } else {
      BigVector<uint32_t> offsets, neighbours;
      size_t borderEdges, nonManifoldEdges;
      BuildFaceAdjacencyInto(mesh_, offsets, neighbours, borderEdges, nonManifoldEdges, threads_);
      makeLists(offsets.data(), neighbours.data(), neighbours.size());
    }
    faceNext_.resize(size_t(nf));
    sparse_ = !params_.strictGreedy;
    if (sparse_)
      slot_.assign(size_t(nf), -1);
    else
      units_.resize(size_t(nf));
    chains_.resize(size_t(nf));
    l1Rounded_ = !params_.strictGreedy;
  }
  stages.Mark("grouping: adjacency, lists");

  // Level-1 units: one per face. In the default mode each pair is scored once, from its lower
  // unit (RunLevel); here already, as soon as both units are made.
  const bool scoreNow = !params_.strictGreedy;
  if (sparse_) {  // mapped: only the slots used take memory
    // A slot is taken for a face alone that merges (it never is one again), so at most nf are,
    // plus the fresh blocks in the hands of the MergeStates (the serial one, the chunks of both
    // rounds). Mapped: only the slots used take memory, and those are packed at the start.
    pool_.resize(size_t(nf) + (2 * chunkCount_ + 2) * kSlotBlock);
    freshSlots_ = 0;
  }
  if (scoreNow) setThreshold(std::min(params_.coneThresholdDeg, 180.0));
  prescored_ = scoreNow;
  // Each face makes its own unit (on every thread; in the default mode none is stored: see
  // sparse_), then scores its pairs with the faces before it, as RunLevel would score them (from
  // the lower unit), writing the score into both lists: each entry is written by one face only,
  // with the same arithmetic whatever the thread.
  ParallelChunks(size_t(nf), threads_, kFaceChunk, [&](size_t begin, size_t end, unsigned) {
    for (int f = int(begin); f < int(end); ++f) {
      if (!sparse_) SingleUnit(f, units_[size_t(f)]);
      faceNext_[size_t(f)] = f;
      chains_[size_t(f)] = Chain{f, 1, links_[size_t(f)].nbCount};
    }
  });
  if (scoreNow) {
    // Sparse: a block's faces alone are made once, and read from there by the pairs within it
    // (most pairs: neighbouring faces of a scan have neighbouring indices).
    ParallelItems<BigVector<Unit>>(
        (size_t(nf) + kFaceChunk - 1) / kFaceChunk, threads_, [&](size_t item, BigVector<Unit>& block) {
          const int begin = int(item * kFaceChunk), end = int(std::min(size_t(nf), (item + 1) * kFaceChunk));
          if (sparse_) MakeSingles(begin, end, block);
          for (int f = begin; f < end; ++f) {
            Unit uAlone, wAlone;
            const Unit& u = sparse_ ? block[size_t(f - begin)] : unitOf(f, uAlone);
            for (Neighbour* nb = nbBegin(f); nb != nbEnd(f); ++nb) {
              const int w = nb->id;
              if (w >= f) continue;
              nb->score = evaluate(sparse_ && w >= begin ? block[size_t(w - begin)] : unitOf(w, wAlone), u);
              setEntryScore(w, f, nb->score);
            }
          }
        });
  }
  if (progress_ && !progress_(0, "grouping faces by normal cones")) return Status::Cancelled();
  stages.Mark("grouping: units, first scores");

  long merges = 0;
  double threshold = params_.coneThresholdDeg;
  for (int level = 1; level <= params_.maxLevels; ++level) {
    // Level 1 (default mode) refreshes its cones at every 8-fold growth: each refresh walks the
    // unit's face list for its normals (a tenth of the build at every 4-fold growth; 8-fold reads
    // a quarter fewer normals); the looser bounds leave 1-3% more level-1 groups, culling as well
    // (docs/cone_grouping.md). Above it a refresh costs about one scan (support_).
    exactGrowth_ = params_.strictGreedy ? 2 : (level == 1 ? 8 : 4);
    const bool merged = RunLevel(std::min(threshold, 180.0), level == 1 && !params_.strictGreedy, merges);
    stages.Mark("grouping: merges", level);
    prescored_ = false;
    l1Rounded_ = false;
    tree_.release();  // (the emission reads no score: its arrays go before the level's output grows)
    if (cancelled_) {
      out = GroupHierarchy();
      return Status::Cancelled();
    }
    if (!merged && level > 1) break;  // nothing changed: the previous level is the top
    EmitLevel(std::min(threshold, 180.0), out, level == 1);
    stages.Mark("grouping: level out", level);
    if (int(out.levels.back().groups.size()) <= MinTopGroups()) break;
    if (level == params_.maxLevels) break;
    if (params_.autoTargetFaces > 0 &&
        out.levels.back().groups.size() * size_t(kAutoFacesPerGroup) <= params_.autoTargetFaces)
      break;  // AutoGroupLevel's level: the ones above are not needed
    threshold *= params_.thresholdGrowth;
  }

  // Areas per group, from the faces' areas (RenumberFaces) in face order: the same sums on every
  // run. Level by level: each group's sum still takes its faces in face order.
  ParallelChunks(out.levels.size(), threads_, 1, [&](size_t begin, size_t end, unsigned) {
    for (size_t l = begin; l < end; ++l) {  // one level per piece of work: each its own sums
      Group* groups = out.levels[l].groups.data();
      const int* faceGroup = out.levels[l].faceGroup.data();
      for (size_t f = 0; f < size_t(nf); ++f) groups[faceGroup[f]].area += faceArea_[f];
    }
  });
  out.faceCount = nf;
  if (progress_ && !progress_(100, "grouping done")) {
    out = GroupHierarchy();
    return Status::Cancelled();
  }
  return Status::Ok();
}

}  // namespace

std::vector<char> LevelsAreEdgeConnected(const FaceAdjacency& adj, const GroupHierarchy& h) {
  std::vector<char> connected(size_t(h.levelCount()), 0);
  if (h.levelCount() == 0) return connected;
  const std::vector<int>& g1 = h.level(1).faceGroup;
  connected[0] = GroupsAreEdgeConnected(adj, g1) ? 1 : 0;
  const size_t nf = g1.size();
  int groups1 = 0;
  for (const int g : g1) groups1 = std::max(groups1, g + 1);
  bool graphUsable = connected[0] && adj.offsets.size() == nf + 1;
  for (const int g : g1) graphUsable &= g >= 0;
  // The graph of level 1's groups: an edge where faces of two groups share an edge.
  FaceAdjacency graph;
  if (graphUsable) {
    std::vector<std::pair<uint32_t, uint32_t>> pairs;
    for (size_t f = 0; f < nf; ++f)
      for (uint32_t i = adj.offsets[f]; i < adj.offsets[f + 1]; ++i) {
        const int a = g1[f], b = g1[adj.neighbours[i]];
        if (a != b) pairs.emplace_back(uint32_t(a), uint32_t(b));  // both ways: the lists are symmetric
      }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    graph.offsets.assign(size_t(groups1) + 1, 0);
    for (const auto& e : pairs) ++graph.offsets[e.first + 1];
    for (size_t g = 0; g < size_t(groups1); ++g) graph.offsets[g + 1] += graph.offsets[g];
    graph.neighbours.reserve(pairs.size());
    for (const auto& e : pairs) graph.neighbours.push_back(e.second);
  }
  std::vector<int> label(static_cast<size_t>(groups1));
  for (int l = 2; l <= h.levelCount(); ++l) {
    const std::vector<int>& gl = h.level(l).faceGroup;
    // Each level-1 group's group at this level, when all its faces have the same one.
    bool nested = graphUsable && gl.size() == nf;
    if (nested) {
      std::fill(label.begin(), label.end(), -1);
      for (size_t f = 0; f < nf && nested; ++f) {
        int& x = label[size_t(g1[f])];
        if (x < 0) x = gl[f];
        nested = x == gl[f] && gl[f] >= 0;
      }
    }
    connected[size_t(l - 1)] =
        (nested ? GroupsAreEdgeConnected(graph, label) : GroupsAreEdgeConnected(adj, gl)) ? 1 : 0;
  }
  return connected;
}

int AutoGroupLevel(const GroupHierarchy& h, size_t targetFaces) {
  for (int k = 1; k <= h.levelCount(); ++k)
    if (h.level(k).groups.size() * size_t(kAutoFacesPerGroup) <= targetFaces) return k;
  return h.levelCount();
}

std::vector<NormalCone> LevelConeBounds(const GroupHierarchy& h, int level) {
  std::vector<NormalCone> bounds;
  if (level < 1 || level > h.levelCount()) return bounds;
  const GroupLevel& L = h.level(level);
  const double limit = std::min(L.thresholdDeg, 180.0) * NormalCone::kPi / 180;
  for (const Group& g : L.groups) {
    NormalCone c;
    c.axis = g.cone.axis;
    c.halfAngle = g.cone.empty() ? -1 : std::max(limit, g.cone.halfAngle);
    bounds.push_back(c);
  }
  return bounds;
}

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

ConeGroupingParams CollapseGroupingParams(size_t targetFaces, bool automatic, int threads) {
  ConeGroupingParams p;
  p.chunkFaces = kGroupingChunkFaces;
  p.threads = threads;
  if (automatic) p.autoTargetFaces = targetFaces;
  return p;
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
  if (p.threads < 0 || p.threads > 1024) return Status::Invalid("threads must be from 0 (one per core) to 1024");
  if (p.chunkFaces < 0) return Status::Invalid("chunkFaces must be >= 0 (0: no chunks)");
  return Status::Ok();
}

Status BuildConeHierarchy(const IndexedMesh& mesh, const ConeGroupingParams& params, GroupHierarchy& out,
                          const Progress& progress, const FaceAdjacency* adjacency) {
  out = GroupHierarchy();
  Status s = ValidateParams(params);
  if (!s.ok()) return s;
  s = RequireValidForFaces(mesh);
  if (!s.ok()) return s;
  if (mesh.faces.size() >= size_t(std::numeric_limits<int>::max()) / 4)
    return Status::Invalid("the mesh has too many faces for 32-bit group ids");
  try {
    if (adjacency && adjacency->offsets.size() != mesh.faces.size() + 1)
      return Status::Invalid("the face adjacency given is not the mesh's");
    HierarchyBuilder builder(mesh, params, progress, adjacency);
    return builder.run(out);
  } catch (const std::bad_alloc&) {
    out = GroupHierarchy();
    return Status::OutOfMemory("not enough memory to group " + std::to_string(mesh.faces.size()) + " faces");
  }
}

}  // namespace conelod
