// ConeLOD — sampled surface distance (see sampled_distance.h).
#include "conelod/mesh/sampled_distance.h"

#include <algorithm>
#include <cmath>

#include <vcg/complex/algorithms/closest.h>
#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/algorithms/update/normal.h>
#include <vcg/complex/complex.h>
#include <vcg/space/index/grid_static_ptr.h>

#include "conelod/mesh/mesh_check.h"

namespace conelod {
namespace {

// The smallest vcg mesh the closest-face query needs: positions, unit face normals, marks.
class DVertex;
class DFace;
struct DUsedTypes : public vcg::UsedTypes<vcg::Use<DVertex>::AsVertexType, vcg::Use<DFace>::AsFaceType> {};
class DVertex : public vcg::Vertex<DUsedTypes, vcg::vertex::Coord3f, vcg::vertex::BitFlags> {};
class DFace
    : public vcg::Face<DUsedTypes, vcg::face::VertexRef, vcg::face::Normal3f, vcg::face::Mark, vcg::face::BitFlags> {};
class DMesh : public vcg::tri::TriMesh<std::vector<DVertex>, std::vector<DFace>> {};
using Grid = vcg::GridStaticPtr<DFace, float>;

void Fill(const IndexedMesh& in, DMesh& m) {
  auto vi = vcg::tri::Allocator<DMesh>::AddVertices(m, in.positions.size());
  for (size_t v = 0; v < in.positions.size(); ++v, ++vi) vi->P() = in.positions[v];
  auto fi = vcg::tri::Allocator<DMesh>::AddFaces(m, in.faces.size());
  for (size_t f = 0; f < in.faces.size(); ++f, ++fi)
    for (int k = 0; k < 3; ++k) fi->V(k) = &m.vert[in.faces[f][size_t(k)]];
  vcg::tri::UpdateNormal<DMesh>::PerFaceNormalized(m);
  // The box of the vertices that faces use: an unreferenced vertex far away (at 1e20, say) would
  // stretch the grid over a box whose cells float cannot tell apart (a crash in the grid search).
  m.bbox.SetNull();
  for (const auto& t : in.faces)
    for (uint32_t v : t) m.bbox.Add(in.positions[v]);
}

// Indexes the faces of `target` for closest-face queries at points inside `queries`. vcglib's
// GridStaticPtr takes a point strictly inside its box to be in a cell, but float rounding can
// put a point just below the box's upper side into the cell past the last one (an out-of-range
// read, a crash on real meshes). The box here holds every query point with a margin, so no point
// is near its sides.
void IndexFaces(DMesh& target, vcg::Box3f queries, Grid& grid) {
  queries.Add(target.bbox);
  const float size = std::max({std::fabs(queries.min[0]), std::fabs(queries.min[1]), std::fabs(queries.min[2]),
                               std::fabs(queries.max[0]), std::fabs(queries.max[1]), std::fabs(queries.max[2])});
  const float margin = std::max(0.01f * queries.Diag(), std::max(1e-6f * size, 1e-30f));
  queries.Offset(margin);
  grid.Set(target.face.begin(), target.face.end(), queries);
}

uint64_t Next(uint64_t& s) {  // xorshift64*
  s ^= s >> 12;
  s ^= s << 25;
  s ^= s >> 27;
  return s * 0x2545F4914F6CDD1Dull;
}
double Unit(uint64_t& s) { return double(Next(s) >> 11) * (1.0 / 9007199254740992.0); }

struct Accumulator {
  double max = 0, sum = 0, sum2 = 0;
  size_t n = 0;
  void add(double d) {
    max = std::max(max, d);
    sum += d;
    sum2 += d * d;
    ++n;
  }
};

// The power of two that makes the used vertices of `a` and `b` together span about 1 (as
// NormalizingScale): the grid search runs in single precision, where the squared distances of a
// model 2^-64 times too small vanish into denormal numbers (a hundred times slower, and zero).
double JointNormalizingScale(const IndexedMesh& a, const IndexedMesh& b) {
  vcg::Box3d box = UsedVertexBox(a);
  box.Add(UsedVertexBox(b));
  if (box.IsNull()) return 1;
  const double d = box.Diag();
  if (!(d > 0) || !std::isfinite(d)) return 1;
  const int e = std::max(-120, std::min(120, int(std::lround(std::log2(d)))));
  return std::ldexp(1.0, -e);
}

// `m` times `scale` (a power of two: exact), or `m` itself when the scale is 1.
const IndexedMesh& Scaled(const IndexedMesh& m, double scale, IndexedMesh& storage) {
  if (scale == 1) return m;
  storage.faces = m.faces;
  storage.positions.resize(m.positions.size());
  const float s = float(scale);
  for (size_t v = 0; v < m.positions.size(); ++v) storage.positions[v] = m.positions[v] * s;
  return storage;
}

Status SampledDistanceScaled(const IndexedMesh& from, const IndexedMesh& to, int faceSamples, SurfaceDistance& out);

}  // namespace

Status SampledDistance(const IndexedMesh& from, const IndexedMesh& to, int faceSamples, SurfaceDistance& out) {
  out = SurfaceDistance();
  if (faceSamples < 0 || faceSamples > kMaxFaceSamples)
    return Status::Invalid("the number of samples must be from 0 to " + std::to_string(kMaxFaceSamples));
  // Computed on both meshes times a power of two and scaled back: the same digits at any scale. The
  // meshes are checked once scaled, so that coordinates beyond kMaxCoordinate (whose squares
  // overflow floats) are measured too.
  const double scale = JointNormalizingScale(from, to);
  IndexedMesh fromStorage, toStorage;
  const IndexedMesh& a = Scaled(from, scale, fromStorage);
  const IndexedMesh& b = Scaled(to, scale, toStorage);
  Status s = RequireValidForFaces(a);
  if (s.ok()) s = RequireValidForFaces(b);
  if (!s.ok()) return s;
  s = SampledDistanceScaled(a, b, faceSamples, out);
  out.max /= scale;
  out.mean /= scale;
  out.rms /= scale;
  return s;
}

namespace {

Status SampledDistanceScaled(const IndexedMesh& from, const IndexedMesh& to, int faceSamples, SurfaceDistance& out) {
  DMesh target;
  Fill(to, target);
  vcg::Box3f box = target.bbox;
  for (const auto& t : from.faces)
    for (uint32_t v : t) box.Add(from.positions[v]);
  Grid grid;
  IndexFaces(target, box, grid);
  const float maxDist = 2 * box.Diag() + 1;
  Accumulator acc;
  auto sample = [&](const vcg::Point3f& p) {
    float dist = maxDist;
    vcg::Point3f closest;
    if (vcg::tri::GetClosestFaceBase(target, grid, p, maxDist, dist, closest)) acc.add(dist);
  };
  std::vector<char> used(from.positions.size(), 0);
  for (const auto& t : from.faces)
    for (uint32_t v : t) used[v] = 1;
  for (size_t v = 0; v < from.positions.size(); ++v)
    if (used[v]) sample(from.positions[v]);
  // Face samples in proportion to area; the fractional parts carry over so the total is exact.
  std::vector<vcg::Point3d> normals;
  std::vector<double> areas;
  ComputeFaceNormalsAndAreas(from, normals, areas);
  double total = 0;
  for (double a : areas) total += a;
  if (total > 0 && faceSamples > 0) {
    uint64_t rng = 0x243F6A8885A308D3ull;
    double carry = 0;
    for (size_t f = 0; f < from.faces.size(); ++f) {
      carry += faceSamples * areas[f] / total;
      const vcg::Point3d a = vcg::Point3d::Construct(from.positions[from.faces[f][0]]);
      const vcg::Point3d b = vcg::Point3d::Construct(from.positions[from.faces[f][1]]);
      const vcg::Point3d c = vcg::Point3d::Construct(from.positions[from.faces[f][2]]);
      for (; carry >= 1; carry -= 1) {
        const double r1 = std::sqrt(Unit(rng)), r2 = Unit(rng);  // uniform on the triangle
        sample(vcg::Point3f::Construct(a * (1 - r1) + b * (r1 * (1 - r2)) + c * (r1 * r2)));
      }
    }
  }
  out.samples = acc.n;
  out.max = acc.max;
  out.mean = acc.n ? acc.sum / double(acc.n) : 0;
  out.rms = acc.n ? std::sqrt(acc.sum2 / double(acc.n)) : 0;
  return Status::Ok();
}

}  // namespace

Status SampledHausdorff(const IndexedMesh& a, const IndexedMesh& b, int faceSamples, HausdorffResult& out) {
  out = HausdorffResult();
  Status s = SampledDistance(a, b, faceSamples, out.ab);
  if (s.ok()) s = SampledDistance(b, a, faceSamples, out.ba);
  if (!s.ok()) return s;
  out.hausdorff = std::max(out.ab.max, out.ba.max);
  vcg::Box3d box;
  for (const auto& t : a.faces)
    for (uint32_t v : t) box.Add(vcg::Point3d::Construct(a.positions[v]));
  out.diagonal = box.Diag();
  return Status::Ok();
}

size_t CountFacesAgainstSurface(const IndexedMesh& coarseIn, const IndexedMesh& referenceIn) {
  if (referenceIn.faces.empty()) return 0;
  const double scale = JointNormalizingScale(coarseIn, referenceIn);  // as in SampledDistance
  IndexedMesh coarseStorage, referenceStorage;
  const IndexedMesh& coarse = Scaled(coarseIn, scale, coarseStorage);
  const IndexedMesh& reference = Scaled(referenceIn, scale, referenceStorage);
  DMesh target;
  Fill(reference, target);
  vcg::Box3f box;
  for (const auto& t : coarse.faces)
    for (uint32_t v : t) box.Add(coarse.positions[v]);
  Grid grid;
  IndexFaces(target, box, grid);
  const float maxDist = 2 * target.bbox.Diag() + 1;
  std::vector<vcg::Point3d> normals;
  std::vector<double> areas;
  ComputeFaceNormalsAndAreas(coarse, normals, areas);
  size_t against = 0;
  for (size_t f = 0; f < coarse.faces.size(); ++f) {
    if (areas[f] == 0) continue;
    const auto& t = coarse.faces[f];
    const vcg::Point3f c = (coarse.positions[t[0]] + coarse.positions[t[1]] + coarse.positions[t[2]]) / 3.0f;
    float dist = maxDist;
    vcg::Point3f closest;
    const DFace* g = vcg::tri::GetClosestFaceBase(target, grid, c, maxDist, dist, closest);
    if (g && vcg::Point3d::Construct(g->cN()) * normals[f] < 0) ++against;
  }
  return against;
}

}  // namespace conelod
