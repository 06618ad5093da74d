// ConeLOD — building the crack-free cluster DAG of the .clod file (lod_build.h).
//
// Karis et al., "Nanite: a deep dive" (SIGGRAPH 2021 course), with the clusters of Kamiya, Suzuki,
// Kawachi (normal-cone groups, so every node keeps a tight cone for back-face culling):
//   1. level 0: the input cut into clusters of about clusterFaces faces whose normals stay within
//      a cone (region growing from a seed face, the cone limit growing level by level);
//   2. neighbouring clusters (sharing the most edges) are gathered into groups of groupClusters
//      (fineGroupClusters on the fine levels, topGroupClusters on the top ones: GroupClustersOf);
//      below the top levels a group left under half of that joins a neighbouring group
//      (MergeSmallGroups), so that fewer of the level's faces lie on locked borders;
//   3. each group is simplified on its own to levelRatio of its faces (at least coarseLevelRatio
//      on the levels of at most 3/8 of the input's faces: LevelRatioOf) by the group-preserving
//      collapse (group_qem.h) with every vertex it shares with another group frozen
//      (GroupQemRegion): its outer border keeps its vertices, ids and positions bit for bit;
//      no collapse costs more than maxGroupError of the diagonal, so a group whose locked border
//      leaves no cheap collapse stops short of the ratio instead of folding;
//   4. the simplified group is re-cut into clusters (step 1 on its faces): the next level;
//   5. repeat from 2 until one cluster is left or a level no longer shrinks; the top levels
//      simplify each small connected part as one group, with nothing locked (BuildLodDag).
// A group's error is the largest distance from its vertices (before) to its simplified faces plus
// the largest error of its clusters: monotonic up the DAG, in model units. Groups are simplified
// side by side on several threads; the result does not depend on their number.
// In spatial chunks (LodBuildParams::chunkFaces, `lod build --memory`; docs/scale.md): the faces
// are split into kd chunks, step 1 runs on each chunk (side by side) and step 2 gathers only
// clusters of one chunk, so a chunk's border is locked; the chunks of level k are the kd nodes
// one depth up from those of level k - 1 (two siblings merge, freeing their common border), and
// each time a level no longer shrinks under the locked borders the chunks merge one depth more
// (for that level and the rest of the build).
#include "conelod/lod/lod_build.h"
#include "conelod/lod/lod_spill.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numeric>
#include <queue>
#include <unordered_map>

#include "conelod/common.h"
#include "conelod/parallel.h"
#include "conelod/mesh/mesh_check.h"
#include "conelod/simplify/attribute_quadric.h"
#include "conelod/stage_log.h"

namespace conelod {
namespace {

using Face = std::array<uint32_t, 3>;
constexpr uint32_t kNoPlace = 0xFFFFFFFFu;

// A map of uint32 keys (below 2^32 - 1) to uint32 values, open addressing with linear probing in
// one table that doubles when half full (SimplifyGroup's id tables: a few allocations, not one
// per key as a std::unordered_map makes; `expected` keys fit the first table).
class IdMap {
 public:
  explicit IdMap(size_t expected) {
    int bits = 4;
    while ((size_t(1) << bits) < 2 * expected) ++bits;
    Allocate(bits);
  }
  // {the key's value, true} after storing `value` for a new key; {its value, false} for a known one.
  std::pair<uint32_t, bool> Emplace(uint32_t key, uint32_t value) {
    const size_t mask = slots_.size() - 1;
    for (size_t h = Home(key);; h = (h + 1) & mask) {
      const uint64_t s = slots_[h];
      if (s == kEmpty) {
        slots_[h] = uint64_t(key) << 32 | value;
        if (2 * ++count_ > slots_.size()) Grow();
        return {value, true};
      }
      if (uint32_t(s >> 32) == key) return {uint32_t(s), false};
    }
  }

 private:
  static constexpr uint64_t kEmpty = ~uint64_t(0);
  size_t Home(uint32_t key) const { return size_t((uint64_t(key) * 0x9E3779B97F4A7C15ull) >> shift_); }
  void Allocate(int bits) {
    shift_ = 64 - bits;
    slots_.assign(size_t(1) << bits, uint64_t(kEmpty));  // (a copy: C++14 would odr-use kEmpty)
  }
  void Grow() {
    std::vector<uint64_t> old;
    old.swap(slots_);
    Allocate(64 - shift_ + 1);
    const size_t mask = slots_.size() - 1;
    for (uint64_t s : old)
      if (s != kEmpty) {
        size_t h = Home(uint32_t(s >> 32));
        while (slots_[h] != kEmpty) h = (h + 1) & mask;
        slots_[h] = s;
      }
  }
  std::vector<uint64_t> slots_;
  size_t count_ = 0;
  int shift_ = 60;
};

// One record per edge of every face, carrying an id of that face (the face itself, or its cluster),
// sorted by edge and then by id: the records of one edge stand together. Works on any vertex id
// space (it sorts rather than indexing by vertex).
struct EdgeRecord {
  uint64_t key;
  uint32_t id;
};
template <class IdOf>
std::vector<EdgeRecord> SortedEdgeRecords(const std::vector<Face>& faces, IdOf idOf) {
  std::vector<EdgeRecord> edges;
  edges.reserve(faces.size() * 3);
  for (uint32_t f = 0; f < faces.size(); ++f)
    for (int i = 0; i < 3; ++i) {
      uint32_t a = faces[f][size_t(i)], b = faces[f][size_t((i + 1) % 3)];
      if (a > b) std::swap(a, b);
      edges.push_back({uint64_t(a) << 32 | b, idOf(f)});
    }
  std::sort(edges.begin(), edges.end(),
            [](const EdgeRecord& x, const EdgeRecord& y) { return x.key < y.key || (x.key == y.key && x.id < y.id); });
  return edges;
}

// Calls fn(x, y) for every ordered pair of records of one edge whose ids differ, edge by edge.
template <class Fn>
void ForPairsOnSharedEdges(const std::vector<EdgeRecord>& edges, Fn fn) {
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].key == edges[i].key) ++j;
    for (size_t a = i; a < j; ++a)
      for (size_t b = i; b < j; ++b)
        if (edges[a].id != edges[b].id) fn(edges[a].id, edges[b].id);
    i = j;
  }
}

// EdgeAdjacency when every vertex id is below V: the edges bucketed by their lower vertex (a
// counting sort instead of a comparison sort of the 3 x faces records), a bucket's records
// (higher vertex << 32 | face; 8 bytes where SortedEdgeRecords' take 16) filled in face order and
// then sorted: the same order, (key, face). The buckets are ordered and read on the threads.
void EdgeAdjacencyBelow(const std::vector<Face>& faces, uint32_t V, unsigned threads, std::vector<uint32_t>& offsets,
                        std::vector<uint32_t>& list) {
  const uint32_t F = uint32_t(faces.size());
  std::vector<uint32_t> end(size_t(V) + 1, 0);  // end[v + 1]: the end of vertex v's bucket
  for (const Face& t : faces)
    for (int i = 0; i < 3; ++i) ++end[size_t(std::min(t[size_t(i)], t[size_t((i + 1) % 3)])) + 1];
  std::partial_sum(end.begin(), end.end(), end.begin());
  std::vector<uint64_t> rec(size_t(F) * 3);
  {
    std::vector<uint32_t> at(end.begin(), end.end() - 1);
    for (uint32_t f = 0; f < F; ++f)
      for (int i = 0; i < 3; ++i) {
        uint32_t a = faces[f][size_t(i)], b = faces[f][size_t((i + 1) % 3)];
        if (a > b) std::swap(a, b);
        rec[at[a]++] = uint64_t(b) << 32 | f;
      }
  }
  // Per bucket: sorted, then each run of one edge gives its ordered pairs of different faces.
  auto pairs = [&](uint32_t v, uint32_t* count, uint32_t* at) {
    const auto b = rec.begin() + end[v], e = rec.begin() + end[size_t(v) + 1];
    for (auto i = b; i < e;) {
      auto j = i;
      while (j < e && (*j >> 32) == (*i >> 32)) ++j;
      for (auto x = i; x < j; ++x)
        for (auto y = i; y < j; ++y) {
          const uint32_t f = uint32_t(*x), g = uint32_t(*y);
          if (f == g) continue;
          if (count)
            ++count[size_t(f) + 1];
          else
            list[at[f]++] = g;
        }
      i = j;
    }
  };
  const size_t step = size_t(1) << 14;
  ParallelChunks(V, threads, step, [&](size_t b, size_t e, unsigned) {
    for (size_t v = b; v < e; ++v) {
      const auto i0 = rec.begin() + end[v], i1 = rec.begin() + end[v + 1];
      if (i1 - i0 > 32)  // a fan of many faces
        std::sort(i0, i1);
      else
        for (auto i = i0 + (i0 != i1); i < i1; ++i)
          for (auto j = i; j != i0 && *(j - 1) > *j; --j) std::iter_swap(j - 1, j);
    }
  });
  // (A face's count: from the buckets of its up to three lower vertices, so counted serially.)
  std::vector<uint32_t> count(size_t(F) + 1, 0);
  for (uint32_t v = 0; v < V; ++v) pairs(v, count.data(), nullptr);
  std::partial_sum(count.begin(), count.end(), count.begin());
  offsets = count;
  list.assign(offsets.back(), 0);
  std::vector<uint32_t> at(offsets.begin(), offsets.end() - 1);
  for (uint32_t v = 0; v < V; ++v) pairs(v, nullptr, at.data());
}

// Faces sharing an edge (by vertex ids), CSR; a face appears once per edge it shares, in the
// order of the edges (lower vertex, higher vertex), then of the faces. `V` (0: unknown) bounds
// the vertex ids: when it is no more than about the faces, EdgeAdjacencyBelow (the same lists).
void EdgeAdjacency(const std::vector<Face>& faces, size_t V, unsigned threads, std::vector<uint32_t>& offsets,
                   std::vector<uint32_t>& list) {
  if (V > 0 && V <= 2 * faces.size() + 1024) return EdgeAdjacencyBelow(faces, uint32_t(V), threads, offsets, list);
  const std::vector<EdgeRecord> edges = SortedEdgeRecords(faces, [](uint32_t f) { return f; });
  std::vector<uint32_t> count(faces.size() + 1, 0);
  ForPairsOnSharedEdges(edges, [&](uint32_t f, uint32_t) { ++count[f + 1]; });
  std::partial_sum(count.begin(), count.end(), count.begin());
  offsets = count;
  list.assign(offsets.back(), 0);
  std::vector<uint32_t> at(offsets.begin(), offsets.end() - 1);
  ForPairsOnSharedEdges(edges, [&](uint32_t f, uint32_t g) { list[at[f]++] = g; });
}

vcg::Point3d Normal(const std::vector<vcg::Point3f>& pos, const Face& t) {
  const vcg::Point3d a = vcg::Point3d::Construct(pos[t[0]]), b = vcg::Point3d::Construct(pos[t[1]]),
                     c = vcg::Point3d::Construct(pos[t[2]]);
  vcg::Point3d n = (b - a) ^ (c - a);
  const double l = n.Norm();
  return l > 0 ? n / l : vcg::Point3d(0, 0, 0);
}

// Cuts faces into clusters of about `cap` faces whose normals stay within maxAngle of their seed's
// (one cluster grown at a time, nearest normal first); clusters under cap/4 then join the
// neighbouring cluster they share the most edges with. Returns the cluster count.
// The adjacency and the normals on `threads` threads; the growing itself is serial.
uint32_t GrowClusters(const std::vector<Face>& faces, const std::vector<vcg::Point3f>& pos, size_t cap, double maxAngle,
                      std::vector<uint32_t>& cluster, unsigned threads = 1) {
  const uint32_t F = uint32_t(faces.size());
  cluster.assign(F, ~0u);
  if (F == 0) return 0;
  std::vector<uint32_t> off, adj;
  EdgeAdjacency(faces, pos.size(), threads, off, adj);
  std::vector<vcg::Point3d> n(F);
  ParallelChunks(F, threads, size_t(1) << 14, [&](size_t b, size_t e, unsigned) {
    for (size_t f = b; f < e; ++f) n[f] = Normal(pos, faces[f]);
  });
  const double minDot = std::cos(std::min(maxAngle, NormalCone::kPi));
  cap = std::max<size_t>(cap, 1);
  std::vector<uint32_t> size;
  using Item = std::pair<double, uint32_t>;  // (-dot, face): smallest first
  std::vector<Item> heap;
  std::vector<uint32_t> queued(F, ~0u);
  for (uint32_t seed = 0; seed < F; ++seed) {
    if (cluster[seed] != ~0u) continue;
    const uint32_t c = uint32_t(size.size());
    size.push_back(0);
    const vcg::Point3d axis = n[seed];
    heap.clear();
    heap.push_back({-1.0, seed});
    queued[seed] = c;
    while (!heap.empty() && size[c] < cap) {
      std::pop_heap(heap.begin(), heap.end(), std::greater<Item>());
      const uint32_t f = heap.back().second;
      heap.pop_back();
      if (cluster[f] != ~0u) continue;
      cluster[f] = c;
      ++size[c];
      for (uint32_t i = off[f]; i < off[f + 1]; ++i) {
        const uint32_t g = adj[i];
        if (cluster[g] != ~0u || queued[g] == c) continue;
        const double d = n[g].SquaredNorm() > 0 && axis.SquaredNorm() > 0 ? n[g] * axis : 1.0;
        if (d < minDot) continue;
        queued[g] = c;
        heap.push_back({-d, g});
        std::push_heap(heap.begin(), heap.end(), std::greater<Item>());
      }
    }
  }
  // Small clusters join a neighbour (deterministic: smallest first, ties by index).
  const uint32_t C = uint32_t(size.size());
  std::vector<uint32_t> start(C + 1, 0), members(F);
  for (uint32_t f = 0; f < F; ++f) ++start[cluster[f] + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  {
    std::vector<uint32_t> at(start.begin(), start.end() - 1);
    for (uint32_t f = 0; f < F; ++f) members[at[cluster[f]]++] = f;
  }
  std::vector<uint32_t> merged(C);
  std::iota(merged.begin(), merged.end(), 0u);
  std::vector<uint32_t> order(C);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return size[a] < size[b]; });
  std::unordered_map<uint32_t, uint32_t> shared;
  for (uint32_t c : order) {
    if (size[FindRoot(merged, c)] * 4 >= cap || FindRoot(merged, c) != c) continue;
    shared.clear();
    for (uint32_t j = start[c]; j < start[c + 1]; ++j)
      for (uint32_t i = off[members[j]]; i < off[members[j] + 1]; ++i) {
        const uint32_t o = FindRoot(merged, cluster[adj[i]]);
        if (o != c) ++shared[o];
      }
    uint32_t best = ~0u, bestCount = 0;
    for (const auto& kv : shared)
      if (kv.second > bestCount || (kv.second == bestCount && kv.first < best)) {
        best = kv.first;
        bestCount = kv.second;
      }
    if (best == ~0u) continue;
    merged[c] = best;
    size[best] += size[c];
    // Members move with the union-find; rewrite their cluster at the end.
    for (uint32_t j = start[c]; j < start[c + 1]; ++j) cluster[members[j]] = best;
  }
  std::vector<uint32_t> dense(C, ~0u);
  uint32_t next = 0;
  for (uint32_t f = 0; f < F; ++f) {
    const uint32_t r = FindRoot(merged, cluster[f]);
    if (dense[r] == ~0u) dense[r] = next++;
    cluster[f] = dense[r];
  }
  return next;
}

// SortedEdgeRecords(L.faces, face's cluster) without the edges whose records all name one cluster
// (they make no pair in ForPairsOnSharedEdges), when every vertex id is below V: an edge two
// clusters share has both ends on faces of two clusters, so only such edges are kept (about a
// tenth of them with clusters of 128 faces), each with all its records.
std::vector<EdgeRecord> ClusterBorderEdgeRecords(const LodDag::Level& L, size_t V, unsigned threads) {
  constexpr uint32_t kNone = ~0u, kMany = ~0u - 1;
  // Per vertex: the cluster of its faces, or kMany (faces side by side: the first to come sets
  // it, one of another cluster makes it kMany, whatever the order).
  std::unique_ptr<std::atomic<uint32_t>[]> first(new std::atomic<uint32_t>[V]);
  const size_t F = L.faces.size(), step = size_t(1) << 14;
  ParallelChunks(V, threads, step, [&](size_t b, size_t e, unsigned) {
    for (size_t v = b; v < e; ++v) first[v].store(kNone, std::memory_order_relaxed);
  });
  ParallelChunks(F, threads, step, [&](size_t b, size_t e, unsigned) {
    for (size_t f = b; f < e; ++f) {
      const uint32_t c = L.faceCluster[f];
      for (uint32_t v : L.faces[f]) {
        uint32_t seen = first[v].load(std::memory_order_relaxed);
        while (seen != c && seen != kMany)
          if (seen == kNone ? first[v].compare_exchange_weak(seen, c, std::memory_order_relaxed)
                            : (first[v].store(kMany, std::memory_order_relaxed), true))
            break;
      }
    }
  });
  // The kept records, a run of faces at a time, then in order.
  std::vector<std::vector<EdgeRecord>> part((F + step - 1) / step);
  ParallelChunks(F, threads, step, [&](size_t b, size_t e, unsigned) {
    std::vector<EdgeRecord>& out = part[b / step];
    for (size_t f = b; f < e; ++f)
      for (int i = 0; i < 3; ++i) {
        uint32_t a = L.faces[f][size_t(i)], c = L.faces[f][size_t((i + 1) % 3)];
        if (first[a].load(std::memory_order_relaxed) != kMany || first[c].load(std::memory_order_relaxed) != kMany)
          continue;
        if (a > c) std::swap(a, c);
        out.push_back({uint64_t(a) << 32 | c, L.faceCluster[f]});
      }
  });
  std::vector<EdgeRecord> edges;
  {
    size_t n = 0;
    for (const auto& p : part) n += p.size();
    edges.reserve(n);
    for (auto& p : part) {
      edges.insert(edges.end(), p.begin(), p.end());
      std::vector<EdgeRecord>().swap(p);
    }
  }
  std::sort(edges.begin(), edges.end(),
            [](const EdgeRecord& x, const EdgeRecord& y) { return x.key < y.key || (x.key == y.key && x.id < y.id); });
  return edges;
}

// Greedy growth leaves groups hemmed in by their neighbours well short of `per` clusters (the
// dragon's level 0 averaged 8 of 24), and a small group locks a larger share of its faces. Each
// group of under per / 2 clusters, in id order, joins the neighbouring group it shares the most
// edges with (`off`/`nb`/`w`: the cluster adjacency and shared edges), if the two hold at most
// 3 / 2 per clusters; a group that grew this way may then join another in its turn. Renumbers the
// groups that remain in the order of their ids; returns their count.
int MergeSmallGroups(const std::vector<uint32_t>& off, const std::vector<uint32_t>& nb, const std::vector<uint32_t>& w,
                     int per, int groups, std::vector<int>& group) {
  const size_t cap = size_t(per) + size_t(per) / 2;
  std::vector<std::vector<uint32_t>> members(static_cast<size_t>(groups));
  for (uint32_t c = 0; c < group.size(); ++c) members[size_t(group[c])].push_back(c);
  std::vector<uint32_t> into(static_cast<size_t>(groups));  // union-find: the group it joined
  std::iota(into.begin(), into.end(), 0u);
  std::unordered_map<int, uint64_t> shared;
  for (int g = 0; g < groups; ++g) {
    if (2 * members[size_t(g)].size() >= size_t(per)) continue;
    shared.clear();
    for (uint32_t c : members[size_t(g)])
      for (uint32_t i = off[c]; i < off[c + 1]; ++i) {
        const int h = int(FindRoot(into, uint32_t(group[nb[i]])));
        if (h != g) shared[h] += w[i];
      }
    int best = -1;
    uint64_t bestShared = 0;
    for (const auto& kv : shared) {
      if (members[size_t(g)].size() + members[size_t(kv.first)].size() > cap) continue;
      if (kv.second > bestShared || (kv.second == bestShared && kv.first < best)) {
        best = kv.first;
        bestShared = kv.second;
      }
    }
    if (best < 0) continue;
    into[size_t(g)] = uint32_t(best);
    std::vector<uint32_t>& to = members[size_t(best)];
    to.insert(to.end(), members[size_t(g)].begin(), members[size_t(g)].end());
    std::vector<uint32_t>().swap(members[size_t(g)]);
  }
  std::vector<int> id(size_t(groups), -1);
  int count = 0;
  for (int g = 0; g < groups; ++g)
    if (into[size_t(g)] == uint32_t(g)) id[size_t(g)] = count++;
  for (int& g : group) g = id[FindRoot(into, uint32_t(g))];
  return count;
}

// Gathers the clusters of a level into groups of about `per` neighbouring clusters (those sharing
// the most edges first); a connected part of at most `whole` clusters (clusters sharing edges)
// is one group. Returns the group count.
// With `node` (per cluster: its kd chunk), clusters of two chunks are no neighbours: a group stays
// within one chunk. `V` (0: unknown) bounds the vertex ids: then only the edges whose two ends
// both touch two clusters are sorted (ClusterBorderEdgeRecords, on `threads` threads), which
// gives the same pairs.
// `across` (> 1; LodBuildParams::lockedBorderWeight): the edges two clusters made from different
// groups of the level below share (that level's locked border: L.clusterCreator) weigh that many
// edges, so that the groups grow across it and free it. `merge`: then MergeSmallGroups.
int GroupClusters(const LodDag::Level& L, int per, size_t whole, std::vector<int>& group,
                  const std::vector<uint32_t>* node = nullptr, size_t V = 0, unsigned threads = 1, double across = 1,
                  bool merge = false) {
  const uint32_t C = uint32_t(L.clusterCount());
  // Cluster adjacency weighted by shared edges.
  const std::vector<EdgeRecord> edges = V > 0
                                            ? ClusterBorderEdgeRecords(L, V, threads)
                                            : SortedEdgeRecords(L.faces, [&](uint32_t f) { return L.faceCluster[f]; });
  // Per cluster a, its neighbours b in increasing order, each with the edges a and b share: the
  // pairs (a, b) of the shared edges bucketed by a, each bucket sorted.
  std::vector<uint32_t> off(C + 1, 0), nb, w, bucket;
  auto neighbours = [&](uint32_t a, uint32_t b) { return !node || (*node)[a] == (*node)[b]; };
  ForPairsOnSharedEdges(edges, [&](uint32_t a, uint32_t b) {
    if (neighbours(a, b)) ++off[a + 1];
  });
  std::partial_sum(off.begin(), off.end(), off.begin());
  bucket.resize(off[C]);
  {
    std::vector<uint32_t> at(off.begin(), off.end() - 1);
    ForPairsOnSharedEdges(edges, [&](uint32_t a, uint32_t b) {
      if (neighbours(a, b)) bucket[at[a]++] = b;
    });
  }
  for (uint32_t a = 0; a < C; ++a) {
    const auto b0 = bucket.begin() + off[a], b1 = bucket.begin() + off[a + 1];
    std::sort(b0, b1);
    off[a] = uint32_t(nb.size());
    for (auto i = b0; i < b1;) {
      auto j = i;
      while (j < b1 && *j == *i) ++j;
      nb.push_back(*i);
      uint32_t shared = uint32_t(j - i);
      if (across > 1 && L.clusterCreator.size() == C && L.clusterCreator[a] != L.clusterCreator[*i])
        shared = uint32_t(std::lround(double(shared) * across));
      w.push_back(shared);
      i = j;
    }
  }
  off[C] = uint32_t(nb.size());
  std::vector<uint32_t>().swap(bucket);
  group.assign(C, -1);
  int groups = 0;
  // Visit clusters breadth-first (locality); a new group starts at each unassigned cluster.
  std::vector<uint32_t> bfs;
  std::vector<uint8_t> seen(C, 0);
  for (uint32_t s = 0; s < C; ++s) {
    if (seen[s]) continue;
    seen[s] = 1;
    const size_t first = bfs.size();
    bfs.push_back(s);
    for (size_t h = first; h < bfs.size(); ++h)
      for (uint32_t i = off[bfs[h]]; i < off[bfs[h] + 1]; ++i)
        if (!seen[nb[i]]) {
          seen[nb[i]] = 1;
          bfs.push_back(nb[i]);
        }
    if (bfs.size() - first <= whole) {
      for (size_t h = first; h < bfs.size(); ++h) group[bfs[h]] = groups;
      ++groups;
    }
  }
  std::unordered_map<uint32_t, uint32_t> gain;
  std::vector<uint32_t> members;
  for (uint32_t c : bfs) {
    if (group[c] >= 0) continue;
    const int g = groups++;
    group[c] = g;
    members.assign(1, c);
    gain.clear();
    while (int(members.size()) < per) {
      for (uint32_t i = off[members.back()]; i < off[members.back() + 1]; ++i)
        if (group[nb[i]] < 0) gain[nb[i]] += w[i];
      uint32_t best = ~0u, bestGain = 0;
      for (const auto& kv : gain)
        if (group[kv.first] < 0 && (kv.second > bestGain || (kv.second == bestGain && kv.first < best))) {
          best = kv.first;
          bestGain = kv.second;
        }
      if (best == ~0u) break;
      group[best] = g;
      members.push_back(best);
      gain.erase(best);
    }
  }
  return merge ? MergeSmallGroups(off, nb, w, per, groups, group) : groups;
}

// GroupClusters(L, per, 0, group, &node) chunk by chunk, when the clusters of a chunk are
// consecutive (clusterNode never decreases: level 0's clusters are numbered chunk by chunk, and a
// level's groups, hence the next level's clusters, follow them): each chunk's clusters and faces
// are grouped on their own and their groups numbered after the previous chunk's, which gives the
// same groups as over the whole level (its breadth-first walk never leaves a chunk) with the
// edge records of one chunk at a time instead of the whole level's (48 bytes a face). Chunks side
// by side on `threads`. Returns -1 when the clusters are not in chunk order.
int GroupClustersByChunk(const LodDag::Level& L, int per, const std::vector<uint32_t>& node, unsigned threads,
                         std::vector<int>& group, double across = 1, bool merge = false) {
  const size_t C = L.clusterCount();
  std::vector<uint32_t> first;  // first cluster of each run of one chunk, then C
  for (size_t c = 0; c < C; ++c) {
    if (c > 0 && node[c] < node[c - 1]) return -1;
    if (c == 0 || node[c] != node[c - 1]) first.push_back(uint32_t(c));
  }
  first.push_back(uint32_t(C));
  const size_t runs = first.size() - 1;
  std::vector<uint32_t> runOf(C);
  for (size_t r = 0; r < runs; ++r)
    for (uint32_t c = first[r]; c < first[r + 1]; ++c) runOf[c] = uint32_t(r);
  // Faces of each run, in level order (counting sort).
  std::vector<uint32_t> start(runs + 1, 0), faces(L.faces.size());
  for (uint32_t c : L.faceCluster) ++start[runOf[c] + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  {
    std::vector<uint32_t> at(start.begin(), start.end() - 1);
    for (uint32_t f = 0; f < L.faces.size(); ++f) faces[at[runOf[L.faceCluster[f]]]++] = f;
  }
  std::vector<uint32_t>().swap(runOf);
  std::vector<std::vector<int>> local(runs);
  std::vector<int> count(runs, 0);
  ParallelItems<LodDag::Level>(runs, threads, [&](size_t r, LodDag::Level& sub) {
    sub.faces.clear();
    sub.faceCluster.clear();
    for (uint32_t j = start[r]; j < start[r + 1]; ++j) {
      sub.faces.push_back(L.faces[faces[j]]);
      sub.faceCluster.push_back(L.faceCluster[faces[j]] - first[r]);
    }
    sub.clusterGroup.assign(first[r + 1] - first[r], -1);
    sub.clusterCreator.clear();
    if (L.clusterCreator.size() == C)
      sub.clusterCreator.assign(L.clusterCreator.begin() + first[r], L.clusterCreator.begin() + first[r + 1]);
    count[r] = GroupClusters(sub, per, 0, local[r], nullptr, 0, 1, across, merge);
  });
  group.assign(C, -1);
  int groups = 0;
  for (size_t r = 0; r < runs; ++r) {
    for (uint32_t c = first[r]; c < first[r + 1]; ++c) group[c] = groups + local[r][c - first[r]];
    groups += count[r];
  }
  return groups;
}

// Splits the faces into 2^depth kd chunks of at most `cap` faces each and returns depth: the box
// of the face centroids is cut at the median on its longest axis (ties by face index, so the
// halves do not depend on the sort's order), every leaf at the same depth. leaf[f]: the chunk of
// face f, whose bits (most significant first) are the halves chosen from the root (1: the upper),
// so that the chunk at depth d holding it is leaf[f] >> (depth - d).
int KdChunks(const IndexedMesh& mesh, size_t cap, std::vector<uint32_t>& leaf) {
  const size_t F = mesh.faces.size();
  int depth = 0;
  while (depth < 24 && (F + (size_t(1) << depth) - 1) >> depth > cap) ++depth;
  leaf.assign(F, 0);
  if (depth == 0) return 0;
  std::vector<vcg::Point3f> c(F);
  for (size_t f = 0; f < F; ++f) {
    const auto& t = mesh.faces[f];
    const vcg::Point3d p =
        (vcg::Point3d::Construct(mesh.positions[t[0]]) + vcg::Point3d::Construct(mesh.positions[t[1]]) +
         vcg::Point3d::Construct(mesh.positions[t[2]])) /
        3.0;
    c[f] = vcg::Point3f::Construct(p);
  }
  std::vector<uint32_t> order(F);
  std::iota(order.begin(), order.end(), 0u);
  struct Range {
    size_t begin, end;
    uint32_t node;
    int level;
  };
  std::vector<Range> todo = {{0, F, 0u, 0}};
  while (!todo.empty()) {
    const Range r = todo.back();
    todo.pop_back();
    if (r.level == depth) {
      for (size_t i = r.begin; i < r.end; ++i) leaf[order[i]] = r.node;
      continue;
    }
    vcg::Box3f box;
    for (size_t i = r.begin; i < r.end; ++i) box.Add(c[order[i]]);
    int axis = 0;
    if (!box.IsNull()) {
      const vcg::Point3f d = box.Dim();
      axis = d[1] > d[axis] ? 1 : axis;
      axis = d[2] > d[axis] ? 2 : axis;
    }
    const size_t mid = r.begin + (r.end - r.begin) / 2;
    std::nth_element(order.begin() + std::ptrdiff_t(r.begin), order.begin() + std::ptrdiff_t(mid),
                     order.begin() + std::ptrdiff_t(r.end), [&](uint32_t a, uint32_t b) {
                       return c[a][axis] < c[b][axis] || (c[a][axis] == c[b][axis] && a < b);
                     });
    todo.push_back({r.begin, mid, r.node << 1, r.level + 1});
    todo.push_back({mid, r.end, r.node << 1 | 1u, r.level + 1});
  }
  return depth;
}

// The sum over `order`'s vertices of the squared distance to the nearest of `tri`'s faces, exact:
// a uniform grid over the faces' and the vertices' box, each face in every cell its box meets,
// each vertex searching shells of cells outwards until its nearest face so far is nearer than
// any cell not searched.
// Only the vertices whose index is a multiple of kSampleStride are measured.
constexpr uint32_t kSampleStride = 4;
template <class TriT, class NearT, class PosT>
double SumSquaredDistances(const std::vector<TriT>& tri, const std::vector<NearT>& order, const PosT& positions) {
  if (tri.empty() || order.empty()) return 0;
  vcg::Box3d box;
  double edge = 0;
  for (const TriT& t : tri) {
    for (const auto& q : t.p) box.Add(q);
    edge += t.radius;
  }
  for (const NearT& n : order) box.Add(vcg::Point3d::Construct(positions[n.vertex]));
  const vcg::Point3d dim = box.Dim();
  double h = std::max(2 * edge / double(tri.size()), 1e-12 * (1 + dim.Norm()));
  int n[3];
  for (;;) {
    uint64_t cells = 1;
    for (int i = 0; i < 3; ++i) {
      n[i] = std::max(1, int(std::min(1024.0, std::ceil(dim[i] / h))));
      cells *= uint64_t(n[i]);
    }
    if (cells <= 4 * tri.size() + 64) break;
    h *= 1.5;
  }
  auto cellOf = [&](double x, int i) { return std::max(0, std::min(n[i] - 1, int((x - box.min[i]) / h))); };
  std::vector<uint32_t> start(size_t(n[0]) * n[1] * n[2] + 1, 0), items;
  auto forCells = [&](const TriT& t, auto&& f) {
    vcg::Box3d b;
    for (const auto& q : t.p) b.Add(q);
    const int x0 = cellOf(b.min[0], 0), x1 = cellOf(b.max[0], 0), y0 = cellOf(b.min[1], 1), y1 = cellOf(b.max[1], 1),
              z0 = cellOf(b.min[2], 2), z1 = cellOf(b.max[2], 2);
    for (int z = z0; z <= z1; ++z)
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) f(size_t(z) * n[1] * n[0] + size_t(y) * n[0] + size_t(x));
  };
  for (const TriT& t : tri) forCells(t, [&](size_t c) { ++start[c + 1]; });
  for (size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  items.resize(start.back());
  {
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (uint32_t i = 0; i < uint32_t(tri.size()); ++i) forCells(tri[i], [&](size_t c) { items[fill[c]++] = i; });
  }
  std::vector<uint32_t> stamp(tri.size(), 0);
  uint32_t mark = 0;
  double sum = 0;
  for (const NearT& v : order) {
    if (v.vertex % kSampleStride) continue;
    const vcg::Point3d p = vcg::Point3d::Construct(positions[v.vertex]);
    const int c[3] = {cellOf(p[0], 0), cellOf(p[1], 1), cellOf(p[2], 2)};
    double best = v.bound;
    ++mark;
    for (int r = 0;; ++r) {
      bool inside = false;
      for (int z = c[2] - r; z <= c[2] + r; ++z) {
        if (z < 0 || z >= n[2]) continue;
        for (int y = c[1] - r; y <= c[1] + r; ++y) {
          if (y < 0 || y >= n[1]) continue;
          const bool edgeZY = z == c[2] - r || z == c[2] + r || y == c[1] - r || y == c[1] + r;
          for (int x = c[0] - r; x <= c[0] + r; x += (edgeZY || r == 0) ? 1 : 2 * r) {
            if (x < 0 || x >= n[0]) continue;
            inside = true;
            const size_t cell = size_t(z) * n[1] * n[0] + size_t(y) * n[0] + size_t(x);
            for (uint32_t k = start[cell]; k < start[cell + 1]; ++k) {
              const uint32_t i = items[k];
              if (stamp[i] == mark) continue;
              stamp[i] = mark;
              best = std::min(best, PointTriangleDistance2(p, tri[i].p[0], tri[i].p[1], tri[i].p[2]));
            }
          }
        }
      }
      // The faces not visited lie in cells outside the cube of cells within r of p's: at least
      // the distance from p to that cube's nearest wall away (a wall on the grid's edge has no
      // cell beyond it).
      if (!inside) break;
      double wall = std::numeric_limits<double>::infinity();
      for (int i = 0; i < 3; ++i) {
        if (c[i] - r > 0) wall = std::min(wall, p[i] - (box.min[i] + double(c[i] - r) * h));
        if (c[i] + r < n[i] - 1) wall = std::min(wall, box.min[i] + double(c[i] + r + 1) * h - p[i]);
      }
      if (best <= std::max(0.0, wall) * std::max(0.0, wall)) break;
    }
    sum += best;
  }
  return sum;
}

// One group simplified: its faces in the group's local vertex ids, the positions of the vertices
// it made (local ids >= the group's input vertex count refer to them), its error.
struct GroupResult {
  std::vector<Face> faces;              // local vertex ids: < keptBase: input vertex; else newPositions
  std::vector<uint32_t> localToGlobal;  // per input local vertex: its global id
  std::vector<vcg::Point3f> newPositions;
  LodAttributes newAttributes;  // per new vertex (the streams the DAG carries)
  // With places (texture seams): per new vertex, the local id of a vertex at its position (< the
  // input local count: that vertex's place; else a new vertex, the first made at that position).
  std::vector<uint32_t> newPlace;
  double distance = 0;  // the largest distance from the group's vertices to its simplified faces
  double typical = 0;   // sqrt(RMS distance x distance) (LodDag::Level::clusterTypical)
  bool ok = false;
  // The faces re-cut into the next level's clusters (RecutGroup): per face its cluster, numbered
  // within the group, and their count.
  std::vector<uint32_t> cluster;
  uint32_t clusters = 0;
};

// The attributes of the DAG's vertices as the attribute quadrics' float channels (colour RGBA in
// [0, 1], then the unit normal, then the texture coordinates' codes / 65535: the UV box mapped to
// [0, 1], an affine map, so the quadrics' linear model is the same and the codes round trip
// exactly) and back to the stored codes.
VertexAttributes LayoutOf(const LodAttributes& a) {
  VertexAttributes l;
  l.colorChannels = a.colors.empty() ? 0 : 4;
  l.normals = !a.normals.empty();
  l.texCoords = !a.texCoords.empty();
  return l;
}
void ChannelsOf(const LodAttributes& a, uint32_t v, float* out) {
  if (!a.colors.empty())
    for (int c = 0; c < 4; ++c) *out++ = float(a.colors[v][size_t(c)]) / 255.f;
  if (!a.normals.empty()) {
    const vcg::Point3f n = DecodeLodNormal(a.normals[v]);
    for (int c = 0; c < 3; ++c) *out++ = n[c];
  }
  if (!a.texCoords.empty())
    for (int c = 0; c < 2; ++c) *out++ = float(a.texCoords[v][size_t(c)]) / 65535.f;
}
// The stored codes of one vertex.
struct Codes {
  std::array<uint8_t, 4> color{{0, 0, 0, 0}};
  std::array<uint16_t, 2> normal{{0, 0}}, uv{{0, 0}};
  bool operator==(const Codes& o) const { return color == o.color && normal == o.normal && uv == o.uv; }
};
Codes StoreChannels(const float* in, const LodAttributes& like) {
  Codes k;
  if (!like.colors.empty()) {
    for (int c = 0; c < 4; ++c) k.color[size_t(c)] = uint8_t(std::lround(std::min(1.f, std::max(0.f, in[c])) * 255.f));
    in += 4;
  }
  if (!like.normals.empty()) {
    k.normal = EncodeLodNormal(vcg::Point3f(in[0], in[1], in[2]));
    in += 3;
  }
  if (!like.texCoords.empty())
    for (int c = 0; c < 2; ++c) {
      const float x = std::isfinite(in[c]) ? in[c] : 0.f;
      k.uv[size_t(c)] = uint16_t(std::lround(std::min(1.f, std::max(0.f, x)) * 65535.f));
    }
  return k;
}
Codes CodesOf(const LodAttributes& a, uint32_t v) {
  Codes k;
  if (!a.colors.empty()) k.color = a.colors[v];
  if (!a.normals.empty()) k.normal = a.normals[v];
  if (!a.texCoords.empty()) k.uv = a.texCoords[v];
  return k;
}
// How far apart two vertices' codes are (a frozen seam vertex whose corner matches none of its
// wedges exactly takes the nearest; it cannot happen, the corners keep their values).
double CodeDistance(const Codes& x, const Codes& y) {
  double d = 0;
  for (size_t c = 0; c < 4; ++c) d += std::fabs(double(x.color[c]) - double(y.color[c]));
  for (size_t c = 0; c < 2; ++c)
    d += std::fabs(double(x.normal[c]) - double(y.normal[c])) + std::fabs(double(x.uv[c]) - double(y.uv[c]));
  return d;
}

// The largest normal-cone half-angle of the clusters of level `level` (radians): the grouping's
// threshold grown once per level, at most 90 degrees.
double ClusterAngle(const LodBuildParams& params, int level) {
  return std::min(90.0, params.grouping.coneThresholdDeg * std::pow(params.grouping.thresholdGrowth, level)) *
         (NormalCone::kPi / 180);
}

// A group's error: the largest error of the clusters it was made from plus its own distance,
// strictly above that largest one even in float (a tiny step when the distance is 0), so that
// errors grow up the DAG.
float GroupErrorAbove(double maxBelow, double distance) {
  float ef = float(maxBelow + distance);
  const float floor = float(maxBelow);
  if (!(ef > floor)) ef = std::nextafter(std::max(floor, 0.f), std::numeric_limits<float>::infinity());
  return ef;
}

// A level of `faces` faces (the input: `inputFaces`) is coarse when it has at most 3/8 of the
// input's faces: level 2 (about a quarter of them) and above.
bool CoarseLevel(uint64_t faces, uint64_t inputFaces) { return 8 * faces <= 3 * inputFaces; }

// Chunks built side by side (a wave, `lod build --memory`): as many as three quarters of what the
// budget leaves after the `fixed` bytes that stay allow, at `perChunk` bytes a chunk in flight; at
// least 1. The budget's process share (kLodMinMemoryBytes) counts as fixed too, but for a budget
// below it (the tests'), which is all chunk work.
size_t ChunksInFlight(const LodBuildParams& params, uint64_t fixed, uint64_t perChunk) {
  const uint64_t budget = uint64_t(params.chunkFaces) * kLodMemoryBytesPerChunkFace;
  if (budget >= kLodMinMemoryBytes) fixed += kLodMinMemoryBytes;
  return budget > fixed ? size_t(std::max<uint64_t>(1, (budget - fixed) / 4 * 3 / perChunk)) : 1;
}

// Whether such a level is a top one, grouped by topGroupClusters (LodBuildParams): not a fine
// level, and under the faces of 4 groups of groupClusters clusters or under topFaceShare of the
// input's faces.
bool UsesTopGroups(const LodBuildParams& params, uint64_t faces, uint64_t inputFaces) {
  if (params.fineGroupClusters > 0 && !CoarseLevel(faces, inputFaces)) return false;
  const bool top = double(faces) < params.topFaceShare * double(inputFaces) ||
                   faces < 4 * uint64_t(params.groupClusters) * params.clusterFaces;
  return params.topGroupClusters > 0 && top;
}

// The fraction of its faces each group of such a level is simplified to (LodBuildParams): the top
// levels' ratio on the top levels (not once the top goes in whole parts), the coarse levels' on
// the coarse ones, levelRatio on the others (at least levelRatio everywhere).
double LevelRatioOf(const LodBuildParams& params, uint64_t faces, uint64_t inputFaces, bool wholeParts = false) {
  const double r = params.simplification.levelRatio;
  if (!wholeParts && params.topLevelRatio > 0 && UsesTopGroups(params, faces, inputFaces))
    return std::max(r, params.topLevelRatio);
  return CoarseLevel(faces, inputFaces) ? std::max(r, params.coarseLevelRatio) : r;
}

// The clusters gathered into one group on such a level (LodBuildParams): fineGroupClusters on the
// fine levels (largeFineGroupClusters on those that hold 32 groups that large), topGroupClusters on
// the top ones, else groupClusters (largeGroupClusters on those that hold largeGroupCount groups
// that large). Of the level's faces and the input's only, so the same for
// every chunk and thread.
int GroupClustersOf(const LodBuildParams& params, uint64_t faces, uint64_t inputFaces) {
  // `large` where it is larger than `base` and the level holds `count` groups of it, else `base`.
  auto largerWhereRoom = [&](int base, int large, uint64_t count) {
    return large > base && faces >= count * uint64_t(large) * params.clusterFaces ? large : base;
  };
  if (params.fineGroupClusters > 0 && !CoarseLevel(faces, inputFaces))
    return largerWhereRoom(params.fineGroupClusters, params.largeFineGroupClusters, 32);
  if (UsesTopGroups(params, faces, inputFaces)) return params.topGroupClusters;
  return largerWhereRoom(params.groupClusters, params.largeGroupClusters, uint64_t(params.largeGroupCount));
}

// Whether such a level's small groups join their neighbours (MergeSmallGroups): on the levels of at
// least 4 full groups, never on the top ones. Where a level holds only a few groups, larger ones
// would free little border and take the cuts through it in coarser steps (LodBuildParams).
bool MergesSmallGroups(const LodBuildParams& params, uint64_t faces, uint64_t inputFaces) {
  return params.mergeSmallGroups && !UsesTopGroups(params, faces, inputFaces) &&
         faces >= 4 * uint64_t(GroupClustersOf(params, faces, inputFaces)) * params.clusterFaces;
}

// A group's faces are in global ids; with places (texture coordinates) one position may carry
// several ids (wedges: one per UV). The collapse runs on the group welded by place, each face
// corner carrying its wedge's attributes (so the attribute quadrics see the seams: a seam vertex
// never moves and goes only along its seam); afterwards every output corner takes the wedge of its
// position and stored values: an existing one where the position and the values did not change,
// else a new one, the wedges of one new position sharing that position.
void SimplifyGroup(const std::vector<Face>& levelFaces, const std::vector<uint32_t>& groupFaces,
                   const std::vector<vcg::Point3f>& positions, const std::vector<uint8_t>& sharedVertex,
                   const LodBuildParams& params, double ratio, double maxError, double diagonal, bool keep,
                   const LodAttributes& attributes, GroupResult& out) {
  const bool wedges = !attributes.place.empty();
  IndexedMesh local;                 // welded by place (without places: one vertex per id)
  std::vector<Face> wedgeFaces;      // the same faces in wedge-local ids (localToGlobal)
  std::vector<uint32_t> weldedOf;    // per wedge-local id: its vertex of `local`
  std::vector<uint32_t> firstWedge;  // per vertex of `local`: its first wedge-local id
  // Global id -> wedge-local id, place -> vertex of `local`.
  // (A group of F faces has about F / 2 vertices: its borders and seams add some.)
  IdMap toLocal(groupFaces.size()), toWelded(wedges ? groupFaces.size() : 0);
  out.localToGlobal.clear();
  local.faces.reserve(groupFaces.size());
  wedgeFaces.reserve(groupFaces.size());
  for (uint32_t f : groupFaces) {
    Face t, w;
    for (int i = 0; i < 3; ++i) {
      const uint32_t v = levelFaces[f][size_t(i)];
      const std::pair<uint32_t, bool> ins = toLocal.Emplace(v, uint32_t(out.localToGlobal.size()));
      if (ins.second) {
        out.localToGlobal.push_back(v);
        // (without places, one vertex per wedge: a new wedge is a new vertex)
        const std::pair<uint32_t, bool> wp =
            wedges ? toWelded.Emplace(attributes.place[v], uint32_t(local.positions.size()))
                   : std::make_pair(uint32_t(local.positions.size()), true);
        if (wp.second) {
          local.positions.push_back(positions[v]);
          firstWedge.push_back(ins.first);
        }
        weldedOf.push_back(wp.first);
      }
      w[size_t(i)] = ins.first;
      t[size_t(i)] = weldedOf[ins.first];
    }
    local.faces.push_back(t);
    wedgeFaces.push_back(w);
  }
  const uint32_t V = uint32_t(out.localToGlobal.size());  // wedges
  const uint32_t W = uint32_t(local.positions.size());    // positions (V without places)
  out.faces.clear();
  out.newPositions.clear();
  out.newPlace.clear();
  out.newAttributes = LodAttributes();
  out.distance = out.typical = 0;
  out.ok = true;
  if (keep) {  // the group stays as it is
    out.faces = wedgeFaces;
    return;
  }
  GroupQemRegion region;
  region.frozenVertex.resize(W);
  for (uint32_t v = 0; v < W; ++v) {
    const uint32_t g = out.localToGlobal[firstWedge[v]];
    region.frozenVertex[v] = sharedVertex[wedges ? attributes.place[g] : g];
  }
  region.diagonal = diagonal;
  // Vertices kept apart by more than a cell of the file's grid (its cell's diagonal is 1.98 x
  // precision x the diagonal of the DAG's positions; 2.5: a margin for a span beyond the input's
  // box): two vertices in one cell read as one, and a vertex joined to both would use the edge to
  // that cell 3 or 4 times (LodCracks.DragonCutsAreWatertightOnceWelded at the dragon's seams).
  region.separation = 2.5 * params.precision * diagonal;
  GroupQemParams qem = params.simplification.qem;
  qem.targetFaces = std::max<size_t>(1, size_t(std::floor(double(local.faces.size()) * ratio)));
  qem.lockGroupBoundaries = false;
  qem.foldPlanes = true;  // each level from the one below: sheets' rims must keep their place (GroupQemParams)
  qem.refreshRatio = params.refreshRatio;  // one memoryless step in a group (LodBuildParams)
  if (maxError > 0) qem.maxError = qem.maxError > 0 ? std::min(qem.maxError, maxError) : maxError;
  const std::vector<int> oneGroup(local.faces.size(), 0);
  // Attributes per face corner: its wedge's (without places one value per vertex, no seam).
  const bool withAttributes = !attributes.empty();
  AttributeQuadrics quadrics;
  const VertexAttributes layout = LayoutOf(attributes);
  const size_t channels = size_t(layout.channels());
  if (withAttributes) {
    std::vector<float> corners(local.faces.size() * 3 * channels);
    for (size_t f = 0; f < local.faces.size(); ++f)
      for (size_t k = 0; k < 3; ++k)
        ChannelsOf(attributes, out.localToGlobal[wedgeFaces[f][k]], corners.data() + (3 * f + k) * channels);
    if (!quadrics.Init(local, layout, std::move(corners), params.attributeWeight).ok()) {
      out.faces = wedgeFaces;  // (cannot happen: the layout and sizes are ours) the group stays
      return;
    }
  }
  GroupQemResult res;
  const Status s = SimplifyPreservingGroups(local, oneGroup, qem, res, Progress(), {}, &region,
                                            withAttributes ? &quadrics : nullptr);
  if (!s.ok() || res.mesh.faces.empty()) {  // the group stays as it is
    out.faces = wedgeFaces;
    return;
  }
  // Each output corner's attributes at its place, as they will be stored; the distinct values of
  // each output vertex in the order its corners come (without seams: one).
  // (One flat list: each vertex's values linked in the order they come, from head[o];
  // cornerVariant: the entry of each corner's value.)
  const size_t O = res.mesh.positions.size();
  struct Variant {
    Codes codes;
    uint32_t id, next;
  };
  std::vector<Variant> variants;
  variants.reserve(O);
  std::vector<uint32_t> head(O, kNoPlace);
  std::vector<uint32_t> cornerVariant(res.mesh.faces.size() * 3, 0);
  {
    std::vector<float> value(std::max<size_t>(1, channels));
    for (size_t f = 0; f < res.mesh.faces.size(); ++f)
      for (int k = 0; k < 3; ++k) {
        const uint32_t o = res.mesh.faces[f][size_t(k)];
        Codes c;
        if (withAttributes) {
          if (!wedges && head[o] != kNoPlace) {  // one value per vertex: its first corner's
            cornerVariant[3 * f + size_t(k)] = head[o];
            continue;
          }
          const vcg::Point3f& q = res.mesh.positions[o];
          quadrics.Evaluate(res.sourceFace[f], k, res.sourceVertex[o], vcg::Point3d(q[0], q[1], q[2]), value.data());
          c = StoreChannels(value.data(), attributes);
        }
        uint32_t* link = &head[o];  // (into `variants`: not used after the push_back below)
        while (*link != kNoPlace && !(variants[*link].codes == c)) link = &variants[*link].next;
        uint32_t j = *link;
        if (j == kNoPlace) {
          j = *link = uint32_t(variants.size());
          variants.push_back({c, 0, kNoPlace});
        }
        cornerVariant[3 * f + size_t(k)] = j;
      }
  }
  // Output vertex (and value) -> local id. A frozen vertex never moves: it keeps its id and its
  // position bit for bit (the simplifier works around the group's centre in double, which can
  // change the last bits of a coordinate near 0, so its output position is not used). Another
  // vertex keeps its id when it did not move (within 1e-9 of the diagonal: the same rounding)
  // and its stored values did not change (a global id has one value in the file), else it is new.
  const float still = float(1e-9 * diagonal);
  std::vector<std::vector<uint32_t>> wedgesOf(wedges ? W : 0);
  for (uint32_t v = 0; v < V && wedges; ++v) wedgesOf[weldedOf[v]].push_back(v);
  auto addNew = [&](const vcg::Point3f& p, const Codes& c, uint32_t place) {
    const uint32_t id = V + uint32_t(out.newPositions.size());
    out.newPositions.push_back(p);
    if (!attributes.colors.empty()) out.newAttributes.colors.push_back(c.color);
    if (!attributes.normals.empty()) out.newAttributes.normals.push_back(c.normal);
    if (!attributes.texCoords.empty()) out.newAttributes.texCoords.push_back(c.uv);
    if (wedges) out.newPlace.push_back(place == kNoPlace ? id : place);
    return id;
  };
  for (size_t o = 0; o < O; ++o) {
    const uint32_t src = res.sourceVertex[o];
    const vcg::Point3f& p = res.mesh.positions[o];
    const vcg::Point3f& q = local.positions[src];
    const bool unmoved =
        region.frozenVertex[src] ||
        (std::fabs(p[0] - q[0]) <= still && std::fabs(p[1] - q[1]) <= still && std::fabs(p[2] - q[2]) <= still);
    uint32_t firstNew = kNoPlace;  // a moved vertex's wedges share their new position
    for (uint32_t j = head[o]; j != kNoPlace; j = variants[j].next) {
      Variant& var = variants[j];
      const Codes& c = var.codes;
      uint32_t id = kNoPlace;
      if (!wedges) {
        if (region.frozenVertex[src] ||
            (unmoved && (!withAttributes || CodesOf(attributes, out.localToGlobal[src]) == c)))
          id = src;
        else
          id = addNew(p, c, kNoPlace);
      } else if (unmoved) {
        const std::vector<uint32_t>& mine = wedgesOf[src];
        for (uint32_t w : mine)
          if (CodesOf(attributes, out.localToGlobal[w]) == c) id = w;
        if (id == kNoPlace && region.frozenVertex[src]) {
          double best = std::numeric_limits<double>::infinity();
          for (uint32_t w : mine) {
            const double d = CodeDistance(CodesOf(attributes, out.localToGlobal[w]), c);
            if (d < best) best = d, id = w;
          }
        }
        if (id == kNoPlace) id = addNew(q, c, mine[0]);  // new values at the same position
      } else {
        id = addNew(p, c, firstNew);
        if (firstNew == kNoPlace) firstNew = id;
      }
      var.id = id;
    }
  }
  out.faces.resize(res.mesh.faces.size());
  for (size_t f = 0; f < res.mesh.faces.size(); ++f)
    for (size_t k = 0; k < 3; ++k) out.faces[f][k] = variants[cornerVariant[3 * f + k]].id;
  // One-sided distance: every input vertex of the group to the simplified faces, the exact
  // maximum over the vertices of each one's minimum over the faces (the order the vertices are
  // taken in and the faces skipped do not change it). Faces are sorted in Morton order of their
  // centroid; each vertex first takes the minimum over the few faces beside its own place in that
  // order (an upper bound of its distance), then the vertices are taken from the largest bound
  // down: once a bound is at most the largest distance found, no vertex left can raise it. A vertex
  // taken scans the faces outwards from its place, stops as soon as a face lies within the largest
  // distance found (it cannot raise it), and skips a face whose bounding sphere lies farther than
  // its nearest face so far.
  auto P = [&](uint32_t id) {
    return vcg::Point3d::Construct(id < V ? local.positions[weldedOf[id]] : out.newPositions[id - V]);
  };
  vcg::Box3d gb;
  for (uint32_t v = 0; v < W; ++v) gb.Add(vcg::Point3d::Construct(local.positions[v]));
  const vcg::Point3d gd = gb.Dim();
  auto morton = [&](const vcg::Point3d& p) {
    uint32_t code = 0;
    for (int i = 0; i < 3; ++i) {
      const double t = gd[i] > 0 ? (p[i] - gb.min[i]) / gd[i] : 0.0;
      code |= SpreadBits10(uint32_t(std::min(1023.0, std::max(0.0, t * 1023.0)))) << i;
    }
    return code;
  };
  struct Tri {
    uint32_t code;
    std::array<vcg::Point3d, 3> p;
    vcg::Point3d centre;
    double radius;
  };
  // (the faces' codes sorted, then the faces laid out in that order: a Tri is 112 bytes)
  std::vector<std::pair<uint32_t, uint32_t>> byCode(out.faces.size());
  for (size_t f = 0; f < out.faces.size(); ++f) {
    const Face& o = out.faces[f];
    byCode[f] = {morton((P(o[0]) + P(o[1]) + P(o[2])) / 3.0), uint32_t(f)};
  }
  std::stable_sort(
      byCode.begin(), byCode.end(),
      [](const std::pair<uint32_t, uint32_t>& a, const std::pair<uint32_t, uint32_t>& b) { return a.first < b.first; });
  std::vector<Tri> tri(out.faces.size());
  for (size_t i = 0; i < byCode.size(); ++i) {
    Tri& t = tri[i];
    const Face& o = out.faces[byCode[i].second];
    t.p = {P(o[0]), P(o[1]), P(o[2])};
    t.centre = (t.p[0] + t.p[1] + t.p[2]) / 3.0;
    t.code = byCode[i].first;
    // (widened by far more than the rounding of the centre, the radius and the distance to the
    // centre: the sphere never misses a point of the face)
    t.radius = std::sqrt(std::max({(t.p[0] - t.centre).SquaredNorm(), (t.p[1] - t.centre).SquaredNorm(),
                                   (t.p[2] - t.centre).SquaredNorm()})) *
                   (1 + 1e-9) +
               1e-7 * gd.Norm() + 1e-13 * t.centre.Norm();
  }
  const size_t T = tri.size();
  struct Near {
    double bound;  // the minimum over a few faces beside the vertex's place: at least its distance
    uint32_t vertex, at;
  };
  std::vector<Near> order;  // the vertices that can move (a frozen one is on the surface)
  order.reserve(W);
  constexpr size_t kBeside = 2;
  for (uint32_t v = 0; v < W; ++v) {
    if (region.frozenVertex[v]) continue;
    const vcg::Point3d p = vcg::Point3d::Construct(local.positions[v]);
    const uint32_t code = morton(p);
    const size_t at =
        size_t(std::lower_bound(tri.begin(), tri.end(), code, [](const Tri& t, uint32_t c) { return t.code < c; }) -
               tri.begin());
    double best = std::numeric_limits<double>::infinity();
    for (size_t i = at > kBeside ? at - kBeside : 0; i < std::min(T, at + kBeside + 1); ++i) {
      const auto& t = tri[i].p;
      best = std::min(best, PointTriangleDistance2(p, t[0], t[1], t[2]));
    }
    order.push_back({best, v, uint32_t(at)});
  }
  std::sort(order.begin(), order.end(), [](const Near& a, const Near& b) {
    return a.bound > b.bound || (a.bound == b.bound && a.vertex < b.vertex);
  });
  // A face is skipped when its sphere's distance squared exceeds the nearest so far by more than
  // rounding could (relative and absolute slack: the face's own distance is never below it).
  const double slack = 1e-12 * gd.SquaredNorm();
  double worst2 = 0;
  for (const Near& n : order) {
    if (T > 0 && n.bound <= worst2) break;  // no vertex left can raise the maximum
    const vcg::Point3d p = vcg::Point3d::Construct(local.positions[n.vertex]);
    const size_t at = n.at;
    double best = n.bound;
    auto visit = [&](const Tri& t) {
      const double c = std::sqrt((p - t.centre).SquaredNorm()) - t.radius;
      if (c > 0 && c * c > best * (1 + 1e-6) + slack) return;
      best = std::min(best, PointTriangleDistance2(p, t.p[0], t.p[1], t.p[2]));
    };
    for (size_t d = 0; d <= T; ++d) {
      bool any = false;
      if (at + d < T) {
        any = true;
        visit(tri[at + d]);
      }
      if (d > 0 && d <= at) {
        any = true;
        visit(tri[at - d]);
      }
      if ((d > 0 && !any) || best <= worst2) break;  // done, or cannot raise the maximum
    }
    worst2 = std::max(worst2, best);
  }
  out.distance = std::sqrt(worst2);
  // The typical distance: the geometric mean of that maximum and the RMS distance over every
  // kSampleStride-th vertex (a frozen one at 0). The maximum alone grows with the group's size
  // and one far vertex; the RMS alone hides a spike (docs/lod_viewer.md, "Fidelity of cuts").
  const uint32_t sampled = (W + kSampleStride - 1) / kSampleStride;
  const double rms = sampled ? std::sqrt(SumSquaredDistances(tri, order, local.positions) / double(sampled)) : 0.0;
  out.typical = std::min(out.distance, std::sqrt(rms * out.distance));
}

// A copy of `faces` with each vertex id replaced by its place (LodAttributes::place: the lowest
// id at its position), as the DAG's topology sees texture seams.
std::vector<Face> FacesByPlace(const std::vector<Face>& faces, const std::vector<uint32_t>& place) {
  std::vector<Face> t(faces);
  for (Face& f : t)
    for (uint32_t& v : f) v = place[v];
  return t;
}

// Per thread: what RecutGroup works in, kept from group to group.
struct RecutScratch {
  std::vector<uint32_t> rank, ids;
  std::vector<uint64_t> keys;
  std::vector<Face> faces;
  std::vector<vcg::Point3f> positions;
};

// A simplified group's faces (r.faces) cut into the next level's clusters, on the group's own
// vertices, on its thread: topology(x) is the id the DAG's topology will see for the group's
// vertex x (a place with texture seams) or, for a new vertex, a stand-in that orders as its
// final id will (any id above the level's vertices plus its index among the group's new ones);
// positionOf(id) that id's position. The ids renumbered densely in their order keep every edge's
// key order, so GrowClusters cuts the same clusters as on the DAG's ids once the group's new
// vertices are numbered (BuildLevels, StreamLevels). (The group's vertices x used are sorted by
// their ids, about half a vertex a face, rather than every corner.)
template <class Topology, class PositionOf>
void RecutGroup(GroupResult& r, Topology topology, PositionOf positionOf, size_t clusterFaces, double angle,
                RecutScratch& s) {
  const size_t F = r.faces.size();
  const size_t X = r.localToGlobal.size() + r.newPositions.size();  // the group's vertices x
  s.rank.assign(X, 0);
  s.keys.clear();
  for (size_t f = 0; f < F; ++f)
    for (size_t i = 0; i < 3; ++i) {
      const uint32_t x = r.faces[f][i];
      if (s.rank[x] == 0) {
        s.rank[x] = 1;
        s.keys.push_back(uint64_t(topology(x)) << 32 | x);
      }
    }
  std::sort(s.keys.begin(), s.keys.end());
  s.ids.clear();
  for (const uint64_t key : s.keys) {
    const uint32_t id = uint32_t(key >> 32);
    if (s.ids.empty() || s.ids.back() != id) s.ids.push_back(id);
    s.rank[uint32_t(key)] = uint32_t(s.ids.size() - 1);
  }
  s.faces.resize(F);
  for (size_t f = 0; f < F; ++f)
    for (size_t i = 0; i < 3; ++i) s.faces[f][i] = s.rank[r.faces[f][i]];
  s.positions.resize(s.ids.size());
  for (size_t j = 0; j < s.ids.size(); ++j) s.positions[j] = positionOf(s.ids[j]);
  r.clusters = GrowClusters(s.faces, s.positions, clusterFaces, angle, r.cluster);
}

// Marks in `shared` (V vertices) every vertex that faces of two groups use (vertexOf: a face
// corner's vertex), the groups side by side: a vertex's owner is the first group to claim it,
// and one that finds another there marks it shared, whatever the order.
template <class VertexOf>
void MarkShared(const std::vector<Face>& faces, const std::vector<std::vector<uint32_t>>& groupFaces, size_t V,
                VertexOf vertexOf, unsigned threads, std::vector<uint8_t>& shared) {
  constexpr int kShared = -2;
  std::unique_ptr<std::atomic<int>[]> owner(new std::atomic<int>[V]);
  const int G = int(groupFaces.size());
  ParallelChunks(V, threads, size_t(1) << 16, [&](size_t b, size_t e, unsigned) {
    for (size_t v = b; v < e; ++v) owner[v].store(-1, std::memory_order_relaxed);
  });
  ParallelChunks(size_t(G), threads, 1, [&](size_t b, size_t e, unsigned) {
    for (int g = int(b); g < int(e); ++g)
      for (uint32_t f : groupFaces[size_t(g)])
        for (uint32_t w : faces[f]) {
          std::atomic<int>& o = owner[vertexOf(w)];
          int seen = o.load(std::memory_order_relaxed);
          while (seen != g && seen != kShared) {
            if (seen < 0 ? o.compare_exchange_weak(seen, g, std::memory_order_relaxed)
                         : (o.store(kShared, std::memory_order_relaxed), true))
              break;
          }
        }
  });
  ParallelChunks(V, threads, size_t(1) << 16, [&](size_t b, size_t e, unsigned) {
    for (size_t v = b; v < e; ++v)
      if (owner[v].load(std::memory_order_relaxed) == kShared) shared[v] = 1;
  });
}

// The levels above `firstK` (dag.levels[firstK] built, its clusters in the kd chunks `clusterNode`
// at kd depth `depth`, the leaves at `leafDepth`): BuildDag's steps 2-5 up to the top.
Status BuildLevels(const LodBuildParams& params, const Progress& progress, LodSpill* spill, size_t inputFaces,
                   double diagonal, unsigned threads, int firstK, int leafDepth, int depth,
                   std::vector<uint32_t>& clusterNode, LodDag& dag) {
  Status s;
  // Texture seams: the ids of one position are one place for the topology (clusters, groups,
  // frozen borders); the faces by place (FacesByPlace) where the ids would split them.
  std::vector<uint32_t>& place = dag.attributes.place;
  const bool wedges = !place.empty();
  auto byPlace = [&](const std::vector<Face>& faces) { return FacesByPlace(faces, place); };
  // Sibling chunks merge one kd depth per level (level k groups within the chunks at depth
  // leafDepth - k - sooner), and one more each time a level no longer shrinks under their locked
  // borders.
  int sooner = 0;
  // The top. When a level no longer shrinks (the locked borders between groups leave no collapse
  // under the cap), each connected part of the mesh of at most 4 groups' clusters becomes one
  // group: nothing of it is locked, and a part down to one cluster stays as it is. When that no
  // longer shrinks either, the cap is doubled, once, and then a level must shrink by a quarter
  // (a smaller step is a near copy of poor collapses: the dragon's last levels were 3-4x MeshLab's
  // RMS uncapped, 1.0x with the cap doubled twice). Only a top still above 1 % of the input goes
  // on without the cap (a coarse input: the tests' tiny spheres).
  double cap = params.maxGroupError;  // 0: no cap
  bool wholeParts = false;
  const size_t wholeUpTo = size_t(4 * params.groupClusters);
  for (int k = firstK; size_t(k + 2) < 64; ++k) {
    if (progress && !progress(std::min(95, 10 + 8 * k), "LOD: simplifying groups")) {
      dag = LodDag();
      return Status::Cancelled();
    }
    LodDag::Level& L = dag.levels[size_t(k)];
    if (L.clusterCount() <= 1 && depth == 0) break;
    StageLog::Scope levelStage("level k, whole", k);
    if (depth > 0) {
      const int want = std::max(0, leafDepth - k - sooner);
      if (want < depth)
        for (uint32_t& n : clusterNode) n >>= (depth - want);
      depth = std::min(depth, want);
    }
    std::vector<int> group;
    const int per = GroupClustersOf(params, L.faces.size(), inputFaces);
    const bool merge = MergesSmallGroups(params, L.faces.size(), inputFaces);
    const double ratio = LevelRatioOf(params, L.faces.size(), inputFaces, wholeParts);
    LodDag::Level topology;  // with places: L's faces by place
    if (wedges) {
      topology.faces = byPlace(L.faces);
      topology.faceCluster = L.faceCluster;
      topology.clusterGroup = L.clusterGroup;
      topology.clusterCreator = L.clusterCreator;
    }
    const LodDag::Level& T = wedges ? topology : L;
    const double across = params.lockedBorderWeight;
    int G = depth > 0 && !wholeParts ? GroupClustersByChunk(T, per, clusterNode, threads, group, across, merge) : -1;
    if (G < 0)
      G = GroupClusters(T, per, wholeParts ? wholeUpTo : 0, group, depth > 0 ? &clusterNode : nullptr,
                        dag.positions.size(), threads, across, merge);
    std::vector<Face>().swap(topology.faces);
    std::vector<uint32_t> groupNode;
    if (depth > 0) {
      groupNode.assign(size_t(G), 0);
      for (size_t c = 0; c < group.size(); ++c) groupNode[size_t(group[c])] = clusterNode[c];
    }
    // Faces per group; vertices shared by two groups stay frozen.
    std::vector<std::vector<uint32_t>> groupFaces(static_cast<size_t>(G));
    {
      std::vector<uint32_t> count(static_cast<size_t>(G), 0);
      for (uint32_t c : L.faceCluster) ++count[size_t(group[c])];
      for (int g = 0; g < G; ++g) groupFaces[size_t(g)].reserve(count[size_t(g)]);
    }
    for (uint32_t f = 0; f < L.faces.size(); ++f) groupFaces[size_t(group[L.faceCluster[f]])].push_back(f);
    std::vector<uint8_t> shared(dag.positions.size(), 0);
    if (wedges)  // (a place: the lowest id at its position)
      MarkShared(
          L.faces, groupFaces, shared.size(), [&](uint32_t w) { return place[w]; }, threads, shared);
    else
      MarkShared(
          L.faces, groupFaces, shared.size(), [](uint32_t w) { return w; }, threads, shared);
    // A group that is a whole part (no shared vertex) and one cluster stays as it is at the top.
    std::vector<uint8_t> keep(static_cast<size_t>(G), 0);
    if (wholeParts) {
      std::vector<uint32_t> clustersOfGroup(static_cast<size_t>(G), 0);
      for (int g : group) ++clustersOfGroup[size_t(g)];
      for (int g = 0; g < G; ++g) keep[size_t(g)] = clustersOfGroup[size_t(g)] <= 1;
      for (uint32_t f = 0; f < L.faces.size(); ++f)
        for (uint32_t v : L.faces[f])
          if (shared[wedges ? place[v] : v]) keep[size_t(group[L.faceCluster[f]])] = 0;
    }
    // Each group simplified and re-cut into the next level's clusters (on its own vertices: the
    // new ones stand in as P0 + their index, below their final ids' order; RecutGroup).
    const uint32_t P0 = uint32_t(dag.positions.size());
    const double angle = ClusterAngle(params, k + 1);
    std::vector<GroupResult> results(static_cast<size_t>(G));
    ParallelItems<RecutScratch>(size_t(G), threads, [&](size_t g, RecutScratch& scratch) {
      GroupResult& r = results[g];
      SimplifyGroup(L.faces, groupFaces[g], dag.positions, shared, params, ratio, cap, diagonal, keep[g] != 0,
                    dag.attributes, r);
      const uint32_t V = uint32_t(r.localToGlobal.size());
      auto positionOf = [&](uint32_t id) { return id < P0 ? dag.positions[id] : r.newPositions[id - P0]; };
      if (wedges)
        RecutGroup(
            r,
            [&](uint32_t x) {
              if (x < V) return place[r.localToGlobal[x]];
              const uint32_t p = r.newPlace[x - V];
              return p < V ? place[r.localToGlobal[p]] : P0 + (p - V);
            },
            positionOf, params.clusterFaces, angle, scratch);
      else
        RecutGroup(
            r, [&](uint32_t x) { return x < V ? r.localToGlobal[x] : P0 + (x - V); }, positionOf, params.clusterFaces,
            angle, scratch);
    });
    std::vector<std::vector<uint32_t>>().swap(groupFaces);
    size_t newFaces = 0;
    for (const auto& r : results) newFaces += r.faces.size();
    // (With texture seams a level must shrink by a tenth: the seams and chart junctions stay, and
    // the dragon's atlas gave levels of 0.92-0.96 of the one below, near copies of it that cost as
    // much file as the input's faces and refine nothing away.)
    const double shrink = cap > params.maxGroupError ? 0.75 : wedges ? 0.9 : 0.97;
    if (double(newFaces) > shrink * double(L.faces.size())) {
      if (depth > 0)
        ++sooner;  // the chunks' borders hold it: merge them
      else if (!wholeParts)
        wholeParts = true;
      else if (cap > 0 && cap < 2 * params.maxGroupError)
        cap *= 2;
      else if (cap > 0 && 100 * L.faces.size() > inputFaces)
        cap = 0;
      else
        break;  // no longer shrinks: L is the top
      --k;
      continue;
    }
    // The new level: global ids for the new vertices (group order: deterministic), the groups'
    // clusters in group order; each group's part written on its thread.
    std::vector<float> groupError(static_cast<size_t>(G), 0.f);
    {
      std::vector<double> maxChild(static_cast<size_t>(G), 0.0);
      for (uint32_t c = 0; c < L.clusterCount(); ++c)
        maxChild[size_t(group[c])] = std::max(maxChild[size_t(group[c])], double(L.clusterError[c]));
      for (int g = 0; g < G; ++g)
        groupError[size_t(g)] = GroupErrorAbove(maxChild[size_t(g)], results[size_t(g)].distance);
    }
    std::vector<uint32_t> firstNew(size_t(G) + 1), firstFace(size_t(G) + 1), firstCluster(size_t(G) + 1);
    firstNew[0] = P0;
    firstFace[0] = firstCluster[0] = 0;
    for (int g = 0; g < G; ++g) {
      const GroupResult& r = results[size_t(g)];
      firstNew[size_t(g) + 1] = firstNew[size_t(g)] + uint32_t(r.newPositions.size());
      firstFace[size_t(g) + 1] = firstFace[size_t(g)] + uint32_t(r.faces.size());
      firstCluster[size_t(g) + 1] = firstCluster[size_t(g)] + r.clusters;
    }
    LodAttributes& A = dag.attributes;
    const size_t P1 = firstNew[size_t(G)];
    dag.positions.resize(P1);
    if (!A.colors.empty()) A.colors.resize(P1);
    if (!A.normals.empty()) A.normals.resize(P1);
    if (!A.texCoords.empty()) A.texCoords.resize(P1);
    if (wedges) place.resize(P1);
    LodDag::Level N;
    const uint32_t NC = firstCluster[size_t(G)];
    N.faces.resize(firstFace[size_t(G)]);
    N.faceCluster.resize(N.faces.size());
    N.clusterGroup.assign(NC, -1);
    N.clusterCreator.resize(NC);
    N.clusterError.resize(NC);
    N.clusterTypical.resize(NC);
    std::vector<uint32_t> nextNode(depth > 0 ? NC : 0);
    {
      ParallelChunks(size_t(G), threads, 1, [&](size_t b, size_t e, unsigned) {
        for (int g = int(b); g < int(e); ++g) {
          GroupResult& r = results[size_t(g)];
          const uint32_t V = uint32_t(r.localToGlobal.size()), first = firstNew[size_t(g)];
          std::copy(r.newPositions.begin(), r.newPositions.end(), dag.positions.begin() + first);
          const LodAttributes& a = r.newAttributes;  // (per new vertex, each stream the DAG carries)
          if (!a.colors.empty()) std::copy(a.colors.begin(), a.colors.end(), A.colors.begin() + first);
          if (!a.normals.empty()) std::copy(a.normals.begin(), a.normals.end(), A.normals.begin() + first);
          if (!a.texCoords.empty()) std::copy(a.texCoords.begin(), a.texCoords.end(), A.texCoords.begin() + first);
          // The place of a new vertex: an input one's (already there), or the first new one's.
          for (size_t j = 0; j < r.newPlace.size(); ++j) {
            const uint32_t x = r.newPlace[j];
            place[first + j] = x < V ? place[r.localToGlobal[x]] : first + (x - V);
          }
          const uint32_t f0 = firstFace[size_t(g)], c0 = firstCluster[size_t(g)];
          for (size_t f = 0; f < r.faces.size(); ++f) {
            Face& u = N.faces[f0 + f];
            for (size_t i = 0; i < 3; ++i) {
              const uint32_t t = r.faces[f][i];
              u[i] = t < V ? r.localToGlobal[t] : first + (t - V);
            }
            N.faceCluster[f0 + f] = c0 + r.cluster[f];
          }
          for (uint32_t c = c0; c < c0 + r.clusters; ++c) {
            N.clusterCreator[c] = g;
            N.clusterError[c] = groupError[size_t(g)];
            N.clusterTypical[c] = float(r.typical);
            if (depth > 0) nextNode[c] = groupNode[size_t(g)];
          }
          r = GroupResult();  // free it
        }
      });
    }
    L.clusterGroup = group;
    L.groupError = groupError;
    dag.levels.push_back(std::move(N));
    clusterNode.swap(nextNode);
    if (spill) {  // level k is finished: only its per-cluster fields stay
      s = spill->put(size_t(k), dag.levels[size_t(k)], dag.positions);
      if (!s.ok()) {
        dag = LodDag();
        return s;
      }
    }
  }
  return Status::Ok();
}

// The streamed build's levels from firstK up while its kd chunks have not merged into one
// (BuildLodDagFromChunks; docs/scale.md). Level k is in the spill, its faces chunk after chunk
// (the clusters of one chunk consecutive, their faces too), and only its per-cluster fields in the
// DAG; clusterFaces: per cluster of level k, its face count. Level k is read back a chunk at a
// time, twice: the first pass marks the vertices two chunks use (two bits a vertex of the DAG);
// the second groups each chunk's clusters alone and simplifies its groups (side by side on the
// threads) with every vertex two groups share frozen, those two chunks share included, and
// appends the chunk's part of level k + 1 to the spill. The DAG is the one BuildLevels builds from
// the same level (the same groups as GroupClustersByChunk's, the same frozen vertices, new
// vertices numbered in group order); a level that does not shrink under the chunks' borders is
// dropped and built again with the chunks one depth coarser, as BuildLevels does. Once the chunks
// have merged into one, level k is read whole and BuildLevels goes on.
Status StreamLevels(const LodBuildParams& params, const Progress& progress, LodSpill& spill, size_t inputFaces,
                    double diagonal, unsigned threads, int firstK, int leafDepth, std::vector<uint32_t>& clusterNode,
                    std::vector<uint32_t>& clusterFaces, LodDag& dag) {
  const double cap = params.maxGroupError;
  auto fail = [&](const Status& s) {
    dag = LodDag();
    return s;
  };
  const Status bad = Status::Invalid("internal error: bad LOD chunks");
  int sooner = 0, depth = leafDepth;
  int k = firstK;
  for (; size_t(k + 2) < 64; ++k) {
    if (progress && !progress(std::min(95, 10 + 8 * k), "LOD: simplifying groups chunk by chunk"))
      return fail(Status::Cancelled());
    const int want = std::max(0, leafDepth - k - sooner);
    if (want < depth)
      for (uint32_t& n : clusterNode) n >>= (depth - want);
    depth = std::min(depth, want);
    if (depth == 0) {  // one chunk left: level k whole, and the in-memory build goes on
      LodDag::Level& L = dag.levels[size_t(k)];
      const Status s = spill.get(size_t(k), L.faces, L.faceCluster);
      if (!s.ok()) return fail(s);
      spill.drop(size_t(k));
      std::vector<uint32_t>().swap(clusterFaces);
      return BuildLevels(params, progress, &spill, inputFaces, diagonal, threads, k, leafDepth, 0, clusterNode, dag);
    }
    const uint64_t F = spill.faceCount(size_t(k));
    const size_t C = clusterNode.size();
    if (dag.levels[size_t(k)].clusterCount() != C || clusterFaces.size() != C) return fail(bad);
    // The chunks: runs of clusters of one kd node, and where their faces end.
    std::vector<uint32_t> firstCluster;
    std::vector<uint64_t> faceEnd;
    {
      uint64_t at = 0;
      for (size_t c = 0; c < C; ++c) {
        if (c > 0 && clusterNode[c] < clusterNode[c - 1]) return fail(bad);
        if (c == 0 || clusterNode[c] != clusterNode[c - 1]) {
          if (c > 0) faceEnd.push_back(at);
          firstCluster.push_back(uint32_t(c));
        }
        at += clusterFaces[c];
      }
      faceEnd.push_back(at);
      firstCluster.push_back(uint32_t(C));
      if (at != F) return fail(bad);
    }
    const size_t chunks = faceEnd.size();
    auto faceBegin = [&](size_t r) { return r ? faceEnd[r - 1] : uint64_t(0); };
    std::vector<Face> faces;
    std::vector<uint32_t> faceCluster;
    StageLog::Scope pass1("level k, pass 1 (two chunks' vertices)", k);
    // Pass 1: the vertices of two chunks.
    const size_t P = dag.positions.size();
    std::vector<uint64_t> border((P + 63) / 64, 0);
    {
      // seen: the vertices of the chunks before; here: this chunk's (cleared after it).
      std::vector<uint64_t> seen((P + 63) / 64, 0), here((P + 63) / 64, 0);
      for (size_t r = 0; r < chunks; ++r) {
        Status s = spill.get(size_t(k), faceBegin(r), faceEnd[r], faces, faceCluster);
        if (!s.ok()) return fail(s);
        for (const Face& t : faces)
          for (uint32_t v : t) {
            if (v >= P) return fail(bad);
            const uint64_t bit = uint64_t(1) << (v & 63);
            if (here[v >> 6] & bit) continue;
            here[v >> 6] |= bit;
            if (seen[v >> 6] & bit) border[v >> 6] |= bit;
          }
        for (const Face& t : faces)
          for (uint32_t v : t) {
            seen[v >> 6] |= here[v >> 6];
            here[v >> 6] = 0;
          }
      }
    }
    pass1.Lap();
    StageLog::Sum sRead("level k, read"), sPrepare("level k, renumber, group, mark"),
        sSimplify("level k, simplify, recut"), sPlace("level k, place, spill");
    // Pass 2: each chunk's groups, simplified, and its part of level k + 1, a wave of chunks at a
    // time (as level 0's, BuildLodDagFromChunks): (a) the wave's chunks read (in order), each put in
    // its own vertex ids, grouped and its frozen vertices marked (a chunk per thread); (b) every
    // group of the wave simplified and re-cut (a group per thread); (c) in chunk order, each
    // chunk's new vertex ids, per-cluster fields and faces, and its part of level k + 1 appended.
    // Only (c) numbers anything across chunks, in chunk order: the file does not depend on the
    // wave's size. A chunk of the wave holds its own bitset of the DAG's vertices.
    const int per = GroupClustersOf(params, F, inputFaces);
    const bool merge = MergesSmallGroups(params, F, inputFaces);
    const double ratio = LevelRatioOf(params, F, inputFaces);
    const double angle = ClusterAngle(params, k + 1);
    LodDag::Level& L = dag.levels[size_t(k)];
    L.clusterGroup.assign(C, -1);
    L.groupError.clear();
    LodDag::Level N;  // level k + 1's per-cluster fields (its faces go to the spill)
    std::vector<uint32_t> nextNode, nextFaces;
    uint64_t newFaces = 0;
    std::vector<Face> out;
    std::vector<uint32_t> outCluster;
    struct GroupPlace {
      uint32_t firstNew, firstCluster;
      size_t firstFace;
    };
    std::vector<GroupPlace> groupAt;
    struct Slot {
      size_t r = 0;
      LodDag::Level sub;  // the chunk (its clusters numbered within it)
      std::vector<uint32_t> faceCluster, verts, rank;
      std::vector<uint64_t> here;  // the chunk's vertices (cleared after it)
      std::vector<int> group;
      int G = 0;
      std::vector<vcg::Point3f> localPos;
      std::vector<uint8_t> localShared;
      std::vector<std::vector<uint32_t>> groupFaces;
      std::vector<GroupResult> results;
      bool bad = false;
    };
    // Chunks side by side: one per thread, as many as the budget holds after the positions and
    // the bitsets (ChunksInFlight), at about 64 bytes a face of the chunk (as level 0's) and its
    // own bitset.
    size_t waveSize;
    {
      uint64_t largest = 1;
      for (size_t r = 0; r < chunks; ++r) largest = std::max<uint64_t>(largest, faceEnd[r] - faceBegin(r));
      waveSize = std::min<size_t>(
          {ChunksInFlight(params, uint64_t(12) * P + P / 4, 64 * largest + P / 8), size_t(threads), chunks});
    }
    std::vector<Slot> slots(waveSize);
    for (Slot& w : slots) w.here.assign((P + 63) / 64, 0);
    std::vector<std::pair<uint32_t, uint32_t>> tasks;  // (slot, group)
    for (size_t r0 = 0; r0 < chunks; r0 += waveSize) {
      if (progress && !progress(std::min(95, 10 + 8 * k), "LOD: simplifying groups chunk by chunk"))
        return fail(Status::Cancelled());
      const size_t n = std::min(waveSize, chunks - r0);
      sRead.Begin();
      for (size_t i = 0; i < n; ++i) {
        Slot& w = slots[i];
        w.r = r0 + i;
        Status s = spill.get(size_t(k), faceBegin(w.r), faceEnd[w.r], w.sub.faces, w.faceCluster);
        if (!s.ok()) return fail(s);
      }
      sRead.End();
      // (a)
      sPrepare.Begin();
      const unsigned inner = unsigned(std::max<size_t>(1, threads / n));
      ParallelChunks(n, threads, 1, [&](size_t b, size_t e, unsigned) {
        for (size_t i = b; i < e; ++i) {
          Slot& w = slots[i];
          LodDag::Level& sub = w.sub;
          const uint32_t c0 = firstCluster[w.r], c1 = firstCluster[w.r + 1];
          const size_t CF = sub.faces.size();
          sub.faceCluster.resize(CF);
          for (size_t f = 0; f < CF; ++f) {
            if (w.faceCluster[f] < c0 || w.faceCluster[f] >= c1) {
              w.bad = true;
              return;
            }
            sub.faceCluster[f] = w.faceCluster[f] - c0;
          }
          sub.clusterGroup.assign(c1 - c0, -1);
          // The chunk in its own vertex ids, in the order of the global ones (verts: the chunk's
          // vertices, read from a bitset of the DAG's; a corner's id: its vertex's rank there,
          // from the words' prefix counts): positions, frozen flags.
          uint32_t lo = ~0u, hi = 0;
          for (const Face& t : sub.faces)
            for (uint32_t v : t) {
              if (v >= P) {
                w.bad = true;
                return;
              }
              w.here[v >> 6] |= uint64_t(1) << (v & 63);
              lo = std::min(lo, v);
              hi = std::max(hi, v);
            }
          w.verts.clear();
          const size_t w0 = CF ? lo >> 6 : 0, w1 = CF ? (hi >> 6) + 1 : 0;
          w.rank.resize(w1 - w0);
          for (size_t x = w0; x < w1; ++x) {
            w.rank[x - w0] = uint32_t(w.verts.size());
            for (uint64_t bits = w.here[x]; bits; bits &= bits - 1)
              w.verts.push_back(uint32_t(64 * x + size_t(__builtin_ctzll(bits))));
          }
          const size_t V = w.verts.size();
          ParallelChunks(CF, inner, size_t(1) << 12, [&](size_t fb, size_t fe, unsigned) {
            for (size_t f = fb; f < fe; ++f)
              for (size_t c = 0; c < 3; ++c) {
                const uint32_t v = sub.faces[f][c];
                const uint64_t below = w.here[v >> 6] & ((uint64_t(1) << (v & 63)) - 1);
                sub.faces[f][c] = w.rank[(v >> 6) - w0] + uint32_t(__builtin_popcountll(below));
              }
          });
          std::fill(w.here.begin() + long(w0), w.here.begin() + long(w1), uint64_t(0));
          sub.clusterCreator.clear();
          if (L.clusterCreator.size() == C)
            sub.clusterCreator.assign(L.clusterCreator.begin() + c0, L.clusterCreator.begin() + c1);
          w.G = GroupClusters(sub, per, 0, w.group, nullptr, V, inner, params.lockedBorderWeight, merge);
          w.localPos.resize(V);
          w.localShared.resize(V);
          for (size_t v = 0; v < V; ++v) {
            w.localPos[v] = dag.positions[w.verts[v]];
            w.localShared[v] = (border[w.verts[v] >> 6] >> (w.verts[v] & 63)) & 1;
          }
          w.groupFaces.assign(static_cast<size_t>(w.G), {});
          for (uint32_t f = 0; f < CF; ++f) w.groupFaces[size_t(w.group[sub.faceCluster[f]])].push_back(f);
          MarkShared(
              sub.faces, w.groupFaces, V, [](uint32_t v) { return v; }, inner, w.localShared);
          w.results.assign(static_cast<size_t>(w.G), GroupResult());
        }
      });
      sPrepare.End();
      for (size_t i = 0; i < n; ++i)
        if (slots[i].bad) return fail(bad);
      // (b) Each group simplified and re-cut into level k + 1's clusters on its thread (its new
      // vertices stand in as V + their index: above the chunk's, as their global ids; RecutGroup).
      sSimplify.Begin();
      tasks.clear();
      for (size_t i = 0; i < n; ++i)
        for (int g = 0; g < slots[i].G; ++g) tasks.emplace_back(uint32_t(i), uint32_t(g));
      ParallelItems<RecutScratch>(tasks.size(), threads, [&](size_t t, RecutScratch& scratch) {
        Slot& w = slots[tasks[t].first];
        const size_t g = tasks[t].second;
        const uint32_t V = uint32_t(w.verts.size());
        GroupResult& res = w.results[g];
        SimplifyGroup(w.sub.faces, w.groupFaces[g], w.localPos, w.localShared, params, ratio, cap, diagonal, false,
                      dag.attributes, res);
        const uint32_t RV = uint32_t(res.localToGlobal.size());
        RecutGroup(
            res, [&](uint32_t x) { return x < RV ? res.localToGlobal[x] : V + (x - RV); },
            [&](uint32_t id) { return id < V ? w.localPos[id] : res.newPositions[id - V]; }, params.clusterFaces, angle,
            scratch);
      });
      sSimplify.End();
      // (c) In chunk order: the chunk's part of level k + 1 in group order: each group's first new
      // vertex id, first cluster and first face (prefix sums, with the per-cluster fields), then
      // each group's new positions and faces written at those places on the threads.
      sPlace.Begin();
      for (size_t i = 0; i < n; ++i) {
        Slot& w = slots[i];
        const int G = w.G;
        const uint32_t c0 = firstCluster[w.r], c1 = firstCluster[w.r + 1];
        std::vector<std::vector<uint32_t>>().swap(w.groupFaces);
        const int groupBase = int(L.groupError.size());
        for (uint32_t c = c0; c < c1; ++c) L.clusterGroup[c] = groupBase + w.group[c - c0];
        std::vector<double> maxChild(static_cast<size_t>(G), 0.0);
        for (uint32_t c = c0; c < c1; ++c)
          maxChild[size_t(w.group[c - c0])] = std::max(maxChild[size_t(w.group[c - c0])], double(L.clusterError[c]));
        groupAt.resize(size_t(G));
        const size_t firstNext = nextFaces.size();
        const uint32_t clusterBase = uint32_t(N.clusterCount());
        {
          size_t id = dag.positions.size(), face = 0;
          uint32_t cluster = clusterBase;
          for (int g = 0; g < G; ++g) {
            const GroupResult& res = w.results[size_t(g)];
            groupAt[size_t(g)] = GroupPlace{uint32_t(id), cluster, face};
            id += res.newPositions.size();
            face += res.faces.size();
            cluster += res.clusters;
            const float ef = GroupErrorAbove(maxChild[size_t(g)], res.distance);
            L.groupError.push_back(ef);
            N.clusterGroup.resize(cluster, -1);
            N.clusterCreator.resize(cluster, groupBase + g);
            N.clusterError.resize(cluster, ef);
            N.clusterTypical.resize(cluster, float(res.typical));
            nextNode.resize(cluster, clusterNode[c0]);
          }
          dag.positions.resize(id);
          out.resize(face);
          outCluster.resize(face);
          nextFaces.resize(firstNext + (cluster - clusterBase), 0);
        }
        ParallelChunks(size_t(G), threads, 1, [&](size_t b, size_t e, unsigned) {
          for (size_t g = b; g < e; ++g) {
            GroupResult& res = w.results[g];
            const GroupPlace& at = groupAt[g];
            const uint32_t RV = uint32_t(res.localToGlobal.size());
            std::copy(res.newPositions.begin(), res.newPositions.end(), dag.positions.begin() + long(at.firstNew));
            uint32_t* count = nextFaces.data() + firstNext + (at.firstCluster - clusterBase);
            for (size_t f = 0; f < res.faces.size(); ++f) {
              Face& u = out[at.firstFace + f];
              for (size_t c = 0; c < 3; ++c) {
                const uint32_t t = res.faces[f][c];
                u[c] = t < RV ? w.verts[res.localToGlobal[t]] : at.firstNew + (t - RV);
              }
              outCluster[at.firstFace + f] = at.firstCluster + res.cluster[f];
              ++count[res.cluster[f]];
            }
            res = GroupResult();
          }
        });
        std::vector<GroupResult>().swap(w.results);
        newFaces += out.size();
        Status s = spill.append(size_t(k + 1), out, outCluster, dag.positions);
        if (!s.ok()) return fail(s);
      }
      sPlace.End();
    }
    std::vector<Slot>().swap(slots);
    for (StageLog::Sum* sum : {&sRead, &sPrepare, &sSimplify, &sPlace}) sum->Flush(k);
    if (double(newFaces) > 0.97 * double(F)) {  // the chunks' borders hold it: merge them one more depth
      dag.positions.resize(P);
      spill.drop(size_t(k + 1));
      L.clusterGroup.assign(C, -1);
      L.groupError.clear();
      ++sooner;
      --k;
      continue;
    }
    Status s = spill.finish(size_t(k + 1));
    if (s.ok()) s = spill.setParts(size_t(k), faceEnd);  // a part a chunk: whole groups
    if (!s.ok()) return fail(s);
    dag.levels.push_back(std::move(N));
    clusterNode.swap(nextNode);
    clusterFaces.swap(nextFaces);
  }
  if (spill.has(size_t(k))) {  // (64 levels) the top: one part
    const Status s = spill.setParts(size_t(k), {spill.faceCount(size_t(k))});
    if (!s.ok()) return fail(s);
  }
  return Status::Ok();
}

// BuildLodDag; with `owned` (== &mesh) the mesh's positions and faces are moved into the DAG; with
// `spill` each finished level is written there (lod_spill.h).
Status BuildDag(const IndexedMesh& mesh, IndexedMesh* owned, const LodBuildParams& params, LodDag& dag,
                const Progress& progress, size_t* chunks, LodSpill* spill, const LodAttributes* attributes) {
  dag = LodDag();
  if (chunks) *chunks = 1;
  Status s = RequireValidForFaces(mesh);
  if (!s.ok()) return s;
  if (attributes) {
    const std::string bad = attributes->Check(mesh.positions.size());
    if (!bad.empty()) return Status::Invalid(bad);
    if (!(params.attributeWeight >= 0) || !std::isfinite(params.attributeWeight))
      return Status::Invalid("the attribute weight must be >= 0");
  }
  {
    GroupQemParams q = params.simplification.qem;
    q.targetFaces = 1;                     // set per group
    q.refreshRatio = params.refreshRatio;  // as SimplifyGroup sets it
    s = ValidateParams(q);
  }
  if (!s.ok()) return s;
  if (!(params.simplification.levelRatio > 0 && params.simplification.levelRatio < 1))
    return Status::Invalid("the level ratio must lie in (0, 1)");
  if (!(params.coarseLevelRatio == 0 || (params.coarseLevelRatio > 0 && params.coarseLevelRatio < 1)))
    return Status::Invalid("the coarse levels' ratio must be 0 or lie in (0, 1)");
  if (!(params.topLevelRatio == 0 || (params.topLevelRatio > 0 && params.topLevelRatio < 1)))
    return Status::Invalid("the top levels' ratio must be 0 or lie in (0, 1)");
  if (params.clusterFaces < 4 || params.clusterFaces > 65536)
    return Status::Invalid("cluster faces must lie in [4, 65536]");
  if (params.groupClusters < 2 || params.groupClusters > 64)
    return Status::Invalid("group clusters must lie in [2, 64]");
  // The other clusters-per-group fields: 0 (off) or as groupClusters.
  for (const auto& f :
       {std::make_pair(params.fineGroupClusters, "fine"), std::make_pair(params.largeFineGroupClusters, "large fine"),
        std::make_pair(params.largeGroupClusters, "large"), std::make_pair(params.topGroupClusters, "top")})
    if (f.first != 0 && (f.first < 2 || f.first > 64))
      return Status::Invalid(std::string(f.second) + " group clusters must be 0 or lie in [2, 64]");
  if (params.largeGroupCount < 1 || params.largeGroupCount > 1024)
    return Status::Invalid("the large groups' count must lie in [1, 1024]");
  if (!(params.topFaceShare >= 0 && params.topFaceShare <= 1))
    return Status::Invalid("the top levels' share of the input's faces must lie in [0, 1]");
  if (!(params.maxGroupError > 0 && params.maxGroupError <= 1))
    return Status::Invalid("the largest group error must lie in (0, 1] (a fraction of the diagonal)");
  if (!(params.grouping.coneThresholdDeg > 0) || !(params.grouping.thresholdGrowth >= 1))
    return Status::Invalid("the cone threshold must be > 0 and its growth >= 1");
  const vcg::Box3d box = UsedVertexBox(mesh);
  const double diagonal = box.IsNull() ? 0.0 : box.Diag();
  const size_t inputFaces = mesh.faces.size();
  const unsigned threads = unsigned(std::max(1, SimplificationThreads(params.simplification)));
  // Chunks (params.chunkFaces): clusterNode holds each cluster's kd chunk at depth `depth`.
  std::vector<uint32_t> clusterNode;
  int depth = 0;
  std::vector<uint32_t> leaf;
  if (params.chunkFaces > 0) {
    depth = KdChunks(mesh, params.chunkFaces, leaf);
    if (chunks) *chunks = size_t(1) << depth;
  }
  dag.levels.emplace_back();
  if (owned) {  // `mesh` is *owned: not used below
    dag.positions = std::move(owned->positions);
    dag.levels[0].faces = std::move(owned->faces);
    *owned = IndexedMesh();
  } else {
    dag.positions = mesh.positions;
    dag.levels[0].faces = mesh.faces;
  }
  dag.inputVertices = dag.positions.size();
  if (attributes) dag.attributes = *attributes;
  // Texture seams: the ids of one position are one place for the topology (clusters, groups,
  // frozen borders); the faces by place (FacesByPlace) where the ids would split them.
  std::vector<uint32_t>& place = dag.attributes.place;
  const bool wedges = !place.empty();
  auto byPlace = [&](const std::vector<Face>& faces) { return FacesByPlace(faces, place); };
  {
    if (depth > 0) {  // each chunk's level-0 clusters on its own, chunks side by side
      const uint32_t leaves = 1u << depth;
      std::vector<uint32_t> start(leaves + 1, 0), members(inputFaces), at;
      for (uint32_t l : leaf) ++start[l + 1];
      std::partial_sum(start.begin(), start.end(), start.begin());
      at.assign(start.begin(), start.end() - 1);
      for (uint32_t f = 0; f < inputFaces; ++f) members[at[leaf[f]]++] = f;
      std::vector<uint32_t>().swap(leaf);
      std::vector<uint32_t>().swap(at);
      const std::vector<Face>& inFaces = dag.levels[0].faces;
      std::vector<std::vector<uint32_t>> local(leaves);
      std::vector<uint32_t> count(leaves, 0);
      ParallelItems<std::vector<Face>>(leaves, threads, [&](size_t l, std::vector<Face>& faces) {
        faces.clear();
        for (uint32_t j = start[l]; j < start[l + 1]; ++j) {
          faces.push_back(inFaces[members[j]]);
          if (wedges)
            for (uint32_t& v : faces.back()) v = place[v];
        }
        count[l] = GrowClusters(faces, dag.positions, params.clusterFaces, ClusterAngle(params, 0), local[l]);
      });
      LodDag::Level& L0 = dag.levels[0];
      L0.faceCluster.assign(inputFaces, 0);
      uint32_t base = 0;
      for (uint32_t l = 0; l < leaves; ++l) {
        for (uint32_t j = start[l]; j < start[l + 1]; ++j) L0.faceCluster[members[j]] = base + local[l][j - start[l]];
        clusterNode.insert(clusterNode.end(), count[l], l);
        base += count[l];
        std::vector<uint32_t>().swap(local[l]);
      }
      L0.clusterGroup.assign(base, -1);
      L0.clusterCreator.assign(base, -1);
      L0.clusterError.assign(base, 0.f);
    }
  }
  if (depth == 0) {
    LodDag::Level& L0 = dag.levels[0];
    std::vector<Face> placed;  // (a conditional of byPlace(...) and L0.faces would copy L0.faces)
    if (wedges) placed = byPlace(L0.faces);
    const uint32_t C = GrowClusters(wedges ? placed : L0.faces, dag.positions, params.clusterFaces,
                                    ClusterAngle(params, 0), L0.faceCluster, threads);
    L0.clusterGroup.assign(C, -1);
    L0.clusterCreator.assign(C, -1);
    L0.clusterError.assign(C, 0.f);
  }
  s = BuildLevels(params, progress, spill, inputFaces, diagonal, threads, 0, depth, depth, clusterNode, dag);
  if (!s.ok()) return s;
  if (progress) progress(100, "LOD: DAG built");
  return Status::Ok();
}

}  // namespace

Status BuildLodDagFromChunks(LodChunkedInput& in, const LodBuildParams& params, LodDag& dag, const Progress& progress,
                             LodSpill& spill) {
  dag = LodDag();
  const size_t leaves = in.chunkFaces.size();
  if (in.depth < 1 || leaves != size_t(1) << in.depth || in.border.size() != in.positions.size())
    return Status::Invalid("internal error: bad LOD chunks");
  const double diagonal = in.box.IsNull() ? 0.0 : in.box.Diag();
  const size_t inputFaces = in.inputFaces;
  const unsigned threads = unsigned(std::max(1, SimplificationThreads(params.simplification)));
  const size_t V0 = in.positions.size();
  dag.positions = std::move(in.positions);
  dag.inputVertices = V0;
  // Per input vertex: 2 when two chunks use it (frozen for good at level 0), 1 while two groups
  // of the chunk being built use it.
  std::vector<uint8_t> shared = std::move(in.border);
  for (uint8_t& b : shared) b = b ? 2 : 0;
  std::vector<int> owner(V0, -1);
  dag.levels.resize(2);
  LodDag::Level& L0 = dag.levels[0];
  LodDag::Level& N = dag.levels[1];  // its per-cluster fields (its faces go to the spill, chunk by chunk)
  std::vector<uint32_t> nextNode, nextFaces;
  std::vector<Face> out;
  std::vector<uint32_t> outCluster;
  const int per = GroupClustersOf(params, inputFaces, inputFaces);  // level 0
  const bool merge = MergesSmallGroups(params, inputFaces, inputFaces);
  const double ratio = LevelRatioOf(params, inputFaces, inputFaces);
  const double angle0 = ClusterAngle(params, 0), angle1 = ClusterAngle(params, 1);
  // Chunks are made a wave at a time, the wave's chunks side by side (issue 27): (a) each chunk's
  // file read, cut into clusters and grouped, its vertices two of its groups use marked (a chunk
  // per thread); (b) every group of the wave simplified (a group per thread); (c) in chunk order,
  // the first DAG id of each group's new vertices (prefix sums) and its chunk's marks cleared (a
  // chunk per thread); (d) each simplified group's new positions stored at its ids, its faces put
  // in DAG ids and re-cut into level 1's clusters (a group per thread); (e) in chunk order, the
  // records and the spill, on one thread while the next wave's (a) runs on the others. Only (c)
  // and (e) decide what the chunks share, in the order of the one-chunk-at-a-time build, so the
  // DAG does not depend on the thread count. A vertex used by one chunk only is marked by that
  // chunk alone (those two chunks use are frozen already and not marked), so the wave's chunks
  // mark and clear disjoint entries of owner / shared. A wave holds one chunk per thread, as many
  // as three quarters of the budget left by the arrays per vertex allow: a chunk in flight and its
  // faces waiting for (e) take about 64 bytes a face of the chunk (docs/scale.md: 28 MiB more a
  // chunk for chunks of 436 k faces); the positions (12 bytes a vertex, up to about 1.45 vertices
  // of the DAG an input vertex), owner / shared (5 bytes an input vertex) and the rest stay.
  // (What stays, measured: 20-34 bytes an input vertex and the process's few MiB.)
  size_t chunksInFlight;
  {
    uint64_t largest = 1;
    for (uint64_t f : in.chunkFaces) largest = std::max<uint64_t>(largest, f);
    chunksInFlight = ChunksInFlight(params, uint64_t(30) * V0, 64 * largest);
  }
  struct ChunkWork {
    size_t chunk = 0;
    LodDag::Level sub;  // the chunk's level 0 (clusters numbered within the chunk)
    std::vector<int> group;
    int groups = 0;
    std::vector<std::vector<uint32_t>> groupFaces;
    std::vector<GroupResult> results;
    std::vector<std::vector<Face>> faces;          // per group: its simplified faces, DAG ids
    std::vector<uint32_t> firstNew;                // per group: the DAG id of its first new vertex
    std::vector<std::vector<uint32_t>> clusterOf;  // per group: level 1's cluster of each face
    std::vector<uint32_t> clusters;                // per group: level 1's clusters in it
    std::vector<float> error;                      // per group
    std::vector<float> typical;                    // per group
    Status status;
  };
  auto prepare = [&](ChunkWork& w) {
    const size_t l = w.chunk;
    const size_t F = size_t(in.chunkFaces[l]);
    LodDag::Level& sub = w.sub;
    sub.faces.resize(F);
    {
      std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(spill.chunk(l).c_str(), "rb"), &std::fclose);
      if (!f || std::fread(sub.faces.data(), sizeof(Face), F, f.get()) != F) {
        w.status = Status::Invalid("cannot read '" + spill.chunk(l) + "' (the temporary folder of --memory)");
        return;
      }
    }
    std::remove(spill.chunk(l).c_str());
    for (const Face& t : sub.faces)
      for (uint32_t v : t)
        if (v >= V0) {
          w.status = Status::Invalid("internal error: bad LOD chunk file");
          return;
        }
    const uint32_t C = GrowClusters(sub.faces, dag.positions, params.clusterFaces, angle0, sub.faceCluster);
    sub.clusterGroup.assign(C, -1);
    w.groups = GroupClusters(sub, per, 0, w.group, nullptr, 0, 1, 1, merge);
    w.groupFaces.resize(size_t(w.groups));
    for (uint32_t f = 0; f < F; ++f) w.groupFaces[size_t(w.group[sub.faceCluster[f]])].push_back(f);
    for (uint32_t f = 0; f < F; ++f) {
      const int g = w.group[sub.faceCluster[f]];
      for (uint32_t v : sub.faces[f]) {
        if (shared[v] & 2) continue;  // frozen already (and used by another chunk of the wave)
        if (owner[v] < 0)
          owner[v] = g;
        else if (owner[v] != g)
          shared[v] |= 1;
      }
    }
    w.results.resize(size_t(w.groups));
  };
  std::vector<uint32_t> globalCluster;
  // (e) of one chunk: group after group.
  auto emit = [&](ChunkWork& w) -> Status {
    const size_t F = w.sub.faces.size();
    const uint32_t clusterBase = uint32_t(L0.clusterGroup.size());
    const int groupBase = int(L0.groupError.size());
    for (uint32_t c = 0; c < uint32_t(w.sub.clusterGroup.size()); ++c) {
      L0.clusterGroup.push_back(groupBase + w.group[c]);
      L0.clusterCreator.push_back(-1);
      L0.clusterError.push_back(0.f);
    }
    out.clear();
    outCluster.clear();
    for (int g = 0; g < w.groups; ++g) {
      const float ef = w.error[size_t(g)];
      L0.groupError.push_back(ef);
      const std::vector<Face>& faces = w.faces[size_t(g)];
      const std::vector<uint32_t>& clusterOfFace = w.clusterOf[size_t(g)];
      const uint32_t NC = w.clusters[size_t(g)];
      const uint32_t base = uint32_t(N.clusterCount());
      const size_t firstNext = nextFaces.size();
      nextFaces.resize(firstNext + NC, 0);
      for (size_t f = 0; f < faces.size(); ++f) {
        out.push_back(faces[f]);
        outCluster.push_back(base + clusterOfFace[f]);
        ++nextFaces[firstNext + clusterOfFace[f]];
      }
      for (uint32_t c = 0; c < NC; ++c) {
        N.clusterGroup.push_back(-1);
        N.clusterCreator.push_back(groupBase + g);
        N.clusterError.push_back(ef);
        N.clusterTypical.push_back(w.typical[size_t(g)]);
        nextNode.push_back(uint32_t(w.chunk));
      }
    }
    globalCluster.resize(F);
    for (uint32_t f = 0; f < F; ++f) globalCluster[f] = clusterBase + w.sub.faceCluster[f];
    Status s = spill.append(0, w.sub.faces, globalCluster, dag.positions);
    if (s.ok()) s = spill.append(1, out, outCluster, dag.positions);
    w = ChunkWork();
    return s;
  };
  auto emitAll = [&](std::vector<ChunkWork>& ws) -> Status {
    Status s;
    for (ChunkWork& w : ws)
      if (s.ok()) s = emit(w);
    ws.clear();
    return s;
  };
  std::vector<ChunkWork> wave, pending;       // pending: the previous wave, waiting for its (e)
  std::vector<std::pair<size_t, int>> tasks;  // (chunk of the wave, group)
  StageLog::Sum stageA("level 0 (a) read, clusters, groups [+ (e)]"), stageB("level 0 (b) simplify"),
      stageC("level 0 (c) ids, clear marks"), stageD("level 0 (d) place, recut"), stageE("level 0 (e) records, spill");
  for (size_t first = 0; first < leaves;) {
    if (progress && !progress(int(10 * first / leaves), "LOD: level 0 chunk by chunk")) {
      dag = LodDag();
      return Status::Cancelled();
    }
    wave.clear();
    for (; first < leaves && wave.size() < std::min<size_t>(threads, chunksInFlight); ++first)
      if (in.chunkFaces[first] > 0) {
        wave.emplace_back();
        wave.back().chunk = first;
      }
    const size_t n = wave.size();
    if (n == 0) continue;
    stageA.Begin();
    {  // (a), and the previous wave's (e) beside it (item 0)
      Status emitted;
      const size_t e = pending.empty() ? 0 : 1;
      ParallelChunks(n + e, threads, 1, [&](size_t b, size_t end, unsigned) {
        for (size_t i = b; i < end; ++i)
          if (i < e)
            emitted = emitAll(pending);
          else
            prepare(wave[i - e]);
      });
      if (!emitted.ok()) {
        dag = LodDag();
        return emitted;
      }
    }
    for (ChunkWork& w : wave)
      if (!w.status.ok()) {
        dag = LodDag();
        return w.status;
      }
    stageA.End();
    tasks.clear();
    for (size_t i = 0; i < n; ++i)
      for (int g = 0; g < wave[i].groups; ++g) tasks.emplace_back(i, g);
    stageB.Begin();
    {  // (b)
      ParallelChunks(tasks.size(), threads, 1, [&](size_t b, size_t e, unsigned) {
        for (size_t t = b; t < e; ++t) {
          ChunkWork& w = wave[tasks[t].first];
          const size_t g = size_t(tasks[t].second);
          SimplifyGroup(w.sub.faces, w.groupFaces[g], dag.positions, shared, params, ratio, params.maxGroupError,
                        diagonal, false, dag.attributes, w.results[g]);
        }
      });
    }
    stageB.End();
    stageC.Begin();
    // (c): the new vertices' ids in chunk and group order, as the one-chunk build numbers them.
    size_t nextId = dag.positions.size();
    for (ChunkWork& w : wave) {
      w.firstNew.resize(size_t(w.groups));
      for (int g = 0; g < w.groups; ++g) {
        w.firstNew[size_t(g)] = uint32_t(nextId);
        nextId += w.results[size_t(g)].newPositions.size();
      }
      w.faces.resize(size_t(w.groups));
      w.error.resize(size_t(w.groups));
      w.typical.resize(size_t(w.groups));
      w.clusterOf.resize(size_t(w.groups));
      w.clusters.resize(size_t(w.groups));
    }
    dag.positions.resize(nextId);
    ParallelChunks(n, threads, 1, [&](size_t b, size_t e, unsigned) {
      for (size_t i = b; i < e; ++i) {
        ChunkWork& w = wave[i];
        for (const Face& t : w.sub.faces)
          for (uint32_t v : t)
            if (!(shared[v] & 2)) {  // (a frozen vertex is never marked, and other chunks use it)
              owner[v] = -1;
              shared[v] = 0;
            }
        std::vector<std::vector<uint32_t>>().swap(w.groupFaces);
      }
    });
    stageC.End();
    stageD.Begin();
    {  // (d)
      ParallelChunks(tasks.size(), threads, 1, [&](size_t b, size_t e, unsigned) {
        for (size_t t = b; t < e; ++t) {
          ChunkWork& w = wave[tasks[t].first];
          const size_t g = size_t(tasks[t].second);
          GroupResult& r = w.results[g];
          const uint32_t V = uint32_t(r.localToGlobal.size());
          const uint32_t firstNew = w.firstNew[g];
          std::copy(r.newPositions.begin(), r.newPositions.end(), dag.positions.begin() + long(firstNew));
          std::vector<Face>& faces = w.faces[g];
          faces.resize(r.faces.size());
          for (size_t f = 0; f < r.faces.size(); ++f)
            for (size_t i = 0; i < 3; ++i) {
              const uint32_t x = r.faces[f][i];
              faces[f][i] = x < V ? r.localToGlobal[x] : firstNew + (x - V);
            }
          w.error[g] = GroupErrorAbove(0.0, r.distance);  // level 0's clusters have error 0
          w.typical[g] = float(r.typical);
          r = GroupResult();
          w.clusters[g] = GrowClusters(faces, dag.positions, params.clusterFaces, angle1, w.clusterOf[g]);
        }
      });
    }
    for (ChunkWork& w : wave) std::vector<GroupResult>().swap(w.results);
    stageD.End();
    if (threads > 1) {  // (e) beside the next wave's (a)
      std::swap(pending, wave);
    } else {  // (e) now: one chunk's work in memory at a time
      stageE.Begin();
      Status s = emitAll(wave);
      stageE.End();
      if (!s.ok()) {
        dag = LodDag();
        return s;
      }
    }
  }
  {
    stageE.Begin();
    Status s = emitAll(pending);
    stageE.End();
    if (!s.ok()) {
      dag = LodDag();
      return s;
    }
  }
  for (StageLog::Sum* sum : {&stageA, &stageB, &stageC, &stageD, &stageE}) sum->Flush();
  std::vector<ChunkWork>().swap(wave);
  std::vector<int>().swap(owner);
  std::vector<uint8_t>().swap(shared);
  std::vector<Face>().swap(out);
  std::vector<uint32_t>().swap(outCluster);
  Status s = spill.finish(0);
  if (s.ok()) s = spill.finish(1);
  if (!s.ok()) {
    dag = LodDag();
    return s;
  }
  s = StreamLevels(params, progress, spill, inputFaces, diagonal, threads, 1, in.depth, nextNode, nextFaces, dag);
  if (!s.ok()) return s;
  if (progress) progress(100, "LOD: DAG built");
  return Status::Ok();
}

Status BuildLodDag(const IndexedMesh& mesh, const LodBuildParams& params, LodDag& out, const Progress& progress,
                   size_t* chunks, const LodAttributes* attributes) {
  return BuildDag(mesh, nullptr, params, out, progress, chunks, nullptr, attributes);
}

Status BuildLodDagOwned(IndexedMesh&& mesh, const LodBuildParams& params, LodDag& out, const Progress& progress,
                        size_t* chunks, LodSpill* spill, const LodAttributes* attributes) {
  return BuildDag(mesh, &mesh, params, out, progress, chunks, spill, attributes);
}

}  // namespace conelod
