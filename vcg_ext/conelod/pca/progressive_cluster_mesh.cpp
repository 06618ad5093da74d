// ConeLOD — the progressive cluster mesh (see progressive_cluster_mesh.h).
#include "conelod/pca/progressive_cluster_mesh.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "conelod/mesh/mesh_check.h"

namespace conelod {

Status ValidateParams(const ProgressiveMeshParams& p) {
  if (p.targetClusters < 1) return Status::Invalid("TargetClusters must be >= 1");
  if (!(p.maxNormalTurnDeg > 0 && p.maxNormalTurnDeg < 180))
    return Status::Invalid("the largest normal turn must be in (0, 180) degrees");
  return Status::Ok();
}

namespace {

// The one-ring of a vertex as its edges (u, x): how many faces use each and their clusters.
struct RingEdge {
  uint32_t other;
  int faces;
  PcaItem label[2];
};

struct Ring {
  std::vector<RingEdge> edges;
  bool manifold = true;  // one fan (closed, or open with two border edges), every edge on 1-2 faces
  bool border = false;
  int clusters = 0;  // distinct clusters of the faces around, counted up to 3
};

class ClusterMeshSimplifier {
 public:
  ClusterMeshSimplifier(const IndexedMesh& mesh, const PcaTree& tree, double cosTurn)
      : tree_(tree), cosTurn_(cosTurn), tri_(mesh.faces) {
    pos_.reserve(mesh.positions.size());
    for (const auto& p : mesh.positions) pos_.push_back(vcg::Point3d::Construct(p));
    const size_t nv = pos_.size(), nf = tri_.size();
    alive_.assign(nf, 1);
    vf_.resize(nv);
    for (uint32_t f = 0; f < nf; ++f)
      for (uint32_t v : tri_[f])
        if (vf_[v].empty() || vf_[v].back() != f) vf_[v].push_back(f);
    label_.resize(nf);
    for (uint32_t f = 0; f < nf; ++f) label_[f] = ItemOfFace(f);
    aliveInNode_.assign(tree.nodes.size(), 0);
    into_.resize(nv);
    for (uint32_t v = 0; v < nv; ++v) into_[v] = v;
    locked_.assign(nv, 0);
    queued_.assign(nv, 0);
    for (uint32_t v = 0; v < nv; ++v) {
      if (vf_[v].empty()) continue;
      analyze(v, ring_);
      if (!ring_.manifold) {
        locked_[v] = 1;
        ++lockedCount_;
      }
    }
  }

  // Undoes the split of `node`: its children become one cluster.
  void merge(int32_t node) {
    const PcaNode& n = tree_.nodes[size_t(node)];
    int32_t alive = 0;
    PcaItem smaller = 0;
    uint32_t smallest = UINT32_MAX;
    for (PcaItem c : tree_.children(node)) {
      alive += IsFaceItem(c) ? alive_[FaceOfItem(c)] : aliveInNode_[size_t(c)];
      if (tree_.itemFaceCount(c) < smallest) {
        smallest = tree_.itemFaceCount(c);
        smaller = c;
      }
    }
    aliveInNode_[size_t(node)] = alive;
    // Vertices that touched both children are vertices of the smaller child's faces.
    auto queueFace = [this](uint32_t f) {
      if (alive_[f])
        for (uint32_t v : tri_[f]) push(v);
    };
    if (IsFaceItem(smaller)) {
      queueFace(FaceOfItem(smaller));
    } else {
      const PcaNode& s = tree_.nodes[size_t(smaller)];
      for (uint32_t k = 0; k < s.faceCount; ++k) queueFace(tree_.faceOrder[s.firstFace + k]);
    }
    for (uint32_t k = 0; k < n.faceCount; ++k) label_[tree_.faceOrder[n.firstFace + k]] = node;
    drain();
  }

  // Retries every vertex until a round removes none (earlier refusals may have become legal).
  void sweep() {
    for (int round = 0; round < 16; ++round) {
      const size_t before = collapses_;
      for (uint32_t v = 0; v < pos_.size(); ++v) push(v);
      drain();
      if (collapses_ == before) break;
    }
  }

  void result(const std::vector<int>& faceClusterOfInput, ProgressiveMeshResult& out) {
    std::vector<uint32_t> index(pos_.size(), UINT32_MAX);
    for (uint32_t f = 0; f < tri_.size(); ++f) {
      if (!alive_[f]) continue;
      for (uint32_t v : tri_[f]) index[v] = 0;
    }
    for (uint32_t v = 0; v < pos_.size(); ++v) {
      if (index[v] == UINT32_MAX) continue;
      index[v] = uint32_t(out.mesh.positions.size());
      out.mesh.positions.push_back(vcg::Point3f::Construct(pos_[v]));
      out.vertexOrigin.push_back(v);
    }
    for (uint32_t f = 0; f < tri_.size(); ++f) {
      if (!alive_[f]) continue;
      const auto& t = tri_[f];
      out.mesh.faces.push_back({index[t[0]], index[t[1]], index[t[2]]});
      out.faceCluster.push_back(faceClusterOfInput[f]);
      out.faceOrigin.push_back(f);
    }
    out.collapses = collapses_;
    out.lockedVertices = lockedCount_;
    out.blockedVertices = 0;
    for (uint32_t v = 0; v < pos_.size(); ++v) {
      if (vf_[v].empty() || locked_[v]) continue;
      analyze(v, ring_);
      if (ring_.clusters + (ring_.border ? 1 : 0) < 3) ++out.blockedVertices;
    }
    // Each input vertex's survivor: the end of its chain of collapses, as a coarse vertex.
    out.survivor.assign(pos_.size(), UINT32_MAX);
    for (uint32_t v = 0; v < pos_.size(); ++v) {
      uint32_t w = v;
      while (into_[w] != w) w = into_[w];
      for (uint32_t x = v; into_[x] != x;) {  // path compression
        const uint32_t next = into_[x];
        into_[x] = w;
        x = next;
      }
      out.survivor[v] = index[w];
    }
  }

 private:
  void push(uint32_t v) {
    if (queued_[v]) return;
    queued_[v] = 1;
    work_.push_back(v);
  }

  void drain() {
    while (!work_.empty()) {
      const uint32_t u = work_.back();
      work_.pop_back();
      queued_[u] = 0;
      if (vf_[u].empty() || locked_[u]) continue;
      uint32_t v;
      if (!TryCollapse(u, v)) continue;
      ++collapses_;
      // The target and its ring changed: they may now be removable, or removable where they were not.
      push(v);
      for (uint32_t f : vf_[v])
        for (uint32_t w : tri_[f]) push(w);
    }
  }

  int32_t aliveIn(PcaItem item) const {
    return IsFaceItem(item) ? alive_[FaceOfItem(item)] : aliveInNode_[size_t(item)];
  }

  void analyze(uint32_t u, Ring& r) const {
    r.edges.clear();
    r.manifold = true;
    r.border = false;
    r.clusters = 0;
    PcaItem labels[2] = {0, 0};
    auto addEdge = [&r](uint32_t x, PcaItem label) {
      for (RingEdge& e : r.edges)
        if (e.other == x) {
          if (e.faces < 2) e.label[e.faces] = label;
          ++e.faces;
          return;
        }
      r.edges.push_back(RingEdge{x, 1, {label, label}});
    };
    for (uint32_t f : vf_[u]) {
      const auto& t = tri_[f];
      const int k = t[0] == u ? 0 : (t[1] == u ? 1 : 2);
      const uint32_t a = t[(k + 1) % 3], b = t[(k + 2) % 3];
      if (a == u || b == u || a == b) {
        r.manifold = false;
        continue;
      }  // a degenerate face
      addEdge(a, label_[f]);
      addEdge(b, label_[f]);
      // Distinct clusters, counted up to 3 ("3 or more" is all that matters).
      const PcaItem l = label_[f];
      if (r.clusters == 0) {
        labels[0] = l;
        r.clusters = 1;
      } else if (l != labels[0] && r.clusters == 1) {
        labels[1] = l;
        r.clusters = 2;
      } else if (l != labels[0] && l != labels[1])
        r.clusters = 3;
    }
    int borderEdges = 0;
    for (const RingEdge& e : r.edges) {
      if (e.faces > 2) r.manifold = false;
      if (e.faces == 1) ++borderEdges;
    }
    if (borderEdges != 0 && borderEdges != 2) r.manifold = false;
    r.border = borderEdges > 0;
    // One fan: faces = edges for a closed fan, edges - 1 for an open one; with every edge on at
    // most two faces, a walk from one border edge (or any edge) must then pass every edge.
    if (!r.manifold) return;
    const size_t faces = vf_[u].size();
    if (faces != r.edges.size() - (r.border ? 1 : 0)) {
      r.manifold = false;
      return;
    }
    size_t walked = 0;
    uint32_t start = r.edges[0].other;
    if (r.border)
      for (const RingEdge& e : r.edges)
        if (e.faces == 1) {
          start = e.other;
          break;
        }
    uint32_t x = start, prevFace = UINT32_MAX;
    for (size_t step = 0; step < faces; ++step) {
      // The face around u through edge (u, x) other than prevFace, and its other ring vertex.
      uint32_t next = UINT32_MAX, nextFace = UINT32_MAX;
      for (uint32_t f : vf_[u]) {
        if (f == prevFace) continue;
        const auto& t = tri_[f];
        if (t[0] != x && t[1] != x && t[2] != x) continue;
        nextFace = f;
        next = (t[0] != u && t[0] != x) ? t[0] : ((t[1] != u && t[1] != x) ? t[1] : t[2]);
        break;
      }
      if (nextFace == UINT32_MAX) break;
      ++walked;
      prevFace = nextFace;
      x = next;
      if (!r.border && x == start) break;
    }
    if (walked != faces) r.manifold = false;
  }

  bool faceHas(uint32_t f, uint32_t v) const {
    const auto& t = tri_[f];
    return t[0] == v || t[1] == v || t[2] == v;
  }

  bool TryCollapse(uint32_t u, uint32_t& target) {
    analyze(u, ring_);
    if (!ring_.manifold) return false;
    const int clusters = ring_.clusters + (ring_.border ? 1 : 0);
    if (clusters >= 3) return false;
    candidates_.clear();
    if (ring_.border) {
      for (const RingEdge& e : ring_.edges)
        if (e.faces == 1) candidates_.push_back(e.other);
    } else if (ring_.clusters == 2) {
      for (const RingEdge& e : ring_.edges)
        if (e.label[0] != e.label[1]) candidates_.push_back(e.other);
      if (candidates_.size() != 2) return false;  // the cluster touches itself at u
    } else {
      for (const RingEdge& e : ring_.edges) candidates_.push_back(e.other);
    }
    const vcg::Point3d pu = pos_[u];
    std::sort(candidates_.begin(), candidates_.end(), [&](uint32_t a, uint32_t b) {
      const double da = (pos_[a] - pu).SquaredNorm(), db = (pos_[b] - pu).SquaredNorm();
      return da != db ? da < db : a < b;
    });
    for (uint32_t v : candidates_) {
      if (locked_[v] || !legal(u, v)) continue;
      collapse(u, v);
      target = v;
      return true;
    }
    return false;
  }

  bool legal(uint32_t u, uint32_t v) {
    // u's ring is in ring_. Lk(uv) = the third vertices of the faces on edge (u, v), plus the
    // virtual border vertex when the edge is on the border.
    analyze(v, ringV_);
    if (!ringV_.manifold) return false;
    PcaItem removedLabel[2];
    int onEdge = 0;
    for (uint32_t f : vf_[u]) {
      if (!faceHas(f, v)) continue;
      if (onEdge == 2) return false;
      removedLabel[onEdge++] = label_[f];
    }
    if (onEdge == 0) return false;
    const bool borderEdge = onEdge == 1;
    // Link condition, the virtual border vertex included.
    size_t common = (ring_.border && ringV_.border) ? 1 : 0;
    for (const RingEdge& a : ring_.edges)
      for (const RingEdge& b : ringV_.edges)
        if (a.other == b.other) {
          ++common;
          break;
        }
    if (common != size_t(onEdge) + (borderEdge ? 1 : 0)) return false;
    // No cluster loses its last face.
    for (int i = 0; i < onEdge; ++i) {
      const int removed = (onEdge == 2 && removedLabel[0] == removedLabel[1]) ? 2 : 1;
      if (aliveIn(removedLabel[i]) <= removed) return false;
    }
    // No face flips or degenerates.
    const vcg::Point3d pv = pos_[v];
    for (uint32_t f : vf_[u]) {
      if (faceHas(f, v)) continue;
      const auto& t = tri_[f];
      const vcg::Point3d a = pos_[t[0]], b = pos_[t[1]], c = pos_[t[2]];
      const vcg::Point3d na = (b - a) ^ (c - a);
      const vcg::Point3d a2 = t[0] == u ? pv : a, b2 = t[1] == u ? pv : b, c2 = t[2] == u ? pv : c;
      const vcg::Point3d nb = (b2 - a2) ^ (c2 - a2);
      const double la = na.Norm(), lb = nb.Norm();
      const double scale = std::max({(b2 - a2).SquaredNorm(), (c2 - a2).SquaredNorm(), (c2 - b2).SquaredNorm()});
      if (!(lb > 1e-10 * scale)) return false;                    // would become degenerate
      if (la > 0 && na * nb <= cosTurn_ * la * lb) return false;  // would turn too far (or flip)
    }
    return true;
  }

  void collapse(uint32_t u, uint32_t v) {
    for (uint32_t f : vf_[u]) {
      if (faceHas(f, v)) {
        alive_[f] = 0;
        const PcaItem l = label_[f];
        if (!IsFaceItem(l)) --aliveInNode_[size_t(l)];
        for (uint32_t w : tri_[f]) {
          if (w == u) continue;
          auto& list = vf_[w];
          list.erase(std::find(list.begin(), list.end(), f));
        }
      } else {
        auto& t = tri_[f];
        for (uint32_t& w : t)
          if (w == u) w = v;
        vf_[v].push_back(f);
      }
    }
    vf_[u].clear();
    vf_[u].shrink_to_fit();
    into_[u] = v;
  }

  const PcaTree& tree_;
  const double cosTurn_;
  std::vector<vcg::Point3d> pos_;
  std::vector<std::array<uint32_t, 3>> tri_;
  std::vector<uint8_t> alive_;
  std::vector<std::vector<uint32_t>> vf_;  // alive faces around each vertex
  std::vector<PcaItem> label_;             // per face: its current cluster
  std::vector<int32_t> aliveInNode_;       // per node: alive faces (while the node is a cluster)
  std::vector<uint32_t> into_;             // per vertex: the vertex it was collapsed into (itself while kept)
  std::vector<uint8_t> locked_, queued_;
  std::vector<uint32_t> work_, candidates_;
  Ring ring_, ringV_;
  size_t collapses_ = 0, lockedCount_ = 0;
};

}  // namespace

Status BuildProgressiveClusterMesh(const IndexedMesh& mesh, const PcaTree& tree, const ProgressiveMeshParams& params,
                                   ProgressiveMeshResult& out, const Progress& progress) {
  out = ProgressiveMeshResult();
  Status s = ValidateParams(params);
  if (!s.ok()) return s;
  s = RequireValidForFaces(mesh);
  if (!s.ok()) return s;
  if (tree.empty() || size_t(tree.faceCount) != mesh.faces.size())
    return Status::Invalid("the PCA tree does not belong to this mesh");

  const std::vector<int32_t> splits = SplitSequence(tree);
  const std::vector<PcaItem> cut = CutByCount(tree, params.targetClusters);
  const int target = int(cut.size());
  int clusters = tree.leafClusterCount();

  ClusterMeshSimplifier simplifier(mesh, tree, std::cos(params.maxNormalTurnDeg * NormalCone::kPi / 180));
  if (progress && !progress(10, "progressive mesh: set-up")) return Status::Cancelled();
  const int merges = std::max(0, clusters - target);
  int done = 0;
  for (size_t i = splits.size(); i-- > 0 && clusters > target;) {
    const int32_t node = splits[i];
    simplifier.merge(node);
    clusters -= tree.children(node).count - 1;
    if (progress && (++done & 1023) == 0 &&
        !progress(10 + 80 * done / std::max(1, merges), "progressive mesh: merging"))
      return Status::Cancelled();
  }
  simplifier.sweep();

  std::vector<int> faceCluster;
  FaceClustersOfCut(tree, cut, faceCluster);
  ProgressiveMeshResult result;
  simplifier.result(faceCluster, result);
  result.clusters = target;
  if (progress && !progress(100, "progressive mesh: done")) return Status::Cancelled();
  out = std::move(result);
  return Status::Ok();
}

Status BuildProgressiveClusterMeshOf(const IndexedMesh& mesh, const ProgressiveMeshParams& params,
                                     ProgressiveMeshResult& out, const Progress& progress, double* treeSeconds) {
  out = ProgressiveMeshResult();
  Status s = ValidateParams(params);
  if (!s.ok()) return s;
  const auto start = std::chrono::steady_clock::now();
  const float scale = float(NormalizingScale(mesh));
  IndexedMesh scaled;
  scaled.faces = mesh.faces;
  scaled.positions.reserve(mesh.positions.size());
  for (const auto& p : mesh.positions) scaled.positions.push_back(p * scale);
  // Checked once scaled (indices and finiteness are the input's): a mesh far beyond kMaxCoordinate,
  // 2^100 across, is about 1 across here, and its output is its input's vertices as given.
  s = RequireValidForFaces(scaled);
  if (!s.ok()) return s;
  PcaTree tree;
  s = BuildPcaTree(scaled, PcaPartitionParams(), tree, SubProgress(progress, 0, 40));
  if (!s.ok()) return s;
  if (treeSeconds) *treeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ProgressiveMeshResult r;
  s = BuildProgressiveClusterMesh(scaled, tree, params, r, SubProgress(progress, 40, 100));
  if (!s.ok()) return s;
  // Every coarse vertex is an input vertex (half-edge collapses move none): its position as given.
  for (size_t v = 0; v < r.mesh.positions.size(); ++v) r.mesh.positions[v] = mesh.positions[r.vertexOrigin[v]];
  out = std::move(r);
  return Status::Ok();
}

}  // namespace conelod
