// ConeLOD — `conelod lod build --memory` of a PLY file without its faces whole in memory (issue 27;
// docs/scale.md, lod_build.h BuildLodFileFromPly).
//
// Passes: (1) the PLY is read streaming (ReadPlyStreaming): the positions stay in memory, the
// triangles go to a file R of the temporary folder as they are read, with a sample of their
// centroids (every s-th face); (2) the weld (equal positions are one vertex, as WeldByPosition
// numbers them) from the positions alone; (3) the kd split planes from the sample (the median of
// the sample on the longest axis of its box, ties by face index, every leaf at one depth: with
// every face in the sample, s = 1, exactly KdChunks's chunks); (4) R is read back, welded, and
// each face goes to its chunk's file K<i>; a vertex two chunks use is marked as a border; (5) the
// DAG from the chunk files (BuildLodDagFromChunks) and the file from the spill (WriteLodFileFrom).
// On --threads: the binary records are read a block at a time side by side (ply_format.cpp), the
// weld's sort runs in parts, and (4) welds and places a block of faces side by side; what depends
// on the order (the marks, the chunk files, the sample) is done in input order.
#include "conelod/lod/lod_build.h"
#include "conelod/lod/lod_spill.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <numeric>

#include "conelod/mesh/mesh_check.h"
#include "conelod/mesh/ply_format.h"
#include "conelod/parallel.h"
#include "conelod/simplify/hierarchical_simplification.h"
#include "conelod/stage_log.h"

namespace conelod {
namespace {

using Face = std::array<uint32_t, 3>;

uint32_t Bits(float x) {  // as weld.cpp: -0 and +0 are one position
  if (x == 0) x = 0;
  uint32_t u;
  std::memcpy(&u, &x, 4);
  return u;
}

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct FileCloser {
  void operator()(std::FILE* f) const {
    if (f) std::fclose(f);
  }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

// A centroid as KdChunks computes it.
template <class P>
vcg::Point3f Centroid(const P& a, const P& b, const P& c) {
  const vcg::Point3d p =
      (vcg::Point3d(a[0], a[1], a[2]) + vcg::Point3d(b[0], b[1], b[2]) + vcg::Point3d(c[0], c[1], c[2])) / 3.0;
  return vcg::Point3f::Construct(p);
}

struct Sample {
  vcg::Point3f c;
  uint32_t face;
};
struct Plane {
  int axis = 0;
  float value = std::numeric_limits<float>::infinity();  // no sample: every face goes below
  uint32_t face = 0;
  bool upper(const vcg::Point3f& c, uint32_t f) const {  // !(c, f) < (value, face), as KdChunks orders
    return !(c[axis] < value || (c[axis] == value && f < face));
  }
};

// KdChunks's splits on the sample: planes[(1 << level) + node] for the inner kd nodes.
std::vector<Plane> SamplePlanes(std::vector<Sample>& s, int depth) {
  std::vector<Plane> planes(size_t(1) << depth);
  struct Range {
    size_t begin, end;
    uint32_t node;
    int level;
  };
  std::vector<Range> todo = {{0, s.size(), 0u, 0}};
  while (!todo.empty()) {
    const Range r = todo.back();
    todo.pop_back();
    if (r.level == depth) continue;
    Plane& p = planes[(size_t(1) << r.level) + r.node];
    if (r.end > r.begin) {
      vcg::Box3f box;
      for (size_t i = r.begin; i < r.end; ++i) box.Add(s[i].c);
      int axis = 0;
      const vcg::Point3f d = box.Dim();
      axis = d[1] > d[axis] ? 1 : axis;
      axis = d[2] > d[axis] ? 2 : axis;
      const size_t mid = r.begin + (r.end - r.begin) / 2;
      std::nth_element(s.begin() + std::ptrdiff_t(r.begin), s.begin() + std::ptrdiff_t(mid),
                       s.begin() + std::ptrdiff_t(r.end), [&](const Sample& a, const Sample& b) {
                         return a.c[axis] < b.c[axis] || (a.c[axis] == b.c[axis] && a.face < b.face);
                       });
      p.axis = axis;
      p.value = s[mid].c[axis];
      p.face = s[mid].face;
      todo.push_back({r.begin, mid, r.node << 1, r.level + 1});
      todo.push_back({mid, r.end, r.node << 1 | 1u, r.level + 1});
    } else {
      todo.push_back({r.begin, r.end, r.node << 1, r.level + 1});
      todo.push_back({r.begin, r.end, r.node << 1 | 1u, r.level + 1});
    }
  }
  return planes;
}

// Sorts v by `less`, a strict total order (so the result is the one std::sort gives), on up to
// `threads` threads: 2^k parts sorted side by side, then merged pairwise side by side, through a
// buffer of v's size.
template <class T, class Less>
void SortOnThreads(std::vector<T>& v, unsigned threads, const Less& less) {
  size_t parts = 1;
  while (parts < threads && v.size() / (2 * parts) >= (size_t(1) << 12)) parts *= 2;
  if (parts == 1) {
    std::sort(v.begin(), v.end(), less);
    return;
  }
  auto at = [&](size_t part) { return v.begin() + std::ptrdiff_t(v.size() * part / parts); };
  ParallelChunks(parts, threads, 1, [&](size_t b, size_t e, unsigned) {
    for (size_t i = b; i < e; ++i) std::sort(at(i), at(i + 1), less);
  });
  std::vector<T> merged(v.size());
  for (size_t width = 1; width < parts; width *= 2) {
    ParallelChunks(parts / (2 * width), threads, 1, [&](size_t b, size_t e, unsigned) {
      for (size_t i = b; i < e; ++i) {
        const size_t lo = 2 * width * i;
        std::merge(at(lo), at(lo + width), at(lo + width), at(lo + 2 * width), merged.begin() + (at(lo) - v.begin()),
                   less);
      }
    });
    v.swap(merged);
  }
}

std::string ReadHeader(const std::string& path, PlyHeader& h) {
  File f(std::fopen(path.c_str(), "rb"));
  if (!f) return "cannot read '" + path + "': " + std::strerror(errno);
  std::fseek(f.get(), 0, SEEK_END);
  const long size = std::ftell(f.get());
  std::fseek(f.get(), 0, SEEK_SET);
  std::vector<char> buf(size_t(1) << 16);
  const size_t n = std::fread(buf.data(), 1, buf.size(), f.get());
  const std::string err = ParsePlyHeader(buf.data(), n, h, size > 0 ? uint64_t(size) : 0);
  return err.empty() ? "" : "'" + path + "' " + err;
}

}  // namespace

uint64_t PlyFaceCount(const std::string& path, bool* vertexAttributes) {
  PlyHeader h;
  if (vertexAttributes) *vertexAttributes = false;
  if (!ReadHeader(path, h).empty()) return 0;
  uint64_t faces = 0;
  for (const PlyElement& e : h.elements) {
    if (e.name == "face") {
      faces = e.count;
      for (const PlyProperty& p : e.properties)  // per-corner texture coordinates
        if (vertexAttributes && p.name == "texcoord") *vertexAttributes = true;
    }
    if (e.name == "vertex" && vertexAttributes)
      for (const PlyProperty& p : e.properties)
        for (const char* a : {"red", "diffuse_red", "nx", "texture_u", "s"})
          if (p.name == a) *vertexAttributes = true;
  }
  return faces;
}

Status BuildLodFileFromPly(const std::string& input, const LodBuildParams& params, const std::string& path,
                           LodBuildStats* stats, const Progress& progress, std::string* readError, size_t sampleFaces) {
  const auto t0 = std::chrono::steady_clock::now();
  StageLog::Laps laps;
  if (readError) readError->clear();
  if (params.chunkFaces == 0) return Status::Invalid("internal error: a streamed LOD build needs chunks");
  LodSpill spill;
  {
    const std::string err = spill.create(path);
    if (!err.empty()) return Status::Invalid(err);
  }
  const uint64_t headerFaces = PlyFaceCount(input);
  const unsigned threads = unsigned(std::max(1, SimplificationThreads(params.simplification)));
  if (sampleFaces == 0) sampleFaces = std::min<size_t>(size_t(1) << 20, 16 * params.chunkFaces);
  const uint64_t step = std::max<uint64_t>(1, (headerFaces + sampleFaces - 1) / sampleFaces);

  // (1) Read: positions in memory, triangles to R, a sample of the centroids.
  PlyMesh ply;
  std::vector<uint8_t> used;
  std::vector<Sample> sample;
  uint64_t F = 0;
  size_t degenerate = 0;
  bool anyArea = false;
  {
    File raw(std::fopen(spill.raw().c_str(), "wb"));
    if (!raw) return Status::Invalid("cannot write '" + spill.raw() + "': " + std::strerror(errno));
    const PlyTriangleSink sink = [&](const std::vector<Face>& batch) -> std::string {
      if (used.size() != ply.positions.size()) used.assign(ply.positions.size(), 0);
      if (F + batch.size() >= uint64_t(0xFFFFFFFFu)) return "'" + input + "': too many faces (at most 2^32 - 1)";
      if (std::fwrite(batch.data(), sizeof(Face), batch.size(), raw.get()) != batch.size())
        return "cannot write '" + spill.raw() + "': " + std::strerror(errno);
      for (const Face& t : batch) {
        for (uint32_t v : t) used[v] = 1;
        const auto& a = ply.positions[t[0]];
        const auto& b = ply.positions[t[1]];
        const auto& c = ply.positions[t[2]];
        if (!anyArea) {
          const vcg::Point3d pa(a[0], a[1], a[2]), pb(b[0], b[1], b[2]), pc(c[0], c[1], c[2]);
          if (((pb - pa) ^ (pc - pa)).Norm() > 0)
            anyArea = true;
          else
            ++degenerate;
        }
        if (F % step == 0) sample.push_back({Centroid(a, b, c), uint32_t(F)});
        ++F;
      }
      return "";
    };
    bool ioError = false;
    const std::string err = ReadPlyStreaming(input, ply, sink, &ioError, threads);
    if (!err.empty()) {
      if (readError) *readError = err;
      return Status::Invalid(err);
    }
    if (std::fclose(raw.release()) != 0)
      return Status::Invalid("cannot write '" + spill.raw() + "': " + std::strerror(errno));
  }
  laps.Mark("read");
  const size_t V = ply.positions.size();
  used.resize(V, 0);
  {
    MeshReport r;
    r.vertices = V;
    r.faces = size_t(F);
    for (size_t v = 0; v < V; ++v) {
      if (!used[v]) {
        ++r.unreferencedVertices;
        continue;
      }
      const auto& p = ply.positions[v];
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
        ++r.nonFiniteVertices;
      else if (std::fabs(p[0]) > kMaxCoordinate || std::fabs(p[1]) > kMaxCoordinate || std::fabs(p[2]) > kMaxCoordinate)
        ++r.hugeVertices;
    }
    r.degenerateFaces = anyArea ? degenerate : size_t(F);
    const Status s = RequireValidForFaces(r);
    if (!s.ok()) return s;
  }

  // (2) The weld (weld.h): sorted by position, each position's lowest vertex its representative,
  // the welded vertices numbered in the order of their representatives. map: input -> welded id.
  std::vector<uint32_t> map(V, UINT32_MAX);
  size_t merged = 0, dropped = 0;
  {
    std::vector<uint32_t> order;
    order.reserve(V);
    for (uint32_t v = 0; v < V; ++v)
      if (used[v]) order.push_back(v);
    dropped = V - order.size();
    std::vector<uint8_t>().swap(used);
    const auto& P = ply.positions;
    auto key = [&](uint32_t v) { return std::array<uint32_t, 4>{{Bits(P[v][0]), Bits(P[v][1]), Bits(P[v][2]), v}}; };
    SortOnThreads(order, threads, [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
    for (size_t i = 0; i < order.size();) {
      size_t j = i;
      const auto ki = key(order[i]);
      while (j < order.size()) {
        const auto kj = key(order[j]);
        if (kj[0] != ki[0] || kj[1] != ki[1] || kj[2] != ki[2]) break;
        map[order[j]] = order[i];
        ++j;
      }
      merged += j - i - 1;
      i = j;
    }
  }
  laps.Mark("weld");
  LodChunkedInput in;
  {
    uint32_t next = 0;
    for (uint32_t v = 0; v < V; ++v) {
      if (map[v] == UINT32_MAX) continue;
      if (map[v] == v) {
        map[v] = next++;
      } else {
        map[v] = map[map[v]];  // the representative is lower: already renumbered
      }
    }
    // The welded positions, compacted in place, go through a file of the folder so that the input's
    // and the welded positions are never in memory together (12 bytes a vertex less at the peak).
    auto& P = ply.positions;
    size_t w = 0;
    for (uint32_t v = 0; v < V; ++v)
      if (map[v] != UINT32_MAX && map[v] == w) P[w++] = P[v];
    const std::string weldPath = spill.raw() + "W";
    {
      File f(std::fopen(weldPath.c_str(), "wb"));
      bool ok = f && std::fwrite(P.data(), sizeof P[0], w, f.get()) == w;
      if (f && std::fclose(f.release()) != 0) ok = false;
      if (!ok) {
        std::remove(weldPath.c_str());
        return Status::Invalid("cannot write '" + weldPath + "': " + std::strerror(errno));
      }
    }
    ply = PlyMesh();
    in.positions.resize(w);
    static_assert(sizeof(vcg::Point3f) == sizeof(std::array<float, 3>), "positions as three floats");
    File f(std::fopen(weldPath.c_str(), "rb"));
    const bool ok = f && std::fread(in.positions.data(), sizeof(vcg::Point3f), w, f.get()) == w;
    f.reset();
    std::remove(weldPath.c_str());
    if (!ok || w != next) return Status::Invalid("cannot read '" + weldPath + "' (the temporary folder of --memory)");
    for (const auto& p : in.positions) in.box.Add(vcg::Point3d::Construct(p));
  }
  const size_t W = in.positions.size();
  in.inputFaces = size_t(F);
  laps.Mark("welded positions");

  // An input of one chunk: the unchunked build, as BuildLodFile builds it (its file byte for byte).
  int depth = 0;
  while (depth < 24 && (F + (uint64_t(1) << depth) - 1) >> depth > params.chunkFaces) ++depth;
  if (depth == 0) {
    IndexedMesh mesh;
    mesh.positions.swap(in.positions);
    mesh.faces.resize(size_t(F));
    File raw(std::fopen(spill.raw().c_str(), "rb"));
    if (!raw || std::fread(mesh.faces.data(), sizeof(Face), size_t(F), raw.get()) != size_t(F))
      return Status::Invalid("cannot read '" + spill.raw() + "' (the temporary folder of --memory)");
    raw.reset();
    spill.remove();
    for (Face& t : mesh.faces)
      for (uint32_t& v : t) v = map[v];
    std::vector<uint32_t>().swap(map);
    Status s = BuildLodFile(std::move(mesh), params, path, stats, progress);
    if (s.ok() && stats) {
      stats->mergedVertices = merged;
      stats->droppedVertices = dropped;
    }
    return s;
  }

  // (3) The kd planes; (4) the chunk files.
  const std::vector<Plane> planes = SamplePlanes(sample, depth);
  std::vector<Sample>().swap(sample);
  const size_t leaves = size_t(1) << depth;
  in.depth = depth;
  in.chunkFaces.assign(leaves, 0);
  spill.setChunks(leaves);
  {
    const uint32_t kNoChunk = UINT32_MAX, kTwoChunks = UINT32_MAX - 1;
    std::vector<uint32_t> chunkOf(W, kNoChunk);
    // Each chunk's faces gather in a buffer flushed to its file when full (4 MiB of buffers in all).
    const size_t cap = std::max<size_t>(64, (size_t(1) << 22) / sizeof(Face) / leaves);
    std::vector<std::vector<Face>> buffer(leaves);
    auto flush = [&](size_t l) -> Status {
      if (buffer[l].empty()) return Status::Ok();
      File f(std::fopen(spill.chunk(l).c_str(), "ab"));
      bool ok = f && std::fwrite(buffer[l].data(), sizeof(Face), buffer[l].size(), f.get()) == buffer[l].size();
      if (f && std::fclose(f.release()) != 0) ok = false;
      if (!ok) return Status::Invalid("cannot write '" + spill.chunk(l) + "': " + std::strerror(errno));
      in.chunkFaces[l] += buffer[l].size();
      buffer[l].clear();
      return Status::Ok();
    };
    File raw(std::fopen(spill.raw().c_str(), "rb"));
    if (!raw) return Status::Invalid("cannot read '" + spill.raw() + "' (the temporary folder of --memory)");
    // A block of faces at a time: welded and given their chunk side by side on the threads, then
    // marked and buffered in input order.
    std::vector<Face> block(size_t(1) << 16);
    std::vector<uint32_t> nodeOf(block.size());
    uint64_t f = 0;
    while (f < F) {
      if (progress && !progress(0, "LOD: faces to chunks")) return Status::Cancelled();
      const size_t n = size_t(std::min<uint64_t>(block.size(), F - f));
      if (std::fread(block.data(), sizeof(Face), n, raw.get()) != n)
        return Status::Invalid("cannot read '" + spill.raw() + "' (the temporary folder of --memory)");
      ParallelChunks(n, threads, size_t(1) << 13, [&](size_t begin, size_t end, unsigned) {
        for (size_t i = begin; i < end; ++i) {
          Face& t = block[i];
          for (uint32_t& v : t) v = map[v];
          const vcg::Point3f c = Centroid(in.positions[t[0]], in.positions[t[1]], in.positions[t[2]]);
          uint32_t node = 0;
          for (int level = 0; level < depth; ++level)
            node = node << 1 | (planes[(size_t(1) << level) + node].upper(c, uint32_t(f + i)) ? 1u : 0u);
          nodeOf[i] = node;
        }
      });
      for (size_t i = 0; i < n; ++i, ++f) {
        const Face& t = block[i];
        const uint32_t node = nodeOf[i];
        for (uint32_t v : t) {
          if (chunkOf[v] == kNoChunk)
            chunkOf[v] = node;
          else if (chunkOf[v] != node)
            chunkOf[v] = kTwoChunks;
        }
        buffer[node].push_back(t);
        if (buffer[node].size() >= cap) {
          const Status s = flush(node);
          if (!s.ok()) return s;
        }
      }
    }
    raw.reset();
    std::remove(spill.raw().c_str());
    for (size_t l = 0; l < leaves; ++l) {
      const Status s = flush(l);
      if (!s.ok()) return s;
      std::vector<Face>().swap(buffer[l]);
    }
    std::vector<uint32_t>().swap(map);
    in.border.resize(W);
    for (size_t v = 0; v < W; ++v) in.border[v] = chunkOf[v] == kTwoChunks ? 1 : 0;
  }

  laps.Mark("chunk files");
  // (5) The DAG and the file.
  LodDag dag;
  Status s = BuildLodDagFromChunks(in, params, dag, SubProgress(progress, 0, 90), spill);
  if (!s.ok()) return s;
  laps.Mark("dag");
  const double dagSeconds = Seconds(t0);
  s = WriteLodFileFrom(dag, &spill, W, size_t(F), in.box, path, stats, SubProgress(progress, 90, 100), params.precision,
                       LodWriterThreads(params));
  if (!s.ok()) return s;
  laps.Mark("write");
  if (stats) {
    stats->chunks = leaves;
    stats->mergedVertices = merged;
    stats->droppedVertices = dropped;
    stats->groupingSeconds = 0;
    stats->simplifySeconds = dagSeconds;
    stats->seconds = Seconds(t0);
  }
  return Status::Ok();
}

}  // namespace conelod
