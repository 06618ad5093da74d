// Crack edges and over-used edges of a .clod file's cuts, counted as scripts/lod_cracks.py counts
// them, for files too large for that script (issue 27: the 55.8 M-face dragon's cuts at 5 / 20 /
// 50 %), in bounded memory. One JSON line per cut, then a summary line.
//
// A cut is what `conelod lod extract FILE --eye E --budget P%` selects (the same reader and
// refiner, culled nodes included). Positions are compared on the file's grid (a vertex's key is
// its three grid indices, which stand for its decoded floats one to one: checked per vertex), so
// vertices at identical positions are one (welded by position); a face whose corners fall on fewer
// than three positions is skipped. Of the cut's edges (pairs of positions):
//   cracks:   edges used by one face that the input does not use exactly once (its border);
//   overlaps: edges used by three faces or more that the input does not use three times or more.
// The input is the file's level 0, which is the welded input on the grid (the build's exact round
// trip): it is never held whole. Only the cut's edges used once or 3+ times (none, when the cut is
// crack-free and the input closed) are looked up in it, in one pass over level 0's nodes, node by
// node; with none, level 0 is not read.
//
// Memory: the refinement keeps the records of the nodes it visited, not their geometry (evicted
// after each batch of expansions); the counting reads the cut's records again in a fresh reader.
// The cut's edges are counted in slabs along the box's longest axis: each slab holds at most
// --memory / 32 edge uses (16 bytes each, sorted in place) of the edges whose lower end lies in
// it, and reads the geometry of the cut's nodes whose bounding sphere meets it. Every edge use
// must be counted in exactly one slab (checked: otherwise a bad-input error). Peak RSS: the
// process's so far (VmHWM), after each cut.
//
//   lod_cracks FILE.clod [--budgets 5,20,50] [--eye X,Y,Z]... [--no-cull] [--memory 256M]
//              [--remove-face | --repeat-face]
// --eye may be repeated (every budget from every eye); default: the box's centre moved 2 diagonals
// along +Z, as lod_cracks.py. --remove-face / --repeat-face (tests): the first face of each cut's
// first node (in the cut's order) is left out / counted twice, a hole (cracks) / an overlap to find.
// Exit: 0 counted (whatever the counts), 1 usage, 2 a file that cannot be read or is corrupt.
#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <malloc.h>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "conelod/lod/lod_read.h"

using namespace conelod;

namespace {

const char* kUsage =
    "usage: lod_cracks FILE.clod [--budgets 5,20,50] [--eye X,Y,Z]... [--no-cull] [--memory SIZE]\n"
    "                  [--remove-face | --repeat-face]\n"
    "For each eye and budget (percent of the input's faces), the cut `conelod lod extract` selects,\n"
    "and its edges welded by position on the file's grid: cracks (edges used by one face that are\n"
    "not the input's border) and overlaps (edges used by 3+ faces the input does not use 3+ times),\n"
    "as scripts/lod_cracks.py counts them. The input is the file's level 0 (the welded input on the\n"
    "grid), read node by node, and only when a cut has an edge used once or 3+ times. SIZE (default\n"
    "256M; K, M, G suffixes) bounds the cut's edge uses held at once (slabs along the longest axis).\n"
    "Prints a JSON line per cut (budget, faces, cracks, overlaps, seconds, peak RSS), then a summary.\n";

struct Edge {
  uint64_t a, b;  // position keys, a <= b
  bool operator<(const Edge& o) const { return a != o.a ? a < o.a : b < o.b; }
  bool operator==(const Edge& o) const { return a == o.a && b == o.b; }
};

double Now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

uint64_t PeakRssBytes() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.compare(0, 6, "VmHWM:") == 0) return uint64_t(std::strtoull(line.c_str() + 6, nullptr, 10)) * 1024;
  return 0;
}

// `s` as a JSON string (quotes, backslashes and control characters escaped).
std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += char(c);
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += char(c);
    }
  }
  return out + "\"";
}

bool ParseSize(const std::string& s, uint64_t& out) {
  if (s.empty() || !std::isdigit(static_cast<unsigned char>(s[0]))) return false;
  char* end = nullptr;
  const unsigned long long v = std::strtoull(s.c_str(), &end, 10);
  int shift = 0;
  if (*end == 'K')
    shift = 10, ++end;
  else if (*end == 'M')
    shift = 20, ++end;
  else if (*end == 'G')
    shift = 30, ++end;
  else if (*end == 'T')
    shift = 40, ++end;
  if (*end != '\0' || v == 0 || v > (std::numeric_limits<uint64_t>::max() >> shift)) return false;
  out = uint64_t(v) << shift;
  return true;
}

bool ParsePoint(const std::string& s, vcg::Point3d& p) {
  const char* c = s.c_str();
  for (int k = 0; k < 3; ++k) {
    char* end = nullptr;
    p[k] = std::strtod(c, &end);
    if (end == c || !std::isfinite(p[k])) return false;
    c = end;
    if (k < 2) {
      if (*c != ',') return false;
      ++c;
    }
  }
  return *c == '\0';
}

// A node's geometry as position keys, and its faces that span three positions.
struct KeyedNode {
  std::vector<uint64_t> keys;                  // per local vertex
  std::vector<float> along;                    // per local vertex: its coordinate on the slab axis
  std::vector<std::array<uint32_t, 3>> faces;  // the non-degenerate faces (local vertices)
};

class Grid {
 public:
  explicit Grid(const LodGrid& g) : g_(g) {}
  // The key of a decoded position: its grid indices, packed. False when the position is not the
  // decoding of its indices (a grid finer than floats: then keys would not stand for positions).
  bool Key(const vcg::Point3f& p, uint64_t& key) const {
    key = 0;
    for (int c = 0; c < 3; ++c) {
      const uint32_t q = g_.Quantize(p[c], c);
      if (g_.Dequantize(q, c) != p[c]) return false;
      key |= uint64_t(q) << (21 * c);
    }
    return true;
  }

 private:
  LodGrid g_;
};

Status KeyNode(LodReader& reader, const Grid& grid, int axis, uint32_t id, KeyedNode& out) {
  Status s = reader.LoadNode(id);
  if (s.ok()) s = reader.LoadGeometry(id);
  if (!s.ok()) return s;
  const LodGeometry& g = *reader.geometry(id);
  out.keys.resize(g.positions.size());
  out.along.resize(g.positions.size());
  for (size_t v = 0; v < g.positions.size(); ++v) {
    if (!grid.Key(g.positions[v], out.keys[v]))
      return Status::Invalid("node " + std::to_string(id) + ": a position is not on the file's grid");
    out.along[v] = g.positions[v][axis];
  }
  out.faces.clear();
  for (const auto& f : g.faces) {
    if (f[0] >= out.keys.size() || f[1] >= out.keys.size() || f[2] >= out.keys.size())
      return Status::Invalid("node " + std::to_string(id) + ": a corner out of range");
    const uint64_t a = out.keys[f[0]], b = out.keys[f[1]], c = out.keys[f[2]];
    if (a == b || b == c || a == c) continue;  // no area on the grid: neither a crack nor an overlap
    out.faces.push_back(f);
  }
  reader.EvictGeometry(id);
  return Status::Ok();
}

struct CutNode {
  uint32_t id;
  float lo, hi, center;  // the bounding sphere's extent on the slab axis (padded), its centre
  uint32_t faces;
};

struct Candidate {
  Edge edge;
  uint32_t uses;  // in the cut: 1, or 3 and more
};

struct CutResult {
  vcg::Point3d eye;
  double percent = 0;
  size_t budget = 0, faces = 0, nodes = 0, edgeUses = 0, slabs = 0;
  std::vector<Candidate> candidates;
  size_t once = 0, overused = 0;  // the cut's edges used once, 3+ times (before the input's lookup)
  size_t cracks = 0, overlaps = 0;
  double seconds = 0;
  uint64_t peakRss = 0;
};

enum class Inject { None, Remove, Repeat };

// The cut of `view`, refined as RefineLod does (the same Steps, in batches) but with each batch's
// geometry evicted: only the node records stay. A batch is a 64th of the cut's nodes, 128 to 512
// expansions (each batch walks the whole cut: LodRefiner::cut() and the evictions).
Status RefineWithoutGeometry(LodReader& reader, const LodView& view, LodCut& cut) {
  LodRefiner r(reader);
  Status s = r.Start(view);
  size_t batch = 128;
  while (s.ok() && !r.Done()) {
    s = r.Step(batch);
    const std::vector<uint32_t>& nodes = r.cut().nodes;
    for (uint32_t id : nodes) reader.EvictGeometry(id);
    batch = std::max<size_t>(128, std::min<size_t>(512, nodes.size() / 64));
  }
  if (!s.ok()) return s;
  cut = r.cut();
  return Status::Ok();
}

Status CountCut(const std::string& path, const LodView& view, uint64_t memory, Inject inject, CutResult& res) {
  const double t0 = Now();
  std::unique_ptr<LodReader> reader;
  Status s = LodReader::Open(path, reader);
  if (!s.ok()) return s;
  for (uint32_t r : reader->roots()) reader->EvictGeometry(r);
  const LodFileInfo info = reader->info();
  LodCut cut;
  s = RefineWithoutGeometry(*reader, view, cut);
  if (!s.ok()) return s;
  res.faces = cut.faces;
  res.nodes = cut.nodes.size();

  const vcg::Point3f dim = info.box.Dim();
  const int axis = dim[0] >= dim[1] && dim[0] >= dim[2] ? 0 : dim[1] >= dim[2] ? 1 : 2;
  const float pad = float(2 * info.quantizationError + 1e-5 * double(info.box.Diag()));
  std::vector<CutNode> nodes;
  nodes.reserve(cut.nodes.size());
  for (uint32_t id : cut.nodes) {
    const LodNode& n = reader->node(id);
    const float c = n.center[axis];
    nodes.push_back({id, c - n.radius - pad, c + n.radius + pad, c, n.faceCount});
  }
  std::sort(nodes.begin(), nodes.end(), [](const CutNode& x, const CutNode& y) { return x.id < y.id; });
  const uint32_t injectNode = cut.nodes.empty() ? ~0u : cut.nodes[0];
  const size_t cutFaces = cut.faces;
  // A fresh reader for the counting: the records of the nodes the refinement visited go (only the
  // cut's are read again), so that they and the slab's edge uses are not in memory together.
  cut = LodCut();
  reader.reset();
  malloc_trim(0);  // the freed records' pages back to the system, not under the slabs' peak
  s = LodReader::Open(path, reader);
  if (!s.ok()) return s;
  for (uint32_t r : reader->roots()) reader->EvictGeometry(r);

  // Slabs: bounds at the quantiles of the nodes' centres weighted by their faces, so that each
  // holds about `perSlab` edge uses.
  const uint64_t perSlab = std::max<uint64_t>(memory / 32, 1024);
  const uint64_t uses = uint64_t(cutFaces) * 3 + (inject == Inject::Repeat ? 3 : 0);
  const size_t slabs = size_t(std::max<uint64_t>(1, (uses + perSlab - 1) / perSlab));
  std::vector<float> bounds;  // slab k: [bounds[k - 1], bounds[k]), open at both ends
  if (slabs > 1) {
    std::vector<std::pair<float, uint32_t>> byCenter;
    byCenter.reserve(nodes.size());
    for (const CutNode& n : nodes) byCenter.push_back({n.center, n.faces});
    std::sort(byCenter.begin(), byCenter.end());
    uint64_t seen = 0;
    for (const auto& c : byCenter) {
      seen += c.second;
      if (seen * slabs >= uint64_t(cutFaces) * (bounds.size() + 1) && bounds.size() + 1 < slabs &&
          (bounds.empty() || c.first > bounds.back()))
        bounds.push_back(c.first);
    }
  }
  res.slabs = bounds.size() + 1;

  KeyedNode kn;
  std::vector<Edge> edges;
  std::vector<uint8_t> counted(nodes.size(), 0);
  uint64_t expected = 0, emitted = 0;
  for (size_t k = 0; k <= bounds.size(); ++k) {
    const float lo = k == 0 ? -std::numeric_limits<float>::infinity() : bounds[k - 1];
    const float hi = k == bounds.size() ? std::numeric_limits<float>::infinity() : bounds[k];
    edges.clear();
    edges.reserve(size_t(std::min<uint64_t>(uses, perSlab + perSlab / 4)));  // no doubling past the budget
    for (size_t i = 0; i < nodes.size(); ++i) {
      const CutNode& n = nodes[i];
      if (n.hi < lo || n.lo >= hi) continue;
      s = KeyNode(*reader, Grid(info.grid), axis, n.id, kn);
      if (!s.ok()) return s;
      for (size_t f = 0; f < kn.faces.size(); ++f) {
        int times = 1;
        if (n.id == injectNode && f == 0 && inject == Inject::Remove) times = 0;
        if (n.id == injectNode && f == 0 && inject == Inject::Repeat) times = 2;
        if (!counted[i]) expected += 3 * uint64_t(times);
        for (int t = 0; t < times; ++t)
          for (int e = 0; e < 3; ++e) {
            const uint32_t u = kn.faces[f][e], v = kn.faces[f][(e + 1) % 3];
            const float along = std::min(kn.along[u], kn.along[v]);
            if (along < lo || along >= hi) continue;
            const uint64_t a = kn.keys[u], b = kn.keys[v];
            edges.push_back(a < b ? Edge{a, b} : Edge{b, a});
          }
      }
      counted[i] = 1;
    }
    emitted += edges.size();
    std::sort(edges.begin(), edges.end());
    for (size_t i = 0; i < edges.size();) {
      size_t j = i + 1;
      while (j < edges.size() && edges[j] == edges[i]) ++j;
      if (j - i != 2) res.candidates.push_back({edges[i], uint32_t(j - i)});
      i = j;
    }
    std::vector<Edge>().swap(edges);
  }
  if (emitted != expected)
    return Status::Invalid("a node's vertices lie outside its bounding sphere: " + std::to_string(expected) +
                           " edge uses, " + std::to_string(emitted) + " counted");
  res.edgeUses = size_t(emitted);
  res.seconds = Now() - t0;
  return Status::Ok();
}

// Per candidate edge, how many faces of the file's level 0 use it: level 0's nodes in id order,
// the reader opened afresh every 65,536 nodes (its records would otherwise grow with the input).
Status CountInInput(const std::string& path, const std::vector<Edge>& cand, std::vector<uint32_t>& uses,
                    uint64_t& level0Faces) {
  uses.assign(cand.size(), 0);
  level0Faces = 0;
  std::vector<uint64_t> filter(size_t(1) << 18, 0);  // 2^24 bits: a quick "not a candidate"
  auto hash = [](const Edge& e) {
    uint64_t h = e.a * 0x9E3779B97F4A7C15ull ^ (e.b + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;
    return (h ^ (h >> 29)) & ((uint64_t(1) << 24) - 1);
  };
  for (const Edge& e : cand) filter[hash(e) >> 6] |= uint64_t(1) << (hash(e) & 63);
  std::unique_ptr<LodReader> reader;
  Status s = LodReader::Open(path, reader);
  if (!s.ok()) return s;
  const uint64_t total = reader->info().nodeCount, first = total - reader->info().levelNodes.at(0);
  const LodGrid grid = reader->info().grid;
  KeyedNode kn;
  for (uint64_t id = first; id < total; ++id) {
    if ((id - first) % 65536 == 0) {
      reader.reset();
      s = LodReader::Open(path, reader);
      if (!s.ok()) return s;
      for (uint32_t r : reader->roots()) reader->EvictGeometry(r);
    }
    s = KeyNode(*reader, Grid(grid), 0, uint32_t(id), kn);
    if (!s.ok()) return s;
    if (reader->node(uint32_t(id)).level != 0)
      return Status::Invalid("node " + std::to_string(id) + " should be of level 0");
    level0Faces += reader->node(uint32_t(id)).faceCount;
    for (const auto& f : kn.faces)
      for (int e = 0; e < 3; ++e) {
        const uint64_t a = kn.keys[f[e]], b = kn.keys[f[(e + 1) % 3]];
        const Edge edge = a < b ? Edge{a, b} : Edge{b, a};
        const uint64_t h = hash(edge);
        if (!(filter[h >> 6] >> (h & 63) & 1)) continue;
        const auto it = std::lower_bound(cand.begin(), cand.end(), edge);
        if (it != cand.end() && *it == edge) ++uses[size_t(it - cand.begin())];
      }
  }
  return Status::Ok();
}

int Usage(const std::string& why) {
  std::fprintf(stderr, "lod_cracks: %s\n%s", why.c_str(), kUsage);
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  std::string path;
  std::vector<double> budgets = {5, 20, 50};
  std::vector<vcg::Point3d> eyes;
  bool cull = true;
  uint64_t memory = uint64_t(256) << 20;
  Inject inject = Inject::None;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool hasValue = i + 1 < argc;
    if (a == "--help" || a == "-h") {
      std::printf("%s", kUsage);
      return 0;
    } else if (a == "--budgets" && hasValue) {
      budgets.clear();
      std::string list = argv[++i];
      size_t at = 0;
      while (at <= list.size()) {
        const size_t comma = std::min(list.find(',', at), list.size());
        const std::string item = list.substr(at, comma - at);
        char* end = nullptr;
        const double b = std::strtod(item.c_str(), &end);
        if (item.empty() || *end != '\0' || !(b >= 0 && b <= 100))
          return Usage("--budgets: percentages 0-100, comma-separated");
        budgets.push_back(b);
        at = comma + 1;
      }
    } else if (a == "--eye" && hasValue) {
      vcg::Point3d e;
      if (!ParsePoint(argv[++i], e)) return Usage("--eye must be X,Y,Z (three numbers)");
      eyes.push_back(e);
    } else if (a == "--no-cull") {
      cull = false;
    } else if (a == "--memory" && hasValue) {
      if (!ParseSize(argv[++i], memory)) return Usage("--memory must be a size: 256M, 1G, ...");
    } else if (a == "--remove-face" && inject == Inject::None) {
      inject = Inject::Remove;
    } else if (a == "--repeat-face" && inject == Inject::None) {
      inject = Inject::Repeat;
    } else if (!a.empty() && a[0] != '-' && path.empty()) {
      path = a;
    } else {
      return Usage("unexpected argument '" + a + "'");
    }
  }
  if (path.empty()) return Usage("expected one .clod file");

  const double t0 = Now();
  LodFileInfo info;
  {
    std::unique_ptr<LodReader> reader;
    Status s = LodReader::Open(path, reader);
    if (!s.ok()) {
      std::fprintf(stderr, "lod_cracks: %s: %s\n", path.c_str(), s.message.c_str());
      return 2;
    }
    info = reader->info();
  }
  if (info.grid.bits > 21) {
    std::fprintf(stderr,
                 "lod_cracks: %s: a grid of %u bits a coordinate (above 21: built with a --precision "
                 "finer than the defaults') is not supported\n",
                 path.c_str(), info.grid.bits);
    return 2;
  }
  if (eyes.empty()) {
    const vcg::Point3f c = info.box.Center();
    eyes.push_back(vcg::Point3d(c[0], c[1], c[2] + 2 * double(info.box.Diag())));
  }

  std::vector<CutResult> results;
  for (const vcg::Point3d& eye : eyes)
    for (double b : budgets) {
      CutResult r;
      r.eye = eye;
      r.percent = b;
      LodView view;
      view.eye = eye;
      view.cullBackFacing = cull;
      view.faceBudget = size_t(std::floor(double(info.inputFaces) * b / 100.0));
      r.budget = view.faceBudget;
      Status s = CountCut(path, view, memory, inject, r);
      if (!s.ok()) {
        std::fprintf(stderr, "lod_cracks: %s: %s\n", path.c_str(), s.message.c_str());
        return 2;
      }
      r.peakRss = PeakRssBytes();
      results.push_back(std::move(r));
    }

  // The input's uses of the cuts' edges used once or 3+ times.
  const double t1 = Now();
  std::vector<Edge> cand;
  for (const CutResult& r : results)
    for (const Candidate& c : r.candidates) cand.push_back(c.edge);
  std::sort(cand.begin(), cand.end());
  cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
  std::vector<uint32_t> inputUses;
  uint64_t level0Faces = 0;
  const bool readInput = !cand.empty();
  if (readInput) {
    Status s = CountInInput(path, cand, inputUses, level0Faces);
    if (!s.ok()) {
      std::fprintf(stderr, "lod_cracks: %s: %s\n", path.c_str(), s.message.c_str());
      return 2;
    }
  }
  const double inputSeconds = Now() - t1;
  for (CutResult& r : results) {
    for (const Candidate& c : r.candidates) {
      ++(c.uses == 1 ? r.once : r.overused);
      const uint32_t in = inputUses[size_t(std::lower_bound(cand.begin(), cand.end(), c.edge) - cand.begin())];
      if (c.uses == 1 && in != 1) ++r.cracks;
      if (c.uses > 2 && in <= 2) ++r.overlaps;
    }
    std::printf(
        "{\"file\":%s,\"eye\":[%.9g,%.9g,%.9g],\"budget_percent\":%g,\"budget\":%zu,\"faces\":%zu,\"nodes\":%zu,"
        "\"cracks\":%zu,\"overlaps\":%zu,\"once_edges\":%zu,\"overused_edges\":%zu,\"edge_uses\":%zu,\"slabs\":%zu,"
        "\"seconds\":%.3f,\"peak_rss_bytes\":%" PRIu64 "}\n",
        JsonString(path).c_str(), r.eye[0], r.eye[1], r.eye[2], r.percent, r.budget, r.faces, r.nodes, r.cracks,
        r.overlaps, r.once, r.overused, r.edgeUses, r.slabs, r.seconds, r.peakRss);
  }
  std::printf("{\"file\":%s,\"input_faces\":%" PRIu64 ",\"level0_faces_read\":%" PRIu64
              ",\"cuts\":%zu,\"edges_looked_up\":%zu,\"input_read\":%s,"
              "\"input_seconds\":%.3f,\"seconds\":%.3f,\"peak_rss_bytes\":%" PRIu64 "}\n",
              JsonString(path).c_str(), info.inputFaces, level0Faces, results.size(), cand.size(),
              readInput ? "true" : "false", inputSeconds, Now() - t0, PeakRssBytes());
  return 0;
}
