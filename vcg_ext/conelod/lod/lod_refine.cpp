// ConeLOD — view-dependent refinement of a .clod file's cluster DAG, and the cut's mesh (lod_read.h).
//
// The cut starts at the roots. A group of the DAG can be expanded once every cluster made from it
// (the siblings of a node) is in the cut: they are replaced by the group's own clusters (their
// children). The group's border was locked when it was simplified, so the children meet the rest
// of the cut at the same vertices: every cut reached this way is watertight, whatever the order
// of the expansions. The order is a priority queue of the expandable groups (LodPriority): by
// default the group's error projected on the screen (Karis et al., "Nanite: a deep dive"; refined
// while it exceeds about a pixel), or by the error in model units what an expansion gains for the
// cut's RMS distance per face it adds (ObjectGain), or the paper's f(g) (Kamiya, Suzuki, Kawachi
// §7). Groups whose clusters all face away from the eye (three-state cone test,
// normal_cone.h) come after every other group, so a full budget still ends at level 0. A drawn
// node above the pixel error whose group waits on other groups (some of its clusters not in the
// cut yet) has those expanded first (Impl::Demand), so that a still cut meets the pixel error
// wherever it is drawn. The refinement stops at the first group whose expansion does not fit the
// face budget; by the error in model units (ObjectError) that group is passed over instead, and
// the smaller groups further down the queue that fit fill what is left of the budget; once none
// fits, expansions are undone for others that fit and gain more (Impl::Fill). Culling only
// flags cut nodes as not drawn: it never changes the selection, so the drawn set is a subset of
// a watertight cut whose other nodes face away.
#include "conelod/lod/lod_read.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <unordered_map>

namespace conelod {

double ProjectedError(const LodNode& node, const LodView& view) {
  double d = 1;
  if (!view.orthographic) {
    const vcg::Point3d c = vcg::Point3d::Construct(node.center);
    d = std::max((view.eye - c).Norm() - double(node.radius), 1e-9 * (1 + c.Norm()));
  }
  return double(node.error) / d * (view.projectionScale > 0 ? view.projectionScale : 1.0);
}

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
  uint8_t culled;  // every cluster of the group faces away (and no visible node waits for it)
  double priority;
  double need;   // the largest ProjectedError of its clusters, or of a visible node waiting for it
  uint32_t key;  // the group: its clusters' smallest node id
  // std::priority_queue pops the largest: visible before culled, larger priority first, lower
  // key first (deterministic ties).
  bool operator<(const QueueItem& o) const {
    if (culled != o.culled) return culled > o.culled;
    if (priority != o.priority) return priority < o.priority;
    return key > o.key;
  }
};
}  // namespace

struct LodRefiner::Impl {
  explicit Impl(LodReader& r) : reader(r) {}
  LodReader& reader;
  LodView view;
  std::vector<uint8_t> state;                      // per node id
  std::unordered_map<uint32_t, uint32_t> cutPos;   // node id -> its entry in cut.nodes
  std::unordered_map<uint32_t, uint32_t> present;  // group key -> its clusters in the cut
  // group key -> the largest ProjectedError of a visible cut node that waits for the group's
  // expansion (Demand); such a group is expanded at least with that need.
  std::unordered_map<uint32_t, double> demand;
  mutable LodCut cut;
  mutable bool statsDirty = true;
  std::priority_queue<QueueItem> queue;
  // ObjectError: per group (its first cluster's id), its error accumulated by the mean (MeanError).
  std::unordered_map<uint32_t, double> meanError;
  // ObjectError: the groups expanded, by key, in order (Fill may undo one of them).
  std::vector<uint32_t> expanded;
  bool fillDone = false;  // Fill found no swap that brings the cut closer to its budget
  bool stopped = false;
  bool started = false;

  // ObjectError keeps filling its budget once the queue is empty (Fill).
  bool fillPending() const {
    return view.priority == LodPriority::ObjectError && !fillDone && cut.faces < view.faceBudget;
  }

  bool culledNode(const LodNode& n) const {
    if (!view.cullBackFacing) return false;
    const Facing f = view.orthographic
                         ? ClassifyOrtho(n.cone, view.viewDir)
                         : ClassifyPerspective(n.cone, vcg::Point3d::Construct(n.center), n.radius, view.eye);
    return f == Facing::Back;
  }

  static uint32_t keyOf(const LodNode& n) { return *std::min_element(n.siblings.begin(), n.siblings.end()); }

  // Priority of expanding the group whose clusters are `siblings` (all in the cut).
  double priorityOf(const std::vector<uint32_t>& siblings) const {
    double p = 0;
    for (uint32_t s : siblings) {
      const LodNode& n = reader.node(s);
      double q = 0;
      switch (view.priority) {
        case LodPriority::ObjectError:  // (AddToCut orders these by ObjectGain instead)
          q = n.error;
          break;
        case LodPriority::ConeFg:
          q = RefinementPriority(n, view);
          break;
        case LodPriority::ScreenError:
          q = ProjectedError(n, view);
          break;
      }
      p = std::max(p, q);
    }
    // Screen-space error, culling on: weighted by how squarely the group can face the eye,
    // 1/4 + 3/4 cos(max(0, angle(axis, eye) - half-angle)) at best over its clusters (a group
    // seen edge-on shows its error at the silhouette only).
    if (view.priority == LodPriority::ScreenError && view.cullBackFacing) {
      double facing = 0;
      for (uint32_t s : siblings) {
        const LodNode& n = reader.node(s);
        vcg::Point3d toEye = view.orthographic ? -view.viewDir : view.eye - vcg::Point3d::Construct(n.center);
        const double len = toEye.Norm();
        if (n.cone.empty() || !(len > 0)) {
          facing = 1;
          break;
        }
        const double a = std::acos(std::max(-1.0, std::min(1.0, toEye * n.cone.axis / len)));
        facing = std::max(facing, std::cos(std::min(NormalCone::kPi / 2, std::max(0.0, a - n.cone.halfAngle))));
      }
      p *= 0.25 + 0.75 * facing;
    }
    return p;
  }

  // The error of the group node `id` was made from, accumulated up the DAG by the mean instead of
  // the max: its own distance plus the mean of its clusters' (weighted by their radius squared; 0
  // at level 0). Its own distance is the group's typical one (LodNode::typical: the geometric mean
  // of the RMS and the largest distance of its vertices; version 9), in older files its error less
  // the largest error of its clusters (what the bound grew by when it was simplified: the largest
  // distance alone, which grows with the group's size and one far vertex). The file's error adds
  // the largest of its clusters', so a few far vertices deep below raise every group above them;
  // this one follows the RMS distance of the levels (docs/lod_viewer.md, "Fidelity of cuts").
  // Loads the records below `id` (once: kept).
  Status MeanError(uint32_t id, double& out) {
    out = 0;
    if (reader.node(id).level == 0 || reader.node(id).children.empty()) return Status::Ok();
    const std::vector<uint32_t> children = reader.node(id).children;  // copied: loading records may rehash
    const uint32_t key = *std::min_element(children.begin(), children.end());
    const auto it = meanError.find(key);
    if (it != meanError.end()) {
      out = it->second;
      return Status::Ok();
    }
    Status s = reader.LoadChildren(id);
    if (!s.ok()) return s;
    const double error = reader.node(id).error;
    double area = 0, sum = 0, plain = 0, largest = 0;
    for (uint32_t c : children) {
      const double r2 = double(reader.node(c).radius) * double(reader.node(c).radius);
      largest = std::max(largest, double(reader.node(c).error));
      double below = 0;
      s = MeanError(c, below);
      if (!s.ok()) return s;
      area += r2;
      sum += r2 * below;
      plain += below;
    }
    const double typical = reader.node(id).typical;
    const double own = typical >= 0 ? typical : std::max(0.0, error - largest);
    out = own + (area > 0 ? sum / area : plain / double(children.size()));
    meanError[key] = out;
    return Status::Ok();
  }

  // What expanding the group whose clusters are `siblings` gains for the cut's squared distance,
  // summed over its surface: MeanError^2 x the sum of its clusters' radius squared.
  Status ObjectWorth(const std::vector<uint32_t>& siblings, double& worth) {
    double mean = 0;
    Status s = MeanError(siblings[0], mean);
    if (!s.ok()) return s;
    double area = 0;
    for (uint32_t id : siblings) area += double(reader.node(id).radius) * double(reader.node(id).radius);
    worth = mean * mean * area;
    return Status::Ok();
  }

  // ObjectError's priority of the group whose clusters are `siblings` (all in the cut): its
  // ObjectWorth per face its expansion adds (its children's faces - its clusters').
  // (The file's error alone, the largest distance accumulated by the max, put the dragon's 2 %
  // cut at 2.03x our static collapse at its count: docs/lod_viewer.md.)
  Status ObjectGain(const std::vector<uint32_t>& siblings, double& gain) {
    Status s = ObjectWorth(siblings, gain);
    if (!s.ok()) return s;
    gain /= std::max(1.0, double(Added(siblings[0])));
    return Status::Ok();
  }

  bool pixelStop() const {
    return view.priority == LodPriority::ScreenError && view.projectionScale > 0 && view.maxPixelError > 0;
  }

  // The largest ProjectedError of the clusters `siblings` (all in the cut) that are not culled.
  double needOf(const std::vector<uint32_t>& siblings) const {
    double need = 0;
    for (uint32_t s : siblings)
      if (!cut.culled[cutPos.at(s)]) need = std::max(need, ProjectedError(reader.node(s), view));
    return need;
  }

  // A visible cut node whose projected error is `need` waits for the expansion of the group made
  // of `clusters` (its siblings), which is possible only once all of them are in the cut. The
  // missing ones lie below the cut: each is in the cut once the group of its parents is expanded,
  // and so on up to groups whose clusters are all in the cut. Those are queued with this need,
  // and every group on the way records it, so that it is queued with it once complete. Without
  // this a near group waits on far or back-facing groups whose own error projects to less than a
  // pixel, and the refinement stops with it unrefined (the dragon's head zoomed in: levels 6-7
  // beside a body at level 3).
  Status Demand(const std::vector<uint32_t>& clusters, double need) {
    const uint32_t key = *std::min_element(clusters.begin(), clusters.end());
    auto ins = demand.emplace(key, need);
    if (!ins.second) {
      if (ins.first->second >= need) return Status::Ok();  // already asked for at least as much
      ins.first->second = need;
    }
    bool complete = true;
    for (uint32_t s : clusters) {
      if (s >= state.size()) return Status::Invalid("corrupt file: no node " + std::to_string(s));
      if (state[s] == kInCut) continue;
      complete = false;
      if (state[s] != kBelow) return Status::Ok();  // its group was expanded: nothing to wait for
      Status st = reader.LoadNode(s);
      if (!st.ok()) return st;
      const std::vector<uint32_t> parents = reader.node(s).parents;  // copied: loading records may rehash
      if (parents.empty()) continue;  // a root, not added yet (Start): the group's entry carries the need
      st = Demand(parents, need);
      if (!st.ok()) return st;
    }
    if (complete) queue.push({0, need, need, key});
    return Status::Ok();
  }

  Status AddToCut(uint32_t id) {
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
    statsDirty = true;
    if (!n.children.empty()) {
      const uint32_t key = keyOf(n);
      if (++present[key] == n.siblings.size()) {
        // Every cluster of the group is in the cut: it can be expanded.
        bool allCulled = view.cullBackFacing;
        for (uint32_t sib : n.siblings) {
          if (state[sib] != kInCut)
            return Status::Invalid("corrupt file: node " + std::to_string(id) + "'s siblings disagree");
          if (!cut.culled[cutPos[sib]]) allCulled = false;
        }
        const std::vector<uint32_t> siblings = n.siblings;  // copied: loading records may rehash
        double priority = 0, need = needOf(siblings);
        if (view.priority == LodPriority::ObjectError) {
          Status gs = ObjectGain(siblings, priority);
          if (!gs.ok()) return gs;
        } else {
          priority = priorityOf(siblings);
        }
        const auto d = demand.find(key);
        if (d != demand.end()) {
          allCulled = false;  // a visible node waits for it
          need = std::max(need, d->second);
          if (view.priority == LodPriority::ScreenError) priority = std::max(priority, d->second);
        }
        queue.push({uint8_t(allCulled), priority, need, key});
      } else if (!culled && view.priority == LodPriority::ScreenError) {
        // Visible, its group not complete yet: make way for its expansion when it matters.
        const double need = ProjectedError(n, view);
        if (need > (pixelStop() ? view.maxPixelError : 0.0)) {
          const std::vector<uint32_t> siblings = n.siblings;  // copied: loading records may rehash
          return Demand(siblings, need);
        }
      }
    }
    return Status::Ok();
  }

  void RemoveFromCut(uint32_t id) {
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

  // Replaces the clusters of group `key` (all in the cut) by their children.
  Status expand(uint32_t key) {
    if (stopped || state[key] != kInCut) return Status::Ok();
    const std::vector<uint32_t> siblings = reader.node(key).siblings;  // copies: loading records may rehash
    const std::vector<uint32_t> children = reader.node(key).children;
    if (children.empty()) return Status::Ok();
    for (uint32_t s : siblings)
      if (s >= state.size() || state[s] != kInCut || reader.node(s).children != children ||
          reader.node(s).siblings != siblings)
        return Status::Invalid("corrupt file: the clusters made from one group disagree (node " + std::to_string(s) +
                               ")");
    Status st = reader.LoadChildren(key);
    if (!st.ok()) return st;
    size_t removed = 0, added = 0;
    for (uint32_t s : siblings) removed += reader.node(s).faceCount;
    for (uint32_t c : children) {
      if (c >= state.size() || state[c] != kBelow)
        return Status::Invalid("corrupt file: node " + std::to_string(c) + " is the child of two groups");
      added += reader.node(c).faceCount;
    }
    if (cut.faces - removed + added > view.faceBudget) {
      cut.budgetReached = true;
      // It does not fit. By the error in model units, its clusters stay and the groups after it
      // that fit are still expanded (a smaller one fills what is left), so the cut ends near its
      // budget. The view-dependent orders stop here: filling would spend the rest of the budget
      // on what the view needs least (the far side of the model), not where it looks.
      if (view.priority != LodPriority::ObjectError || cut.faces >= view.faceBudget) stopped = true;
      return Status::Ok();
    }
    for (uint32_t s : siblings) RemoveFromCut(s);
    present.erase(key);
    for (uint32_t c : children) {
      st = AddToCut(c);
      if (!st.ok()) return st;
    }
    ++cut.refinements;
    if (view.priority == LodPriority::ObjectError) expanded.push_back(key);
    return Status::Ok();
  }

  // Faces an expansion of group `key` adds: its children's less its clusters'.
  int64_t Added(uint32_t key) const {
    const LodNode& n = reader.node(key);
    int64_t added = 0;
    for (uint32_t s : n.siblings) added -= int64_t(reader.node(s).faceCount);
    for (uint32_t c : n.children) added += int64_t(reader.node(c).faceCount);
    return added;
  }

  // Undoes the expansion of group `key`, whose children are all in the cut: its clusters again.
  Status Collapse(uint32_t key) {
    const std::vector<uint32_t> siblings = reader.node(key).siblings;  // copies: loading may rehash
    const std::vector<uint32_t> children = reader.node(key).children;
    for (uint32_t c : children) {
      const LodNode& n = reader.node(c);
      if (!n.children.empty()) {
        const auto it = present.find(keyOf(n));
        if (it != present.end() && --it->second == 0) present.erase(it);
      }
      RemoveFromCut(c);
      state[c] = kBelow;
    }
    for (uint32_t s : siblings) {
      Status st = AddToCut(s);
      if (!st.ok()) return st;
    }
    --cut.refinements;
    return Status::Ok();
  }

  // ObjectError, the queue empty below the budget: the cut changes by whole groups, and near the
  // top a group adds hundreds of faces, so what is left may fit no expansion. Expansions whose
  // children are all still in the cut are undone for others that then fit and gain more in all
  // (ObjectWorth): one undone for one or two expanded, or two undone for one larger. Of those
  // moves, the one that brings the cut closest to its budget (ties: the first in the order of the
  // keys). The queue then goes on: the new children may fit what is left. Each move adds faces, so
  // moves end; the cut stays one of the DAG's cuts (watertight), and the choice depends on the
  // file and the budget only.
  Status Fill(bool& swapped) {
    swapped = false;
    const int64_t slack = int64_t(view.faceBudget) - int64_t(cut.faces);
    if (slack <= 0) return Status::Ok();
    struct Open {
      int64_t added;  // faces its expansion adds
      uint32_t key;
      double worth;  // ObjectWorth
      bool operator<(const Open& o) const { return added != o.added ? added < o.added : key < o.key; }
    };
    std::vector<Open> open;  // the groups that can be expanded
    for (const auto& kv : present) {
      const uint32_t key = kv.first;
      if (kv.second != reader.node(key).siblings.size() || state[key] != kInCut) continue;
      Status st = reader.LoadChildren(key);
      if (!st.ok()) return st;
      const std::vector<uint32_t> siblings = reader.node(key).siblings;  // copied: loading may rehash
      double worth = 0;
      st = ObjectWorth(siblings, worth);
      if (!st.ok()) return st;
      open.push_back({Added(key), key, worth});
    }
    if (open.empty()) return Status::Ok();
    std::sort(open.begin(), open.end());
    struct Undo {
      uint32_t key;
      int64_t removed;  // faces its undoing removes
      double lost;      // ObjectWorth
    };
    std::vector<Undo> undoable;  // the expansions whose children are all in the cut
    for (uint32_t key : expanded) {
      if (state[key] != kRefined) continue;
      bool leaf = true;
      for (uint32_t c : reader.node(key).children) leaf = leaf && state[c] == kInCut;
      if (!leaf) continue;
      const std::vector<uint32_t> siblings = reader.node(key).siblings;  // copied: loading may rehash
      double lost = 0;
      Status st = ObjectWorth(siblings, lost);
      if (!st.ok()) return st;
      undoable.push_back({key, Added(key), lost});
    }
    std::sort(undoable.begin(), undoable.end(), [](const Undo& x, const Undo& y) { return x.key < y.key; });
    const int64_t before = int64_t(cut.faces);
    int64_t bestFaces = before;
    uint32_t bestUndo[2] = {kNone, kNone}, bestExpand[2] = {kNone, kNone};
    std::vector<uint32_t> gone;  // the children the undoing removes
    // The best groups to expand once `removed` faces (worth `lost`) are undone: one, then (with
    // `pairs`) two, each adding at most `removed + slack` less the other.
    auto consider = [&](int64_t removed, double lost, uint32_t u1, uint32_t u2, bool pairs) {
      const auto hi = std::upper_bound(open.begin(), open.end(), Open{removed + slack, UINT32_MAX, 0});
      auto take = [&](int64_t faces, uint32_t a, uint32_t b) {
        bestFaces = faces;
        bestUndo[0] = u1;
        bestUndo[1] = u2;
        bestExpand[0] = a;
        bestExpand[1] = b;
      };
      for (auto it = hi; it != open.begin();) {  // largest first
        --it;
        if (it->added <= removed) break;
        const int64_t faces = before - removed + it->added;
        if (faces <= bestFaces) break;                                // the rest add fewer
        if (it->worth <= lost || !Disjoint(it->key, gone)) continue;  // gains less, or loses its clusters
        take(faces, it->key, kNone);
      }
      if (!pairs) return;
      for (auto a = hi; a != open.begin();) {
        --a;
        if (before - removed + 2 * a->added <= bestFaces) break;  // b adds at most what a adds
        if (!Disjoint(a->key, gone)) continue;
        const auto bEnd = std::upper_bound(open.begin(), a, Open{removed + slack - a->added, UINT32_MAX, 0});
        for (auto b = bEnd; b != open.begin();) {
          --b;
          const int64_t faces = before - removed + a->added + b->added;
          if (faces <= bestFaces) break;
          if (a->worth + b->worth <= lost || !Disjoint(b->key, gone)) continue;
          take(faces, a->key, b->key);
        }
      }
    };
    const int64_t mostAdded = open.back().added;
    for (size_t i = 0; i < undoable.size(); ++i) {
      const Undo& u = undoable[i];
      gone = reader.node(u.key).children;
      const size_t own = gone.size();
      consider(u.removed, u.lost, u.key, kNone, true);
      for (size_t j = i + 1; j < undoable.size(); ++j) {  // two undone for one larger
        const Undo& w = undoable[j];
        if (u.removed + w.removed >= mostAdded) continue;
        gone.resize(own);  // u's children, then w's
        const std::vector<uint32_t>& more = reader.node(w.key).children;
        gone.insert(gone.end(), more.begin(), more.end());
        consider(u.removed + w.removed, u.lost + w.lost, u.key, w.key, false);
      }
    }
    if (bestFaces == before) return Status::Ok();
    for (uint32_t u : bestUndo) {
      if (u == kNone) continue;
      Status st = Collapse(u);
      if (!st.ok()) return st;
    }
    for (uint32_t e : bestExpand) {
      if (e == kNone) continue;
      Status st = expand(e);
      if (!st.ok()) return st;
    }
    swapped = true;
    return Status::Ok();
  }

  static constexpr uint32_t kNone = UINT32_MAX;

  // Whether none of the clusters of group `key` is among `gone`.
  bool Disjoint(uint32_t key, const std::vector<uint32_t>& gone) const {
    for (uint32_t s : reader.node(key).siblings)
      if (std::find(gone.begin(), gone.end(), s) != gone.end()) return false;
    return true;
  }

  void UpdateStats() const {
    if (!statsDirty) return;
    // Cut nodes sharing a (global) vertex: the largest difference of their levels.
    std::unordered_map<uint32_t, std::pair<int, int>> range;
    for (uint32_t id : cut.nodes) {
      const LodGeometry* g = reader.geometry(id);
      if (!g) continue;
      const int level = reader.node(id).level;
      for (uint32_t v : g->vertexIds) {
        auto ins = range.emplace(v, std::make_pair(level, level));
        if (!ins.second) {
          ins.first->second.first = std::min(ins.first->second.first, level);
          ins.first->second.second = std::max(ins.first->second.second, level);
        }
      }
    }
    int worst = 0;
    for (const auto& kv : range) worst = std::max(worst, kv.second.second - kv.second.first);
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
  m.present.clear();
  m.demand.clear();
  m.cut = LodCut();
  m.queue = std::priority_queue<QueueItem>();
  m.expanded.clear();
  m.fillDone = false;
  m.stopped = false;
  m.started = true;
  for (uint32_t r : m.reader.roots()) {
    Status s = m.AddToCut(r);
    if (!s.ok()) return s;
  }
  return Status::Ok();
}

Status LodRefiner::Step(size_t maxRefinements) {
  Impl& m = *impl_;
  if (!m.started) return Status::Invalid("LodRefiner::Step before Start");
  size_t done = 0;
  const bool pixelStop = m.pixelStop();
  while (done < maxRefinements && !m.stopped && (!m.queue.empty() || m.fillPending())) {
    if (m.queue.empty()) {
      bool swapped = false;
      Status s = m.Fill(swapped);
      if (!s.ok()) {
        m.stopped = true;
        return s;
      }
      if (!swapped) m.fillDone = true;
      ++done;
      continue;
    }
    const QueueItem top = m.queue.top();
    m.queue.pop();
    // With a pixel threshold, a group is expanded only when one of its visible clusters (or a
    // visible node waiting for it) projects its error to more than the threshold; the order is
    // the priority's, so the loop ends when the queue is empty, not at the first small priority
    // (a group seen edge-on weighs less in the order but still shows its error at the silhouette).
    if (pixelStop && (top.culled || top.need <= m.view.maxPixelError)) continue;  // no pixel to gain
    const size_t before = m.cut.refinements;
    Status s = m.expand(top.key);
    if (!s.ok()) {
      m.stopped = true;
      return s;
    }
    done += m.cut.refinements - before;
  }
  return Status::Ok();
}

bool LodRefiner::Done() const {
  return !impl_->started || impl_->stopped || (impl_->queue.empty() && !impl_->fillPending());
}

const LodCut& LodRefiner::cut() const {
  impl_->UpdateStats();
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
                      std::vector<int>* faceLevel, std::vector<uint32_t>* faceNode, LodAttributes* attributes) {
  out = IndexedMesh();
  if (attributes) {
    *attributes = LodAttributes();
    for (int c = 0; c < 2; ++c) {
      attributes->uvMin[c] = reader.info().uvMin[c];
      attributes->uvMax[c] = reader.info().uvMax[c];
    }
  }
  if (faceLevel) faceLevel->clear();
  if (faceNode) faceNode->clear();
  if (cut.culled.size() != cut.nodes.size())
    return Status::Invalid("ExtractCutMesh: the cut's culled flags do not match its nodes");
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
  // Vertices are welded by global id: shared between nodes of every level.
  std::unordered_map<uint32_t, uint32_t> weld;
  weld.reserve(verts);
  std::vector<uint32_t> local;
  for (size_t i = 0; i < cut.nodes.size(); ++i) {
    if (!includeCulled && cut.culled[i]) continue;
    const uint32_t id = cut.nodes[i];
    const bool wasLoaded = reader.geometry(id) != nullptr;
    Status s = reader.LoadGeometry(id);
    if (!s.ok()) return s;
    const LodGeometry& g = *reader.geometry(id);
    const LodAttributes* ga = reader.attributes(id);
    const int level = reader.node(id).level;
    local.resize(g.vertexIds.size());
    for (size_t v = 0; v < g.vertexIds.size(); ++v) {
      auto ins = weld.emplace(g.vertexIds[v], uint32_t(out.positions.size()));
      if (ins.second) {
        out.positions.push_back(g.positions[v]);
        if (attributes && ga && !ga->colors.empty()) attributes->colors.push_back(ga->colors[v]);
        if (attributes && ga && !ga->normals.empty()) attributes->normals.push_back(ga->normals[v]);
        if (attributes && ga && !ga->texCoords.empty()) attributes->texCoords.push_back(ga->texCoords[v]);
      }
      local[v] = ins.first->second;
    }
    for (const auto& t : g.faces) {
      const std::array<uint32_t, 3> face = {local[t[0]], local[t[1]], local[t[2]]};
      // A face of the input whose corners the build's weld joined: a point or a segment, no
      // surface. MeshLab's filters assume there is none (vcglib's UpdateTopology asserts).
      if (UsesAVertexTwice(face)) continue;
      out.faces.push_back(face);
      if (faceLevel) faceLevel->push_back(level);
      if (faceNode) faceNode->push_back(id);
    }
    if (!wasLoaded) reader.EvictGeometry(id);  // leave the reader as it was
  }
  return Status::Ok();
}

}  // namespace conelod
