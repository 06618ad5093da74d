// ConeLOD — view-dependent refinement of a .clod file's node hierarchy, and the cut's mesh (lod.h).
//
// Kamiya, Suzuki, Kawachi, §7: the coarsest level is drawn first; then groups are refined (replaced
// by their children) breadth-first in the order of f(g) = (1 - cos(angle(e,n) + c)) / 2, adjacent
// groups never more than one level apart. We keep the cut as nodes in one of three states (below
// the cut, in it, refined) and a priority queue of the cut's nodes keyed by (back-facing last,
// coarser level first, larger f first). Refining a node first refines, recursively, every coarser
// cut node that covers one of its same-level neighbours, as in a restricted quadtree: after each
// single refinement adjacent cut nodes differ by at most one level. Back-facing nodes (three-state
// cone test, normal_cone.h) wait until no visible node is left to refine, so a full budget still
// ends with every node at level 0.
//
// Two choices of ours. (1) Within a level, visible nodes whose cone axis points towards the eye
// come before those whose axis points away, then f decides. f grows with the angle between the
// axis and the eye, so on its own it refines the far side first wherever the coarse cones are too
// wide to be culled (most of a small budget on the bunny went to the half facing away); the paper
// wants the silhouette and rough groups first, which f still orders within each half. (2) The
// refinement stops at the first node (with the neighbours it forces) that does not fit the budget,
// rather than skipping it for smaller ones, so the cut stays breadth-first.
#include "conelod/lod.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <unordered_map>

namespace conelod {

double RefinementPriority(const LodNode& node, const LodView& view) {
  if (node.cone.empty()) return 0;
  vcg::Point3d e = view.orthographic ? -view.viewDir : view.eye - vcg::Point3d::Construct(node.center);
  const double len = e.Norm();
  if (!(len > 0)) return 1;  // the eye is at the node's centre: refine it early
  e /= len;
  double d = e * node.cone.axis;
  d = std::max(-1.0, std::min(1.0, d));
  const double a = std::acos(d) + std::max(0.0, node.cone.halfAngle);
  if (a >= NormalCone::kPi) return 1;
  return (1 - std::cos(a)) / 2;
}

namespace {
enum : uint8_t { kBelow = 0, kInCut = 1, kRefined = 2 };

struct QueueItem {
  uint8_t culled;
  int level;
  uint8_t facesAway;  // visible, but the cone axis points away from the eye
  double priority;
  uint32_t id;
  // std::priority_queue pops the largest: visible before culled, coarser first, facing the eye
  // before facing away, larger f first, lower id first (deterministic ties).
  bool operator<(const QueueItem& o) const {
    if (culled != o.culled) return culled > o.culled;
    if (level != o.level) return level < o.level;
    if (facesAway != o.facesAway) return facesAway > o.facesAway;
    if (priority != o.priority) return priority < o.priority;
    return id > o.id;
  }
};
}  // namespace

struct LodRefiner::Impl {
  explicit Impl(LodReader& r) : reader(r) {}
  LodReader& reader;
  LodView view;
  std::vector<uint8_t> state;                     // per node id
  std::unordered_map<uint32_t, uint32_t> cutPos;  // node id -> its entry in cut.nodes
  mutable LodCut cut;
  mutable bool statsDirty = true;
  std::priority_queue<QueueItem> queue;
  bool stopped = false;
  bool started = false;

  bool culledNode(const LodNode& n) const {
    if (!view.cullBackFacing) return false;
    const Facing f = view.orthographic
                         ? ClassifyOrtho(n.cone, view.viewDir)
                         : ClassifyPerspective(n.cone, vcg::Point3d::Construct(n.center), n.radius, view.eye);
    return f == Facing::Back;
  }

  // The cone axis points away from the eye (more than 90 degrees from the direction to it).
  bool facesAway(const LodNode& n) const {
    if (!view.cullBackFacing || n.cone.empty() || !n.cone.cullable()) return false;
    const vcg::Point3d toEye = view.orthographic ? -view.viewDir : view.eye - vcg::Point3d::Construct(n.center);
    return toEye * n.cone.axis < 0;
  }

  Status addToCut(uint32_t id) {
    Status s = reader.LoadGeometry(id);
    if (!s.ok()) return s;
    const LodNode& n = reader.node(id);
    const bool culled = culledNode(n);
    state[id] = kInCut;
    cutPos[id] = uint32_t(cut.nodes.size());
    cut.nodes.push_back(id);
    cut.culled.push_back(culled ? 1 : 0);
    cut.faces += n.faceCount;
    if (culled) {
      ++cut.groupsCulled;
    } else {
      ++cut.groupsDrawn;
      cut.drawnFaces += n.faceCount;
    }
    if (n.childCount) queue.push({uint8_t(culled), n.level, uint8_t(facesAway(n)), RefinementPriority(n, view), id});
    statsDirty = true;
    return Status::Ok();
  }

  void removeFromCut(uint32_t id) {
    const LodNode& n = reader.node(id);
    const uint32_t at = cutPos[id];
    const bool culled = cut.culled[at] != 0;
    cut.faces -= n.faceCount;
    if (culled) {
      --cut.groupsCulled;
    } else {
      --cut.groupsDrawn;
      cut.drawnFaces -= n.faceCount;
    }
    const uint32_t last = cut.nodes.back();
    cut.nodes[at] = last;
    cut.culled[at] = cut.culled.back();
    cutPos[last] = at;
    cut.nodes.pop_back();
    cut.culled.pop_back();
    cutPos.erase(id);
    state[id] = kRefined;
    reader.EvictGeometry(id);
    statsDirty = true;
  }

  // The cut node that covers node m (m below the cut): its nearest ancestor in the cut.
  Status covering(uint32_t m, uint32_t& out) {
    Status s = reader.LoadNode(m);
    if (!s.ok()) return s;
    uint32_t at = m;
    for (size_t guard = 0; state[at] != kInCut; ++guard) {
      const int64_t p = reader.node(at).parent;
      if (p < 0 || guard > 64) return Status::Invalid("corrupt file: a node is covered by no node of the cut");
      at = uint32_t(p);
    }
    out = at;
    return Status::Ok();
  }

  // Replaces node id (in the cut) by its children, first refining coarser neighbours.
  Status refine(uint32_t id) {
    if (stopped || state[id] != kInCut) return Status::Ok();
    const LodNode* n = &reader.node(id);
    if (n->childCount == 0) return Status::Ok();
    const int level = n->level;
    const std::vector<uint32_t> neighbours = n->neighbours;  // copy: loading records may rehash
    for (uint32_t m : neighbours) {
      if (m >= state.size()) return Status::Invalid("corrupt file: neighbour id out of range");
      while (state[m] == kBelow) {
        uint32_t c = 0;
        Status s = covering(m, c);
        if (!s.ok()) return s;
        if (reader.node(c).level <= level) break;
        s = refine(c);
        if (!s.ok() || stopped) return s;
        if (state[c] == kInCut) return Status::Invalid("corrupt file: a node could not be refined");
      }
    }
    Status s = reader.LoadChildren(id);
    if (!s.ok()) return s;
    n = &reader.node(id);
    size_t childFaces = 0;
    for (uint32_t c = 0; c < n->childCount; ++c) childFaces += reader.node(n->firstChild + c).faceCount;
    if (cut.faces - n->faceCount + childFaces > view.faceBudget) {
      stopped = true;
      return Status::Ok();
    }
    const uint32_t first = n->firstChild, count = n->childCount;
    removeFromCut(id);
    for (uint32_t c = 0; c < count; ++c) {
      s = addToCut(first + c);
      if (!s.ok()) return s;
    }
    ++cut.refinements;
    return Status::Ok();
  }

  void updateStats() const {
    if (!statsDirty) return;
    // Adjacent cut nodes: for each cut node b and each same-level neighbour m below the cut, the
    // cut node covering m (m in the cut: same level; m refined: its cut descendants see b from
    // their side). The covering node is m's nearest ancestor in the cut.
    int worst = 0;
    for (uint32_t b : cut.nodes) {
      const LodNode& nb = reader.node(b);
      for (uint32_t m : nb.neighbours) {
        if (state[m] != kBelow) continue;
        // While the invariant holds, m's parent is in the cut, and it is a neighbour of b's parent
        // (whose record is loaded: it was refined): found without reading m's record.
        int diff = 0;
        if (nb.parent >= 0)
          for (uint32_t p : reader.node(uint32_t(nb.parent)).neighbours)
            if (state[p] == kInCut) {
              const LodNode& np = reader.node(p);
              if (m >= np.firstChild && m - np.firstChild < np.childCount) diff = 1;
            }
        if (diff == 0) {
          // Otherwise walk up from m, reading its record and its ancestors' if needed.
          uint32_t at = m;
          diff = 2;  // also when the file cannot be read: report a violation
          if (reader.LoadNode(m).ok()) {
            diff = 0;
            while (state[at] != kInCut && reader.node(at).parent >= 0) {
              at = uint32_t(reader.node(at).parent);
              ++diff;
            }
          }
        }
        worst = std::max(worst, diff);
      }
    }
    cut.maxLevelDifference = worst;
    statsDirty = false;
  }
};

LodRefiner::LodRefiner(LodReader& reader) : impl_(new Impl(reader)) {}
LodRefiner::~LodRefiner() = default;

Status LodRefiner::Start(const LodView& view) {
  Impl& m = *impl_;
  // Geometry of the previous cut goes (the roots' is read again just below when needed).
  for (uint32_t id : m.cut.nodes) m.reader.EvictGeometry(id);
  m.view = view;
  m.state.assign(size_t(m.reader.info().nodeCount), kBelow);
  m.cutPos.clear();
  m.cut = LodCut();
  m.queue = std::priority_queue<QueueItem>();
  m.stopped = false;
  m.started = true;
  for (uint32_t r : m.reader.roots()) {
    Status s = m.addToCut(r);
    if (!s.ok()) return s;
  }
  return Status::Ok();
}

Status LodRefiner::Step(size_t maxRefinements) {
  Impl& m = *impl_;
  if (!m.started) return Status::Invalid("LodRefiner::Step before Start");
  size_t done = 0;
  while (done < maxRefinements && !m.stopped && !m.queue.empty()) {
    const QueueItem top = m.queue.top();
    m.queue.pop();
    if (m.state[top.id] != kInCut) continue;
    const size_t before = m.cut.refinements;
    Status s = m.refine(top.id);
    if (!s.ok()) {
      m.stopped = true;
      return s;
    }
    done += m.cut.refinements - before;
  }
  return Status::Ok();
}

bool LodRefiner::Done() const { return !impl_->started || impl_->stopped || impl_->queue.empty(); }

const LodCut& LodRefiner::cut() const {
  impl_->updateStats();
  return impl_->cut;
}

Status RefineLod(LodReader& reader, const LodView& view, LodCut& cut) {
  LodRefiner r(reader);
  Status s = r.Start(view);
  if (!s.ok()) return s;
  while (!r.Done()) {
    s = r.Step(size_t(1) << 30);
    if (!s.ok()) return s;
  }
  cut = r.cut();
  return Status::Ok();
}

Status ExtractCutMesh(LodReader& reader, const LodCut& cut, bool includeCulled, IndexedMesh& out,
                      std::vector<int>* faceLevel, std::vector<uint32_t>* faceNode) {
  out = IndexedMesh();
  if (faceLevel) faceLevel->clear();
  if (faceNode) faceNode->clear();
  if (cut.culled.size() != cut.nodes.size()) return Status::Invalid("ExtractCutMesh: the cut's culled flags do not match its nodes");
  size_t faces = 0, verts = 0;
  for (size_t i = 0; i < cut.nodes.size(); ++i) {
    const uint32_t id = cut.nodes[i];
    if (id >= reader.info().nodeCount) return Status::Invalid("ExtractCutMesh: no node " + std::to_string(id));
    if (!includeCulled && cut.culled[i]) continue;
    Status s = reader.LoadNode(id);
    if (!s.ok()) return s;
    faces += reader.node(id).faceCount;
    verts += reader.node(id).vertexCount;
  }
  out.faces.reserve(faces);
  out.positions.reserve(verts);
  if (faceLevel) faceLevel->reserve(faces);
  if (faceNode) faceNode->reserve(faces);
  // Vertices are welded by (level, vertex id): shared between nodes of one level.
  std::unordered_map<uint64_t, uint32_t> weld;
  weld.reserve(verts);
  std::vector<uint32_t> local;
  for (size_t i = 0; i < cut.nodes.size(); ++i) {
    if (!includeCulled && cut.culled[i]) continue;
    const uint32_t id = cut.nodes[i];
    const bool wasLoaded = reader.geometry(id) != nullptr;
    Status s = reader.LoadGeometry(id);
    if (!s.ok()) return s;
    const LodGeometry& g = *reader.geometry(id);
    const int level = reader.node(id).level;
    local.resize(g.vertexIds.size());
    for (size_t v = 0; v < g.vertexIds.size(); ++v) {
      const uint64_t key = uint64_t(uint32_t(level)) << 32 | g.vertexIds[v];
      auto ins = weld.emplace(key, uint32_t(out.positions.size()));
      if (ins.second) out.positions.push_back(g.positions[v]);
      local[v] = ins.first->second;
    }
    for (const auto& t : g.faces) {
      out.faces.push_back({local[t[0]], local[t[1]], local[t[2]]});
      if (faceLevel) faceLevel->push_back(level);
      if (faceNode) faceNode->push_back(id);
    }
    if (!wasLoaded) reader.EvictGeometry(id);  // leave the reader as it was
  }
  return Status::Ok();
}

}  // namespace conelod
