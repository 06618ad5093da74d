// ConeLOD — a big group-preserving simplification in spatial parts (see partitioned_simplify.h).
#include "conelod/simplify/partitioned_simplify.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>

#include <time.h>

#include <vcg/space/box3.h>

#include "conelod/mesh/mesh_check.h"
#include "conelod/simplify/hierarchical_simplification.h"
#include "conelod/parallel.h"

namespace conelod {

namespace {

constexpr uint32_t kNone = UINT32_MAX;

// CPU seconds of the calling thread so far.
double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

struct Part {
  std::vector<uint32_t> vertices;  // indices into the input, increasing
  GroupQemResult result;
  Status status;
  double cpuSeconds = 0;
  std::atomic<int> percent{0};
};

// Simplifies the faces `faces` (indices into `mesh`, increasing) on their own; `local` is this
// thread's scratch map (kNone everywhere on entry and on return).
void SimplifyOnePart(const IndexedMesh& mesh, const std::vector<int>& faceGroup, const std::vector<uint8_t>& shared,
                     const uint32_t* faces, size_t faceCount, const GroupQemParams& qem, double diagonal,
                     size_t targetFaces, std::vector<uint32_t>& local, const std::atomic<bool>& cancel, Part& part) {
  const double cpu = ThreadCpuSeconds();
  try {
    for (size_t i = 0; i < faceCount; ++i)
      for (uint32_t v : mesh.faces[faces[i]])
        if (local[v] == kNone) {
          local[v] = 0;
          part.vertices.push_back(v);
        }
    std::sort(part.vertices.begin(), part.vertices.end());
    for (size_t i = 0; i < part.vertices.size(); ++i) local[part.vertices[i]] = uint32_t(i);
    IndexedMesh sub;
    std::vector<int> subGroup(faceCount);
    sub.positions.reserve(part.vertices.size());
    for (uint32_t v : part.vertices) sub.positions.push_back(mesh.positions[v]);
    sub.faces.reserve(faceCount);
    for (size_t i = 0; i < faceCount; ++i) {
      const auto& t = mesh.faces[faces[i]];
      sub.faces.push_back({local[t[0]], local[t[1]], local[t[2]]});
      subGroup[i] = faceGroup[faces[i]];
    }
    for (uint32_t v : part.vertices) local[v] = kNone;
    GroupQemRegion region;
    region.diagonal = diagonal;
    region.frozenVertex.resize(part.vertices.size());
    for (size_t i = 0; i < part.vertices.size(); ++i) region.frozenVertex[i] = shared[part.vertices[i]];
    GroupQemParams p = qem;
    p.targetFaces = targetFaces;
    p.removeComponents = false;  // a decision for the whole mesh: the final pass makes it
    part.status = SimplifyPreservingGroups(
        sub, subGroup, p, part.result,
        [&](int percent, const char*) {
          part.percent.store(percent, std::memory_order_relaxed);
          return !cancel.load(std::memory_order_relaxed);
        },
        {}, &region);
  } catch (const std::bad_alloc&) {
    for (uint32_t v : part.vertices) local[v] = kNone;
    part.status = Status::OutOfMemory("not enough memory to simplify a part of the mesh");
  }
  part.cpuSeconds = ThreadCpuSeconds() - cpu;
  part.percent.store(100, std::memory_order_relaxed);
}

void AddStats(GroupQemStats& to, const GroupQemStats& s) {
  to.collapses += s.collapses;
  to.passes += s.passes;
  to.collapsesInPasses += s.collapsesInPasses;
  to.evaluations += s.evaluations;
  to.refusedTopology += s.refusedTopology;
  to.refusedCondition1 += s.refusedCondition1;
  to.refusedCondition2 += s.refusedCondition2;
  to.refusedLock += s.refusedLock;
  to.refusedFixed += s.refusedFixed;
  to.refusedGeometry += s.refusedGeometry;
  to.refusedCone += s.refusedCone;
  to.maxCollapseError = std::max(to.maxCollapseError, s.maxCollapseError);
}

}  // namespace

int PartitionCount(size_t faces, const GroupQemParams& qem, const PartitionParams& params) {
  (void)qem;
  if (params.minFaces == 0 || faces < params.minFaces || faces < 2) return 1;
  const size_t perPart = std::max<size_t>(1, params.facesPerPart);
  int parts = 2;
  while (parts < kMaxPartitions && faces > size_t(parts) * perPart) parts *= 2;
  return parts;
}

Status SimplifyPartitioned(const IndexedMesh& mesh, const std::vector<int>& faceGroup, const GroupQemParams& qem,
                           const PartitionParams& params, GroupQemResult& out, const Progress& progress,
                           PartitionStats* stats) {
  out = GroupQemResult();
  PartitionStats ps;
  if (stats) *stats = ps;
  const int parts = PartitionCount(mesh.faces.size(), qem, params);
  Status s = ValidateParams(qem);
  if (!s.ok()) return s;
  if (parts <= 1 || faceGroup.size() != mesh.faces.size())
    return SimplifyPreservingGroups(mesh, faceGroup, qem, out, progress);  // it also judges bad input
  s = RequireValidForFaces(mesh);
  if (!s.ok()) return s;
  for (int g : faceGroup)
    if (g < 0) return Status::Invalid("group ids must be >= 0");

  const auto start = std::chrono::steady_clock::now();
  ps.parts = parts;
  const std::vector<uint8_t> partOfFace = CutGroupsIntoParts(mesh, faceGroup, parts, -1);
  // The faces of each part, in input order (a counting sort).
  std::vector<size_t> begin(size_t(parts) + 1, 0);
  for (uint8_t p : partOfFace) ++begin[size_t(p) + 1];
  for (int p = 0; p < parts; ++p) begin[size_t(p) + 1] += begin[size_t(p)];
  std::vector<uint32_t> faceOrder(mesh.faces.size());
  {
    std::vector<size_t> at(begin.begin(), begin.end() - 1);
    for (uint32_t f = 0; f < partOfFace.size(); ++f) faceOrder[at[partOfFace[f]]++] = f;
  }
  // A vertex used by faces of two parts is shared: frozen while the parts run.
  std::vector<uint8_t> shared(mesh.positions.size(), 0);
  {
    std::vector<uint8_t> firstPart(mesh.positions.size(), 0xff);
    for (size_t f = 0; f < mesh.faces.size(); ++f)
      for (uint32_t v : mesh.faces[f]) {
        if (firstPart[v] == 0xff)
          firstPart[v] = partOfFace[f];
        else if (firstPart[v] != partOfFace[f])
          shared[v] = 1;
      }
  }
  for (uint8_t x : shared) ps.frozenVertices += x;
  const double diagonal = UsedVertexBox(mesh).Diag();
  const double ratio = qem.targetFaces > 0 ? double(qem.targetFaces) / double(mesh.faces.size()) : 0;

  std::vector<std::unique_ptr<Part>> part(static_cast<size_t>(parts));
  for (auto& p : part) p.reset(new Part);
  std::atomic<bool> cancel{false};
  std::atomic<int> next{0};
  const unsigned threads = unsigned(std::min(parts, params.threads > 0 ? params.threads : int(CoreCount())));
  const Progress partsProgress = SubProgress(progress, 0, 80);
  RunThreadsWhile(
      threads,
      [&](unsigned) {
        std::vector<uint32_t> local(mesh.positions.size(), kNone);
        for (int i; (i = next.fetch_add(1)) < parts;) {
          const size_t n = begin[size_t(i) + 1] - begin[size_t(i)];
          // Its share of the target (0: no face-count target, maxError alone), counted on the
          // faces that can go: those at a shared vertex stay for the final pass, which takes
          // them down to the same density (aiming the whole part at ratio x n would leave the
          // seams dense and the rest of the part coarser than the serial run).
          size_t seam = 0;
          for (size_t k = begin[size_t(i)]; k < begin[size_t(i) + 1]; ++k) {
            const auto& t = mesh.faces[faceOrder[k]];
            seam += (shared[t[0]] | shared[t[1]] | shared[t[2]]) != 0;
          }
          const size_t target =
              ratio > 0 ? std::max<size_t>(1, seam + size_t(std::floor(ratio * double(n - seam)))) : 0;
          if (n > 0)
            SimplifyOnePart(mesh, faceGroup, shared, faceOrder.data() + begin[size_t(i)], n, qem, diagonal, target,
                            local, cancel, *part[size_t(i)]);
          part[size_t(i)]->percent.store(100, std::memory_order_relaxed);
        }
      },
      [&] {
        if (!partsProgress || cancel.load()) return;
        int sum = 0;
        for (const auto& p : part) sum += p->percent.load(std::memory_order_relaxed);
        if (!partsProgress(std::min(99, sum / parts), "Simplifying in parts side by side")) cancel.store(true);
      });
  for (const auto& p : part)
    if (!p->status.ok() && p->status.code != Status::Code::Cancelled) return p->status;
  if (cancel.load()) return Status::Cancelled();
  for (const auto& p : part)
    if (!p->status.ok()) return p->status;

  // Stitch: surviving vertices and faces in their input order.
  GroupQemResult stitched;
  GroupQemStats total;
  {
    std::vector<uint32_t> newIndex(mesh.positions.size(), kNone);
    std::vector<vcg::Point3f> position(mesh.positions.size());
    std::vector<uint8_t> faceAlive(mesh.faces.size(), 0);
    std::vector<std::array<uint32_t, 3>> face(mesh.faces.size());
    for (int i = 0; i < parts; ++i) {
      const Part& p = *part[size_t(i)];
      const GroupQemResult& r = p.result;
      const uint32_t* faces = faceOrder.data() + begin[size_t(i)];
      for (size_t k = 0; k < r.sourceVertex.size(); ++k) {
        const uint32_t v = p.vertices[r.sourceVertex[k]];
        newIndex[v] = 0;
        position[v] = r.mesh.positions[k];
      }
      for (size_t k = 0; k < r.sourceFace.size(); ++k) {
        const uint32_t f = faces[r.sourceFace[k]];
        faceAlive[f] = 1;
        for (int c = 0; c < 3; ++c) face[f][size_t(c)] = p.vertices[r.sourceVertex[r.mesh.faces[k][size_t(c)]]];
      }
      AddStats(total, r.stats);
      ps.partsCpuSeconds += p.cpuSeconds;
      ps.largestPartCpuSeconds = std::max(ps.largestPartCpuSeconds, p.cpuSeconds);
    }
    part.clear();
    for (uint32_t v = 0; v < newIndex.size(); ++v)
      if (newIndex[v] == 0) {
        newIndex[v] = uint32_t(stitched.mesh.positions.size());
        stitched.mesh.positions.push_back(position[v]);
        stitched.sourceVertex.push_back(v);
      }
    for (uint32_t f = 0; f < face.size(); ++f)
      if (faceAlive[f]) {
        stitched.mesh.faces.push_back({newIndex[face[f][0]], newIndex[face[f][1]], newIndex[face[f][2]]});
        stitched.sourceFace.push_back(f);
      }
  }
  ps.facesAfterParts = stitched.mesh.faces.size();
  ps.partsSeconds = Seconds(start);

  // The final pass: the serial collapse over the stitched mesh, with the caller's parameters.
  const auto finalStart = std::chrono::steady_clock::now();
  std::vector<int> stitchedGroup(stitched.sourceFace.size());
  for (size_t f = 0; f < stitchedGroup.size(); ++f) stitchedGroup[f] = faceGroup[stitched.sourceFace[f]];
  GroupQemResult pass;
  GroupQemRegion whole;  // nothing frozen; errors relative to the input's diagonal, as in one piece
  whole.diagonal = diagonal;
  s = SimplifyPreservingGroups(stitched.mesh, stitchedGroup, qem, pass, SubProgress(progress, 80, 100), {}, &whole);
  if (!s.ok()) return s;  // (a cancelled pass: its partial mesh is dropped as well)
  ps.finalPassCollapses = pass.stats.collapses;
  ps.finalSeconds = Seconds(finalStart);

  out.mesh = std::move(pass.mesh);
  out.sourceFace.resize(pass.sourceFace.size());
  for (size_t f = 0; f < pass.sourceFace.size(); ++f) out.sourceFace[f] = stitched.sourceFace[pass.sourceFace[f]];
  out.sourceVertex.resize(pass.sourceVertex.size());
  for (size_t v = 0; v < pass.sourceVertex.size(); ++v)
    out.sourceVertex[v] = stitched.sourceVertex[pass.sourceVertex[v]];
  out.stats = pass.stats;
  AddStats(out.stats, total);
  out.stats.facesIn = mesh.faces.size();
  out.stats.maxCollapseError = std::max(pass.stats.maxCollapseError, total.maxCollapseError);
  if (stats) *stats = ps;
  return Status::Ok();
}

}  // namespace conelod
