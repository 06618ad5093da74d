// ConeLOD — face-based PCA and the recursive PCA partition (see pca_partition.h).
#include "conelod/pca/pca_partition.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include <Eigen/Eigenvalues>

#include "conelod/common.h"
#include "conelod/mesh/mesh_check.h"

namespace conelod {
namespace {

using Vec3 = Eigen::Vector3d;

Vec3 ToVec(const vcg::Point3f& p) { return Vec3(p[0], p[1], p[2]); }
vcg::Point3f ToPoint(const Vec3& v) { return vcg::Point3f(float(v[0]), float(v[1]), float(v[2])); }

// Unit normal and area of face f (indexed_mesh.h's shared rule), one face at a time, so that the
// tree needs no per-face normal array.
double FaceNormalOf(const IndexedMesh& m, uint32_t f, vcg::Point3d& normal) {
  double area;
  FaceNormalAndArea(m, f, normal, area);
  return area;
}

// Additive sums of a set of triangles about a reference point p: area, Σ A_i (r_i − p) and
// Σ M_i(p) (upper triangle xx xy xz yy yz zz). Taking p near the set keeps the central moments
// accurate however far the mesh lies from the origin.
struct MomentSums {
  double area = 0;
  double first[3] = {0, 0, 0};
  double second[6] = {0, 0, 0, 0, 0, 0};

  // The triangle (a, b, c), already relative to p, with its area.
  void add(const Vec3& a, const Vec3& b, const Vec3& c, double A) {
    const Vec3 s = a + b + c;
    area += A;
    const double w = A / 3;
    first[0] += w * s[0];
    first[1] += w * s[1];
    first[2] += w * s[2];
    // M = A/12 (a aᵀ + b bᵀ + c cᵀ + s sᵀ)
    const double k = A / 12;
    second[0] += k * (a[0] * a[0] + b[0] * b[0] + c[0] * c[0] + s[0] * s[0]);
    second[1] += k * (a[0] * a[1] + b[0] * b[1] + c[0] * c[1] + s[0] * s[1]);
    second[2] += k * (a[0] * a[2] + b[0] * b[2] + c[0] * c[2] + s[0] * s[2]);
    second[3] += k * (a[1] * a[1] + b[1] * b[1] + c[1] * c[1] + s[1] * s[1]);
    second[4] += k * (a[1] * a[2] + b[1] * b[2] + c[1] * c[2] + s[1] * s[2]);
    second[5] += k * (a[2] * a[2] + b[2] * b[2] + c[2] * c[2] + s[2] * s[2]);
  }

  // Z_f = (Σ M_i − A r̄ r̄ᵀ)/A about the centroid (eq. 8), with d = r̄ − p.
  Eigen::Matrix3d covariance(Vec3& d) const {
    d = Vec3(first[0], first[1], first[2]) / area;
    Eigen::Matrix3d z;
    z << second[0], second[1], second[2], second[1], second[3], second[4], second[2], second[4], second[5];
    z /= area;
    z -= d * d.transpose();
    return z;
  }
};

// Eigen-decomposes a covariance into `frame` (ascending eigenvalues, x_max last). λ_min below
// 1e-10 λ_max is float noise on a planar set: it is reported as 0, so that planar clusters tie
// on the error and the larger one is split first.
void Decompose(const Eigen::Matrix3d& z, Vec3& eigenvalues, Eigen::Matrix3d& axes) {
  // computeDirect: the closed-form 3x3 solver, several times faster than the iterative one and
  // accurate to ~1e-15 λ_max, which is all the split direction and the error order need.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(z);
  eigenvalues = es.eigenvalues();
  axes = es.eigenvectors();
  for (int k = 0; k < 3; ++k) eigenvalues[k] = std::max(0.0, eigenvalues[k]);
  if (eigenvalues[0] <= 1e-10 * eigenvalues[2]) eigenvalues[0] = 0;
  if (!axes.allFinite()) {
    axes = Eigen::Matrix3d::Identity();
    eigenvalues.setZero();
  }
}

// The eigenvalues (ascending, with Decompose's rules) and x_max only: what a tree node stores.
// Eigen computes the eigenvalues; x_max is the largest cross product of two rows of Z − λ_max I
// (those rows span the plane orthogonal to x_max), which skips the two other eigenvectors.
void EigenvaluesAndMajorAxis(const Eigen::Matrix3d& z, Vec3& eigenvalues, Vec3& axisMax) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(z, Eigen::EigenvaluesOnly);
  eigenvalues = es.eigenvalues();
  for (int k = 0; k < 3; ++k) eigenvalues[k] = std::max(0.0, eigenvalues[k]);
  if (eigenvalues[0] <= 1e-10 * eigenvalues[2]) eigenvalues[0] = 0;
  auto kernel = [&z](double lambda, Vec3& out) {  // false when the kernel is more than a line
    const Eigen::Matrix3d a = z - lambda * Eigen::Matrix3d::Identity();
    const Vec3 c[3] = {a.row(0).cross(a.row(1)), a.row(0).cross(a.row(2)), a.row(1).cross(a.row(2))};
    int best = 0;
    for (int k = 1; k < 3; ++k)
      if (c[k].squaredNorm() > c[best].squaredNorm()) best = k;
    const double n2 = c[best].squaredNorm(), scale = a.squaredNorm();
    if (!(n2 > 1e-20 * scale * scale)) return false;
    out = c[best] / std::sqrt(n2);
    return true;
  };
  const Vec3 ev = es.eigenvalues();
  if (kernel(ev[2], axisMax)) return;
  // λ_max is (nearly) double: any direction orthogonal to x_min is a major axis.
  Vec3 axisMin;
  if (!kernel(ev[0], axisMin)) {
    axisMax = Vec3(1, 0, 0);
    return;
  }  // isotropic
  axisMax = axisMin.unitOrthogonal();
}

PcaFrame FrameFromSums(const MomentSums& s, const Vec3& p) {
  PcaFrame fr;
  fr.area = s.area;
  Vec3 d;
  const Eigen::Matrix3d z = s.covariance(d);
  fr.centroid = p + d;
  Decompose(z, fr.eigenvalues, fr.axes);
  return fr;
}

// The faces the caller asked for, or all of them.
template <class F>
void ForFaces(const IndexedMesh& m, const std::vector<uint32_t>* faces, F&& fn) {
  if (faces) {
    for (uint32_t f : *faces) fn(f);
  } else {
    for (uint32_t f = 0; f < uint32_t(m.faces.size()); ++f) fn(f);
  }
}

}  // namespace

Eigen::Matrix3d TriangleSecondMoment(const Vec3& a, const Vec3& b, const Vec3& c, double area) {
  const Vec3 s = a + b + c;
  return area / 12 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
}

PcaFrame FaceBasedPca(const IndexedMesh& m, const std::vector<uint32_t>* faces) {
  PcaFrame fr;
  bool first = true;
  Vec3 p(0, 0, 0), unweighted(0, 0, 0);
  size_t count = 0;
  MomentSums s;
  ForFaces(m, faces, [&](uint32_t f) {
    const auto& t = m.faces[f];
    if (first) {
      p = ToVec(m.positions[t[0]]);
      first = false;
    }
    const Vec3 a = ToVec(m.positions[t[0]]) - p, b = ToVec(m.positions[t[1]]) - p, c = ToVec(m.positions[t[2]]) - p;
    vcg::Point3d n;
    s.add(a, b, c, FaceNormalOf(m, f, n));
    unweighted += (a + b + c) / 3;
    ++count;
  });
  if (count == 0) return fr;
  if (!(s.area > 0)) {
    fr.centroid = p + unweighted / double(count);
    return fr;
  }
  return FrameFromSums(s, p);
}

PcaFrame VertexBasedPca(const IndexedMesh& m, const std::vector<uint32_t>* faces) {
  PcaFrame fr;
  std::vector<char> used(m.positions.size(), 0);
  std::vector<uint32_t> verts;
  ForFaces(m, faces, [&](uint32_t f) {
    for (uint32_t v : m.faces[f])
      if (!used[v]) {
        used[v] = 1;
        verts.push_back(v);
      }
  });
  if (verts.empty()) return fr;
  const Vec3 p = ToVec(m.positions[verts[0]]);
  Vec3 sum(0, 0, 0);
  for (uint32_t v : verts) sum += ToVec(m.positions[v]) - p;
  const double k = double(verts.size());
  const Vec3 d = sum / k;
  fr.centroid = p + d;
  if (verts.size() < 2) return fr;
  Eigen::Matrix3d z = Eigen::Matrix3d::Zero();
  for (uint32_t v : verts) {
    const Vec3 q = ToVec(m.positions[v]) - fr.centroid;
    z += q * q.transpose();
  }
  z /= (k - 1);  // eq. (1)
  Decompose(z, fr.eigenvalues, fr.axes);
  return fr;
}

NormalCone PcaBounds::cone() const {
  if (coneHalfAngle < 0) return NormalCone::Empty();
  if (coneHalfAngle >= NormalCone::kPi / 2) return NormalCone::Uncullable();
  NormalCone c;
  c.halfAngle = coneHalfAngle;
  c.axis = vcg::Point3d::Construct(coneAxis);
  return c;
}

int PcaTree::leafClusterCount() const {
  int n = 0;
  for (int32_t i = 0; i < int32_t(nodes.size()); ++i) {
    const PcaItemRange kids = children(i);
    if (kids.count == 0) ++n;
    for (PcaItem c : kids)
      if (IsFaceItem(c)) ++n;
  }
  return n;
}

size_t PcaTree::memoryBytes() const {
  return nodes.capacity() * sizeof(PcaNode) + bounds.capacity() * sizeof(PcaBounds) +
         components.capacity() * sizeof(PcaItem) + faceOrder.capacity() * sizeof(uint32_t);
}

Status ValidateParams(const PcaPartitionParams& p) {
  if (p.targetClusters < 0) return Status::Invalid("TargetClusters must be >= 0 (0: no limit)");
  if (p.maxDepth < 0) return Status::Invalid("MaxDepth must be >= 0 (0: no limit)");
  if (p.minFaces < 1) return Status::Invalid("MinFaces must be >= 1");
  if (!(p.maxErrorRms >= 0) || !std::isfinite(p.maxErrorRms))
    return Status::Invalid("MaxError must be a finite length >= 0 (0: no limit)");
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// The builder

namespace {

// Per-face mark while a cluster is split: (generation << kStateBits) | state. A face belongs to
// the cluster being split iff its generation is the current one, so no per-face owner array has
// to be rewritten after each split.
enum : uint32_t { kOnPlane = 0, kPositive = 1, kNegative = 2, kSide1 = 3, kSide2 = 4, kLeftover = 5 };
constexpr int kStateBits = 3;
constexpr uint32_t kStateMask = (1u << kStateBits) - 1;

// Area, area centroid and central second moment C = Σ ∫ (r − r̄)(r − r̄)ᵀ dS = A Z_f of a set of
// triangles. Central moments subtract well: the larger child of a split is the parent minus the
// smaller child (parallel-axis theorem), so only the smaller child's faces are summed.
struct Moments {
  double area = 0;
  Vec3 centroid{0, 0, 0};
  Eigen::Matrix3d central = Eigen::Matrix3d::Zero();

  static Moments FromSums(const MomentSums& s, const Vec3& p) {
    Moments m;
    m.area = s.area;
    if (!(s.area > 0)) {
      m.centroid = p;
      return m;
    }
    Vec3 d;
    m.central = s.covariance(d) * s.area;
    m.centroid = p + d;
    return m;
  }
  // The parent minus `part`: the moments of the other part.
  Moments minus(const Moments& part) const {
    Moments r;
    r.area = area - part.area;
    r.centroid = centroid + (centroid - part.centroid) * (part.area / r.area);
    const Vec3 ds = part.centroid - centroid, dr = r.centroid - centroid;
    r.central = central - part.central - part.area * ds * ds.transpose() - r.area * dr * dr.transpose();
    return r;
  }
};

// 30-bit Morton code of a point of the box (10 bits per axis).
uint32_t Morton(const Vec3& p, const Vec3& lo, const Vec3& scale) {
  uint32_t q[3];
  for (int k = 0; k < 3; ++k) q[k] = uint32_t(std::min(1023.0, std::max(0.0, (p[k] - lo[k]) * scale[k])));
  return (SpreadBits10(q[0]) << 2) | (SpreadBits10(q[1]) << 1) | SpreadBits10(q[2]);
}

class TreeBuilder {
 public:
  TreeBuilder(const IndexedMesh& mesh, const PcaPartitionParams& params, PcaTree& tree)
      : mesh_(mesh), params_(params), tree_(tree) {}

  Status run(const Progress& progress);

 private:
  struct Pending {
    int32_t node;
    Moments moments;
  };

  bool canSplit(const PcaNode& n) const {
    if (n.faceCount <= uint32_t(std::max(1, params_.minFaces))) return false;
    if (params_.maxDepth > 0 && n.depth >= params_.maxDepth) return false;
    if (params_.maxErrorRms > 0 && std::sqrt(double(n.eigenvalues[0])) <= params_.maxErrorRms * scale_) return false;
    return true;
  }
  void renumber();
  Moments sum(uint32_t firstFace, uint32_t faceCount) const;
  int32_t MakeNode(int32_t parent, uint32_t firstFace, uint32_t faceCount, int32_t depth, const Moments& m);
  void split(const Pending& p, Pending out[2], int& outCount);
  uint32_t grow(uint32_t seed, uint32_t accept, uint32_t mark, uint32_t* out);
  void GrowBoth(uint32_t seed1, uint32_t seed2, uint32_t& left, uint32_t& right);
  void AttachLeftovers(uint32_t begin, uint32_t end, uint32_t& left, uint32_t& right);
  void ComputeBounds();
  void toInputNumbering();

  const IndexedMesh& mesh_;
  const PcaPartitionParams& params_;
  PcaTree& tree_;
  // The mesh renumbered in Morton order of the face centroids (vertices in order of first use):
  // clusters are then compact in memory as well as in space, and the region growing, which
  // touches neighbours of neighbours, stays in cache. Positions are the input's floats.
  IndexedMesh local_;
  std::vector<uint32_t> inputFace_;  // local face -> input face
  Vec3 origin_{0, 0, 0};             // the bounding-box centre (times scale_)
  // While splitting, every length is in coordinates times scale_ (NormalizingScale): the faces'
  // float areas and second moments (lengths to the fourth) neither overflow nor vanish whatever
  // the model's size, so the splits do not depend on it. The nodes are given back in the mesh's
  // coordinates at the end (exactly: scale_ is a power of two).
  double scale_ = 1;
  // What a split reads and writes per face, in one 32-byte record: the R pass warms the cache
  // lines that the region growing then reads (neighbour lists and marks).
  struct FaceRecord {
    vcg::Point3f centroid;  // relative to origin_
    float area;
    uint32_t mark;    // see kStateBits
    uint32_t nbr[3];  // edge neighbours; the sentinel for none; kManyNeighbours: see adj_
  };
  static constexpr uint32_t kManyNeighbours = 0xFFFFFFFEu;
  // Calls fn(g) for every neighbour g of f, and for the sentinel record (whose mark matches no
  // state) in place of missing neighbours: the common case runs without branches on the mesh.
  template <class F>
  void ForNeighbours(uint32_t f, F&& fn) const {
    const uint32_t* nb = rec_[f].nbr;
    if (nb[0] == kManyNeighbours) {  // more than three (non-manifold edges): the full lists
      for (uint32_t i = adj_.offsets[f]; i < adj_.offsets[f + 1]; ++i) fn(adj_.neighbours[i]);
      return;
    }
    fn(nb[0]);
    fn(nb[1]);
    fn(nb[2]);
  }
  std::vector<FaceRecord> rec_;  // per local face, then the sentinel
  // Per local face: its second moment about its own centroid, (A/12) Σ (v−g)(v−g)ᵀ (xx xy xz yy
  // yz zz). With it M_i(p) = that + A (g−p)(g−p)ᵀ: summing a face needs no vertex, and the sums are
  // as accurate as the float centroids, i.e. as the input's own float coordinates.
  std::vector<std::array<float, 6>> ownMoment_;
  std::vector<uint32_t> side2_;  // the second half while it grows
  FaceAdjacency adj_;            // kept only when some face has more than three neighbours
  uint32_t generation_ = 0;
  std::vector<uint32_t> members_;  // the faces of the cluster being split
};

void TreeBuilder::renumber() {
  const uint32_t nf = uint32_t(mesh_.faces.size());
  vcg::Box3d box;
  for (const auto& t : mesh_.faces)
    for (uint32_t v : t) box.Add(vcg::Point3d::Construct(mesh_.positions[v]));
  scale_ = NormalizingScale(mesh_);
  origin_ = Vec3(box.Center()[0], box.Center()[1], box.Center()[2]) * scale_;
  const Vec3 lo(box.min[0], box.min[1], box.min[2]);
  Vec3 scale;
  for (int k = 0; k < 3; ++k) scale[k] = box.Dim()[k] > 0 ? 1023.999 / box.Dim()[k] : 0.0;
  // Radix sort of (code, face) by the code's two 16-bit halves: stable, O(N).
  std::vector<uint32_t> key(nf), order(nf), tmp(nf);
  for (uint32_t f = 0; f < nf; ++f) {
    const auto& t = mesh_.faces[f];
    const Vec3 c = (ToVec(mesh_.positions[t[0]]) + ToVec(mesh_.positions[t[1]]) + ToVec(mesh_.positions[t[2]])) / 3;
    key[f] = Morton(c, lo, scale);
    order[f] = f;
  }
  for (int shift = 0; shift < 32; shift += 16) {
    std::vector<uint32_t> count(65537, 0);
    for (uint32_t f : order) ++count[((key[f] >> shift) & 0xFFFF) + 1];
    for (size_t i = 1; i < count.size(); ++i) count[i] += count[i - 1];
    for (uint32_t f : order) tmp[count[(key[f] >> shift) & 0xFFFF]++] = f;
    order.swap(tmp);
  }
  key = std::vector<uint32_t>();
  tmp = std::vector<uint32_t>();
  inputFace_ = std::move(order);

  std::vector<uint32_t> localVertex(mesh_.positions.size(), UINT32_MAX);
  local_.faces.resize(nf);
  local_.positions.reserve(mesh_.positions.size());
  for (uint32_t lf = 0; lf < nf; ++lf) {
    const auto& t = mesh_.faces[inputFace_[lf]];
    for (int k = 0; k < 3; ++k) {
      uint32_t& lv = localVertex[t[size_t(k)]];
      if (lv == UINT32_MAX) {
        lv = uint32_t(local_.positions.size());
        local_.positions.push_back(mesh_.positions[t[size_t(k)]]);
      }
      local_.faces[lf][size_t(k)] = lv;
    }
  }
  rec_.resize(size_t(nf) + 1);
  ownMoment_.resize(nf);
  rec_[nf].mark = 0xFFFFFFFFu;  // the sentinel: state 7 is never used, so it never matches
  for (uint32_t f = 0; f < nf; ++f) {
    const auto& t = local_.faces[f];
    const Vec3 c = (ToVec(local_.positions[t[0]]) + ToVec(local_.positions[t[1]]) + ToVec(local_.positions[t[2]])) / 3;
    rec_[f].centroid = ToPoint(c * scale_ - origin_);
    vcg::Point3d n;
    const double area = FaceNormalOf(local_, f, n) * scale_ * scale_;
    rec_[f].area = float(area);
    rec_[f].mark = 0;
    double o[6] = {0, 0, 0, 0, 0, 0};
    for (uint32_t v : t) {
      const double ux = (local_.positions[v][0] - c[0]) * scale_, uy = (local_.positions[v][1] - c[1]) * scale_,
                   uz = (local_.positions[v][2] - c[2]) * scale_;
      o[0] += ux * ux;
      o[1] += ux * uy;
      o[2] += ux * uz;
      o[3] += uy * uy;
      o[4] += uy * uz;
      o[5] += uz * uz;
    }
    const double k = area / 12;
    for (int i = 0; i < 6; ++i) ownMoment_[f][size_t(i)] = float(k * o[i]);
  }
}

// Moments of faceOrder[firstFace, +faceCount), summed about the first face's centroid (a point of
// the set, so that the sums keep their precision wherever the mesh lies).
Moments TreeBuilder::sum(uint32_t firstFace, uint32_t faceCount) const {
  const uint32_t* order = tree_.faceOrder.data() + firstFace;
  const FaceRecord* rec = rec_.data();
  const std::array<float, 6>* own = ownMoment_.data();
  const vcg::Point3f& p = rec[order[0]].centroid;  // relative to origin_
  const double px = p[0], py = p[1], pz = p[2];
  double area = 0, fx = 0, fy = 0, fz = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
  for (uint32_t i = 0; i < faceCount; ++i) {
    const uint32_t f = order[i];
    const FaceRecord& r = rec[f];
    const double a = r.area;
    const double gx = r.centroid[0] - px, gy = r.centroid[1] - py, gz = r.centroid[2] - pz;
    const double ax = a * gx, ay = a * gy, az = a * gz;
    const std::array<float, 6>& o = own[f];
    area += a;
    fx += ax;
    fy += ay;
    fz += az;
    xx += o[0] + ax * gx;
    xy += o[1] + ax * gy;
    xz += o[2] + ax * gz;
    yy += o[3] + ay * gy;
    yz += o[4] + ay * gz;
    zz += o[5] + az * gz;
  }
  MomentSums s;
  s.area = area;
  s.first[0] = fx;
  s.first[1] = fy;
  s.first[2] = fz;
  s.second[0] = xx;
  s.second[1] = xy;
  s.second[2] = xz;
  s.second[3] = yy;
  s.second[4] = yz;
  s.second[5] = zz;
  const Vec3 pAbs = origin_ + Vec3(px, py, pz);
  Moments m = Moments::FromSums(s, pAbs);
  if (!(m.area > 0)) {  // zero-area faces only: the mean of the face centroids
    Vec3 c(0, 0, 0);
    for (uint32_t i = 0; i < faceCount; ++i) c += ToVec(rec[order[i]].centroid);
    m.centroid = origin_ + c / double(faceCount);
  }
  return m;
}

int32_t TreeBuilder::MakeNode(int32_t parent, uint32_t firstFace, uint32_t faceCount, int32_t depth, const Moments& m) {
  const int32_t id = int32_t(tree_.nodes.size());
  tree_.nodes.emplace_back();
  PcaNode& n = tree_.nodes.back();
  n.parent = parent;
  n.depth = depth;
  n.firstFace = firstFace;
  n.faceCount = faceCount;
  n.area = float(m.area);
  n.centroid = ToPoint(m.centroid);
  if (m.area > 0) {
    Vec3 ev, axis;
    EigenvaluesAndMajorAxis(m.central / m.area, ev, axis);
    n.eigenvalues = ToPoint(ev);
    n.axis = ToPoint(axis);
  } else {  // zero-area faces only: no PCA; split() grows both halves from two faces
    n.eigenvalues = vcg::Point3f(0, 0, 0);
    n.axis = vcg::Point3f(1, 0, 0);
  }
  return id;
}

// Breadth-first growth from `seed` over faces marked `accept` (which carries the generation, so
// only faces of the cluster match), re-marking them `mark`. The grown faces are written to `out`,
// which is the BFS queue too; `out` must have room for one more entry than can be grown (each
// neighbour is written at the tail whether it is taken or not: no unpredictable branch). Returns
// how many faces were grown.
uint32_t TreeBuilder::grow(uint32_t seed, uint32_t accept, uint32_t mark, uint32_t* out) {
  FaceRecord* rec = rec_.data();
  rec[seed].mark = mark;
  out[0] = seed;
  uint32_t head = 0, tail = 1;
  while (head != tail) {
    ForNeighbours(out[head++], [&](uint32_t g) {
      const uint32_t m = rec[g].mark;
      const bool take = m == accept;
      rec[g].mark = take ? mark : m;
      out[tail] = g;
      tail += take ? 1 : 0;
    });
  }
  return tail;
}

// Both halves grown at once, breadth-first, from two faces: the split of a cluster that has no
// split plane (every face centroid on it, or no area). Side 1 is written forwards from `left`,
// side 2 backwards from `right` (one past the end); each face goes to the side that reaches it
// first, so both sides are connected and non-empty.
void TreeBuilder::GrowBoth(uint32_t seed1, uint32_t seed2, uint32_t& left, uint32_t& right) {
  uint32_t* order = tree_.faceOrder.data();
  const uint32_t base = generation_ << kStateBits;
  for (uint32_t f : members_) rec_[f].mark = base | kOnPlane;
  rec_[seed1].mark = base | kSide1;
  rec_[seed2].mark = base | kSide2;
  uint32_t head1 = left, head2 = right - 1;
  order[left++] = seed1;
  order[--right] = seed2;
  while (head1 < left || head2 >= right) {
    for (int side = 0; side < 2; ++side) {
      const bool first = side == 0;
      if (first ? head1 >= left : head2 < right) continue;
      const uint32_t f = first ? order[head1++] : order[head2--];
      ForNeighbours(f, [&](uint32_t g) {
        if (rec_[g].mark != (base | kOnPlane)) return;
        rec_[g].mark = base | (first ? kSide1 : kSide2);
        if (first)
          order[left++] = g;
        else
          order[--right] = g;
      });
    }
  }
}

// Faces reached by neither growth: each connected region of them joins, whole, the side it
// shares more edges with (the side with fewer faces on a tie). The regions are written into the
// gap [left, right) of faceOrder and moved to the chosen side's end.
void TreeBuilder::AttachLeftovers(uint32_t begin, uint32_t end, uint32_t& left, uint32_t& right) {
  uint32_t* order = tree_.faceOrder.data();
  const uint32_t base = generation_ << kStateBits;
  for (uint32_t seed : members_) {
    if ((rec_[seed].mark & kStateMask) > kNegative) continue;  // grown, or in a region already
    // Breadth-first over the region, queued at [left, left + size).
    uint32_t head = left, tail = left;
    rec_[seed].mark = base | kLeftover;
    order[tail++] = seed;
    uint64_t touch1 = 0, touch2 = 0;
    while (head < tail) {
      ForNeighbours(order[head++], [&](uint32_t g) {
        const uint32_t m = rec_[g].mark;
        if ((m >> kStateBits) != generation_) return;  // not in this cluster
        const uint32_t sg = m & kStateMask;
        if (sg == kSide1)
          ++touch1;
        else if (sg == kSide2)
          ++touch2;
        else if (sg != kLeftover) {
          rec_[g].mark = base | kLeftover;
          order[tail++] = g;
        }
      });
    }
    const uint32_t size = tail - left;
    const bool toSide1 = touch1 != touch2 ? touch1 > touch2 : (left - begin) <= (end - right);
    const uint32_t mark = base | (toSide1 ? kSide1 : kSide2);
    for (uint32_t i = left; i < tail; ++i) rec_[order[i]].mark = mark;
    if (toSide1) {
      left = tail;
    } else {
      std::memmove(order + right - size, order + left, size * sizeof(uint32_t));
      right -= size;
    }
    if (left == right) return;
  }
}

// Splits p.node into two edge-connected halves; `out` receives the halves that are nodes.
void TreeBuilder::split(const Pending& p, Pending out[2], int& outCount) {
  const PcaNode node = tree_.nodes[size_t(p.node)];  // a copy: MakeNode() appends to the array
  const uint32_t n = node.faceCount, begin = node.firstFace, end = begin + n;
  uint32_t* order = tree_.faceOrder.data();
  outCount = 0;
  if (n == 2) {  // every split of two faces gives the two faces (a third of all splits)
    tree_.nodes[size_t(p.node)].child[0] = ItemOfFace(order[begin]);
    tree_.nodes[size_t(p.node)].child[1] = ItemOfFace(order[begin + 1]);
    return;
  }
  // The member list survives the growth, which overwrites this range of faceOrder: the
  // leftover regions are searched in it.
  members_.assign(order + begin, order + end);
  ++generation_;
  const uint32_t base = generation_ << kStateBits;

  // R_i = x_max · (r_i − r̄) = x_max · r_i − x_max · r̄ for every face; the seeds are the extremes.
  const float ax = node.axis[0], ay = node.axis[1], az = node.axis[2];
  const vcg::Point3f c = ToPoint(ToVec(node.centroid) - origin_);
  const float offset = ax * c[0] + ay * c[1] + az * c[2];
  float rMax = -std::numeric_limits<float>::infinity(), rMin = std::numeric_limits<float>::infinity();
  uint32_t seed1 = members_[0], seed2 = members_[n - 1];
  FaceRecord* rec = rec_.data();
  for (uint32_t f : members_) {
    FaceRecord& fr = rec[f];
    const float r = ax * fr.centroid[0] + ay * fr.centroid[1] + az * fr.centroid[2] - offset;
    fr.mark = base | uint32_t(r > 0) | (uint32_t(r < 0) << 1);  // kPositive, kNegative or kOnPlane
    if (r > rMax) {
      rMax = r;
      seed1 = f;
    }
    if (r < rMin) {
      rMin = r;
      seed2 = f;
    }
  }

  uint32_t left = begin, right = end;
  if (node.area > 0 && rMax > 0 && rMin < 0) {
    // Side 1 grows in place (it cannot take seed 2, so the spare slot exists); side 2 grows
    // aside and moves to the end of the range.
    left += grow(seed1, base | kPositive, base | kSide1, order + begin);
    if (side2_.size() < size_t(n) + 1) side2_.resize(size_t(n) + 1);
    const uint32_t n2 = grow(seed2, base | kNegative, base | kSide2, side2_.data());
    right -= n2;
    std::memcpy(order + right, side2_.data(), n2 * sizeof(uint32_t));
  } else {
    GrowBoth(members_[0], members_[n - 1], left, right);
  }
  if (left < right) AttachLeftovers(begin, end, left, right);

  // The halves [begin, left) and [left, end). Only the smaller one is summed.
  const uint32_t n1 = left - begin, n2 = end - left;
  const bool firstSmaller = n1 <= n2;
  const Moments small = firstSmaller ? sum(begin, n1) : sum(left, n2);
  Moments large = p.moments.minus(small);
  // A part of (almost) no area would come out of the subtraction as noise: sum it instead.
  if (!(large.area > 1e-9 * p.moments.area)) large = firstSmaller ? sum(left, n2) : sum(begin, n1);
  const Moments* m[2] = {firstSmaller ? &small : &large, firstSmaller ? &large : &small};
  const uint32_t first[2] = {begin, left}, count[2] = {n1, n2};
  for (int k = 0; k < 2; ++k) {
    PcaItem item;
    if (count[k] == 1) {
      item = ItemOfFace(order[first[k]]);
    } else {
      item = MakeNode(p.node, first[k], count[k], node.depth + 1, *m[k]);
      out[outCount++] = Pending{item, *m[k]};
    }
    tree_.nodes[size_t(p.node)].child[k] = item;
  }
}

// Cones and boxes bottom-up: a child's index is above its parent's, so a backward sweep sees
// every child before its parent. Single faces give their own normal and box; a leaf cluster (a
// stop criterion held) gets the exact minimal cone of its normals.
void TreeBuilder::ComputeBounds() {
  tree_.bounds.resize(tree_.nodes.size());
  auto addFace = [this](vcg::Box3f& b, uint32_t f) {
    for (uint32_t v : local_.faces[f]) b.Add(local_.positions[v]);
  };
  auto store = [](PcaBounds& b, const NormalCone& cone) {
    if (cone.empty()) {
      b.coneHalfAngle = -1;
      return;
    }
    if (!cone.cullable()) {
      b.coneHalfAngle = float(NormalCone::kPi);
      return;
    }
    b.coneAxis = vcg::Point3f::Construct(cone.axis);
    // Rounding to float must not let a normal out: pad by a few float ulps.
    b.coneHalfAngle = float(cone.halfAngle + 1e-6);
  };
  std::vector<vcg::Point3d> normals;
  for (size_t i = tree_.nodes.size(); i-- > 0;) {
    const PcaNode& node = tree_.nodes[i];
    PcaBounds& bounds = tree_.bounds[i];
    bounds.box.SetNull();
    const PcaItemRange kids = tree_.children(int32_t(i));
    if (kids.count == 0) {
      normals.clear();
      for (uint32_t k = 0; k < node.faceCount; ++k) {
        const uint32_t f = tree_.faceOrder[node.firstFace + k];
        vcg::Point3d nrm;
        FaceNormalOf(local_, f, nrm);
        normals.push_back(nrm);
        addFace(bounds.box, f);
      }
      store(bounds, MinimalCone(normals));
      continue;
    }
    NormalCone cone = NormalCone::Empty();
    for (PcaItem c : kids) {
      if (IsFaceItem(c)) {
        vcg::Point3d nrm;
        if (FaceNormalOf(local_, FaceOfItem(c), nrm) > 0)
          cone = cone.empty() ? NormalCone::Of(nrm) : FastUnionCone(cone, NormalCone::Of(nrm));
        addFace(bounds.box, FaceOfItem(c));
      } else {
        const NormalCone childCone = tree_.bounds[size_t(c)].cone();
        if (!childCone.empty()) cone = cone.empty() ? childCone : FastUnionCone(cone, childCone);
        bounds.box.Add(tree_.bounds[size_t(c)].box);
      }
    }
    store(bounds, cone);
  }
}

// Face ids back to the input's numbering.
void TreeBuilder::toInputNumbering() {
  for (uint32_t& f : tree_.faceOrder) f = inputFace_[f];
  auto remap = [this](PcaItem& item) {
    if (IsFaceItem(item)) item = ItemOfFace(inputFace_[FaceOfItem(item)]);
  };
  for (PcaNode& node : tree_.nodes)
    for (PcaItem& c : node.child)
      if (c != kNoChild) remap(c);
  for (PcaItem& c : tree_.components) remap(c);
}

Status TreeBuilder::run(const Progress& progress) {
  const uint32_t nf = uint32_t(mesh_.faces.size());
  tree_ = PcaTree();
  tree_.faceCount = int(nf);
  renumber();
  bool anyArea = false;
  for (uint32_t f = 0; f < nf && !anyArea; ++f) anyArea = rec_[f].area > 0;
  if (!anyArea) {  // the last check of RequireValidForFaces(), with its message
    MeshReport r;
    r.vertices = mesh_.positions.size();
    r.faces = r.degenerateFaces = nf;
    return RequireValidForFaces(r);
  }
  adj_ = BuildFaceAdjacency(local_);
  if (progress && !progress(5, "PCA partition: adjacency")) return Status::Cancelled();

  // Components, as consecutive ranges of faceOrder (counting sort, faces in local order).
  std::vector<uint32_t> compStart;
  {
    std::vector<int> comp;
    const int components = ConnectedComponents(adj_, comp);
    tree_.componentCount = components;
    compStart.assign(size_t(components) + 1, 0);
    for (int c : comp) ++compStart[size_t(c) + 1];
    for (int c = 0; c < components; ++c) compStart[size_t(c) + 1] += compStart[size_t(c)];
    tree_.faceOrder.resize(nf);
    std::vector<uint32_t> fill(compStart.begin(), compStart.end() - 1);
    for (uint32_t f = 0; f < nf; ++f) tree_.faceOrder[fill[size_t(comp[f])]++] = f;
  }
  const int components = tree_.componentCount;
  bool many = false;
  for (uint32_t f = 0; f < nf; ++f) {
    uint32_t* nb = rec_[f].nbr;
    const uint32_t degree = adj_.offsets[f + 1] - adj_.offsets[f];
    for (uint32_t k = 0; k < 3; ++k) nb[k] = k < degree ? adj_.neighbours[adj_.offsets[f] + k] : nf;
    if (degree > 3) {
      nb[0] = kManyNeighbours;
      many = true;
    }
  }
  if (!many) adj_ = FaceAdjacency();

  // At most one node per split and child: reserve once, so that no reallocation copies the tree.
  const size_t maxNodes = params_.targetClusters > 0 ? 2 * size_t(params_.targetClusters) + 1 : size_t(nf);
  tree_.nodes.reserve(std::min(size_t(nf), maxNodes) + size_t(components) + 1);

  std::vector<Pending> pending;  // clusters that may be split
  const Moments all = sum(0, nf);
  MakeNode(-1, 0, nf, 0, all);  // the root
  int clusters = 1;
  if (components > 1) {
    tree_.components.resize(size_t(components));
    for (int c = 0; c < components; ++c) {
      const uint32_t first = compStart[size_t(c)], count = compStart[size_t(c) + 1] - first;
      if (count == 1) {
        tree_.components[size_t(c)] = ItemOfFace(tree_.faceOrder[first]);
        continue;
      }
      const Moments m = sum(first, count);
      tree_.components[size_t(c)] = MakeNode(0, first, count, 1, m);
      pending.push_back(Pending{tree_.components[size_t(c)], m});
    }
    clusters = components;
  } else {
    pending.push_back(Pending{0, all});
  }

  // Best-first (largest error, then area, then position) when a cluster count is asked for, so
  // that the result equals that cut of the full tree; depth-first otherwise.
  const bool bestFirst = params_.targetClusters > 0;
  auto before = [this](const Pending& a, const Pending& b) {  // heap order: b is split before a
    const PcaNode& x = tree_.nodes[size_t(a.node)];
    const PcaNode& y = tree_.nodes[size_t(b.node)];
    if (x.eigenvalues[0] != y.eigenvalues[0]) return x.eigenvalues[0] < y.eigenvalues[0];
    if (x.area != y.area) return x.area < y.area;
    return x.firstFace > y.firstFace;
  };
  auto splittable = [this](const Pending& p) { return canSplit(tree_.nodes[size_t(p.node)]); };
  pending.erase(std::remove_if(pending.begin(), pending.end(), [&](const Pending& p) { return !splittable(p); }),
                pending.end());
  if (bestFirst) std::make_heap(pending.begin(), pending.end(), before);
  uint64_t facesDone = nf;  // for progress: faces in clusters that will not be split again
  for (const Pending& p : pending) facesDone -= tree_.nodes[size_t(p.node)].faceCount;

  uint64_t splits = 0;
  Pending halves[2];
  int halfCount = 0;
  while (!pending.empty()) {
    if (bestFirst && clusters >= params_.targetClusters) break;
    if (bestFirst) std::pop_heap(pending.begin(), pending.end(), before);
    const Pending p = pending.back();
    pending.pop_back();
    split(p, halves, halfCount);
    ++clusters;
    facesDone += tree_.nodes[size_t(p.node)].faceCount;
    for (int k = halfCount - 1; k >= 0; --k) {  // depth-first continues with the first half
      if (!splittable(halves[k])) continue;
      facesDone -= tree_.nodes[size_t(halves[k].node)].faceCount;
      pending.push_back(halves[k]);
      if (bestFirst) std::push_heap(pending.begin(), pending.end(), before);
    }
    if (progress && (++splits & 4095) == 0) {
      const int pct = bestFirst ? int(85.0 * clusters / params_.targetClusters) : int(85.0 * facesDone / nf);
      if (!progress(5 + std::min(85, pct), "PCA partition: splitting")) return Status::Cancelled();
    }
  }
  // The split pass's work arrays go before the bounds are allocated: a lower peak of memory.
  adj_ = FaceAdjacency();
  rec_ = std::vector<FaceRecord>();
  ownMoment_ = std::vector<std::array<float, 6>>();
  members_ = std::vector<uint32_t>();
  side2_ = std::vector<uint32_t>();
  const double inv = 1 / scale_;
  for (PcaNode& node : tree_.nodes) {
    node.area = float(node.area * inv * inv);
    node.centroid = ToPoint(ToVec(node.centroid) * inv);
    node.eigenvalues = ToPoint(ToVec(node.eigenvalues) * (inv * inv));
  }
  if (progress && !progress(92, "PCA partition: cones and boxes")) return Status::Cancelled();
  ComputeBounds();
  local_ = IndexedMesh();
  toInputNumbering();
  int maxDepth = 0;
  for (int32_t i = 0; i < int32_t(tree_.nodes.size()); ++i)
    maxDepth = std::max(maxDepth, tree_.nodes[size_t(i)].depth + (tree_.isLeaf(i) ? 0 : 1));
  tree_.maxDepth = maxDepth;
  if (progress && !progress(100, "PCA partition: done")) return Status::Cancelled();
  return Status::Ok();
}

}  // namespace

Status BuildPcaTree(const IndexedMesh& mesh, const PcaPartitionParams& params, PcaTree& out, const Progress& progress) {
  out = PcaTree();
  Status s = ValidateParams(params);
  if (!s.ok()) return s;
  // Only the checks that must come before the build run here (the build computes the areas and
  // reports a mesh of zero-area faces itself); RequireValidForFaces() words the message when one
  // fails.
  bool valid = !mesh.faces.empty();
  for (const auto& t : mesh.faces) {
    for (uint32_t v : t) {
      if (v >= mesh.positions.size()) {
        valid = false;
        break;
      }
      const auto& p = mesh.positions[v];
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) valid = false;
      if (std::fabs(p[0]) > kMaxCoordinate || std::fabs(p[1]) > kMaxCoordinate || std::fabs(p[2]) > kMaxCoordinate)
        valid = false;
    }
    if (!valid) break;
  }
  if (!valid) {
    s = RequireValidForFaces(mesh);
    if (!s.ok()) return s;
  }
  if (mesh.faces.size() >= (size_t(1) << (32 - kStateBits)))
    return Status::Invalid("the mesh has too many faces for the PCA partition (2^29 or more)");
  PcaTree tree;
  s = TreeBuilder(mesh, params, tree).run(progress);
  if (s.ok()) out = std::move(tree);
  return s;
}

// ---------------------------------------------------------------------------------------------
// Cuts

namespace {

// Walks the splits largest error first. `visit(node)` is told of each split; the walk stops when
// it returns false. Returns the clusters of the final cut, each with its first position in
// faceOrder, in faceOrder order.
template <class Visit>
std::vector<PcaItem> WalkSplits(const PcaTree& tree, Visit&& visit) {
  std::vector<PcaItem> cut;
  if (tree.empty()) return cut;
  struct Entry {
    PcaItem item;
    uint32_t position;
  };
  std::vector<Entry> done;
  auto before = [&tree](int32_t a, int32_t b) {
    const PcaNode& x = tree.nodes[size_t(a)];
    const PcaNode& y = tree.nodes[size_t(b)];
    if (x.eigenvalues[0] != y.eigenvalues[0]) return x.eigenvalues[0] < y.eigenvalues[0];
    if (x.area != y.area) return x.area < y.area;
    return x.firstFace > y.firstFace;
  };
  std::vector<int32_t> heap;
  auto addChildren = [&](int32_t node) {
    uint32_t pos = tree.nodes[size_t(node)].firstFace;
    for (PcaItem c : tree.children(node)) {
      if (IsFaceItem(c) || tree.isLeaf(c)) {
        done.push_back({c, pos});
      } else {
        heap.push_back(c);
        std::push_heap(heap.begin(), heap.end(), before);
      }
      pos += tree.itemFaceCount(c);
    }
  };
  if (tree.componentCount > 1)
    addChildren(0);
  else if (!tree.isLeaf(0))
    heap.push_back(0);
  else
    done.push_back({0, 0});
  while (!heap.empty()) {
    if (!visit(int32_t(heap.front()))) break;
    std::pop_heap(heap.begin(), heap.end(), before);
    const int32_t id = heap.back();
    heap.pop_back();
    addChildren(id);
  }
  for (int32_t id : heap) done.push_back({id, tree.nodes[size_t(id)].firstFace});
  std::sort(done.begin(), done.end(), [](const Entry& a, const Entry& b) { return a.position < b.position; });
  cut.reserve(done.size());
  for (const Entry& e : done) cut.push_back(e.item);
  return cut;
}

int StartingClusters(const PcaTree& tree) {
  return tree.empty() ? 0 : (tree.componentCount > 1 ? tree.componentCount : 1);
}

}  // namespace

std::vector<PcaItem> CutByCount(const PcaTree& tree, int clusterCount) {
  int clusters = StartingClusters(tree);
  return WalkSplits(tree, [&](int32_t id) {
    if (clusters >= clusterCount) return false;
    clusters += tree.children(id).count - 1;
    return true;
  });
}

std::vector<PcaItem> CutByError(const PcaTree& tree, double maxErrorRms) {
  // Every cluster above the threshold is split: the order does not matter, but the walk's order
  // (largest first) means that once the largest is below, all are.
  return WalkSplits(tree,
                    [&](int32_t id) { return std::sqrt(double(tree.nodes[size_t(id)].eigenvalues[0])) > maxErrorRms; });
}

std::vector<int32_t> SplitSequence(const PcaTree& tree) {
  std::vector<int32_t> seq;
  WalkSplits(tree, [&](int32_t id) {
    seq.push_back(id);
    return true;
  });
  return seq;
}

void FaceClustersOfCut(const PcaTree& tree, const std::vector<PcaItem>& cut, std::vector<int>& faceCluster) {
  faceCluster.assign(size_t(tree.faceCount), -1);
  for (size_t i = 0; i < cut.size(); ++i) {
    const PcaItem item = cut[i];
    if (IsFaceItem(item)) {
      faceCluster[FaceOfItem(item)] = int(i);
      continue;
    }
    const PcaNode& node = tree.nodes[size_t(item)];
    for (uint32_t k = 0; k < node.faceCount; ++k) faceCluster[tree.faceOrder[node.firstFace + k]] = int(i);
  }
}

std::string VerifyPcaTree(const IndexedMesh& mesh, const FaceAdjacency& adj, const PcaTree& tree) {
  const uint32_t nf = uint32_t(mesh.faces.size());
  if (tree.empty()) return "the tree is empty";
  if (uint32_t(tree.faceCount) != nf || tree.faceOrder.size() != nf) return "the tree does not belong to this mesh";
  std::vector<int32_t> mark(nf, -1);
  for (uint32_t f : tree.faceOrder) {
    if (f >= nf || mark[f] >= 0) return "faceOrder is not a permutation of the faces";
    mark[f] = 0;
  }
  const PcaNode& root = tree.nodes[0];
  if (root.parent != -1 || root.firstFace != 0 || root.faceCount != nf || root.depth != 0) return "bad root";
  std::fill(mark.begin(), mark.end(), -1);
  std::vector<uint32_t> queue;
  for (size_t i = 0; i < tree.nodes.size(); ++i) {
    const PcaNode& node = tree.nodes[i];
    const std::string where = "node " + std::to_string(i) + ": ";
    if (i > 0 && (node.faceCount < 2 || node.parent < 0 || size_t(node.parent) >= i ||
                  node.depth != tree.nodes[size_t(node.parent)].depth + 1))
      return where + "bad parent, depth or face count";
    // Children tile the node's range, in order.
    uint32_t pos = node.firstFace;
    const PcaItemRange kids = tree.children(int32_t(i));
    for (PcaItem c : kids) {
      if (IsFaceItem(c)) {
        if (tree.faceOrder[pos] != FaceOfItem(c)) return where + "a face child is not at its place in faceOrder";
        ++pos;
      } else {
        const PcaNode& child = tree.nodes[size_t(c)];
        if (child.parent != int32_t(i) || child.firstFace != pos) return where + "a child is not at its place";
        pos += child.faceCount;
      }
    }
    if (kids.count > 0 && pos != node.firstFace + node.faceCount) return where + "children do not cover the node";
    if ((i == 0 && tree.componentCount > 1) != (i == 0 && !tree.components.empty()))
      return "the root's components do not match the component count";
    if (i == 0 && tree.componentCount > 1) continue;  // the root of a disconnected mesh
    // Edge-connected: a breadth-first search within the node reaches all its faces.
    for (uint32_t k = 0; k < node.faceCount; ++k) mark[tree.faceOrder[node.firstFace + k]] = int32_t(i);
    queue.assign(1, tree.faceOrder[node.firstFace]);
    mark[queue[0]] = -2;
    for (size_t h = 0; h < queue.size(); ++h) {
      const uint32_t f = queue[h];
      for (uint32_t j = adj.offsets[f]; j < adj.offsets[f + 1]; ++j) {
        const uint32_t g = adj.neighbours[j];
        if (mark[g] != int32_t(i)) continue;
        mark[g] = -2;
        queue.push_back(g);
      }
    }
    if (queue.size() != node.faceCount)
      return where + "not edge-connected (" + std::to_string(queue.size()) + " of " + std::to_string(node.faceCount) +
             " faces reached)";
  }
  return "";
}

// ---------------------------------------------------------------------------------------------
// Group hierarchy from nested cuts

Status PcaGroupHierarchy(const IndexedMesh& mesh, const PcaTree& tree, const std::vector<int>& clusterCounts,
                         GroupHierarchy& out) {
  out = GroupHierarchy();
  if (tree.empty() || size_t(tree.faceCount) != mesh.faces.size())
    return Status::Invalid("the PCA tree does not belong to this mesh");
  if (clusterCounts.empty()) return Status::Invalid("no cluster count given");
  for (size_t i = 0; i < clusterCounts.size(); ++i)
    if (clusterCounts[i] < 1 || (i > 0 && clusterCounts[i] >= clusterCounts[i - 1]))
      return Status::Invalid("cluster counts must be >= 1 and decreasing (finest level first)");
  std::vector<vcg::Point3d> normals;
  std::vector<double> areas;
  ComputeFaceNormalsAndAreas(mesh, normals, areas);
  GroupHierarchy h;
  h.faceCount = tree.faceCount;
  std::vector<vcg::Point3d> groupNormals;
  for (int count : clusterCounts) {
    GroupLevel level;
    level.thresholdDeg = 180;  // no cone threshold: PCA clusters are made by shape
    const std::vector<PcaItem> cut = CutByCount(tree, count);
    if (!h.levels.empty() && cut.size() >= h.levels.back().groups.size()) continue;  // no coarser cut exists
    FaceClustersOfCut(tree, cut, level.faceGroup);
    level.groups.resize(cut.size());
    for (size_t g = 0; g < cut.size(); ++g) {
      Group& grp = level.groups[g];
      const PcaItem item = cut[g];
      const uint32_t first = IsFaceItem(item) ? 0 : tree.nodes[size_t(item)].firstFace;
      const uint32_t n = tree.itemFaceCount(item);
      auto faceAt = [&](uint32_t k) { return IsFaceItem(item) ? FaceOfItem(item) : tree.faceOrder[first + k]; };
      groupNormals.clear();
      grp.box.SetNull();
      grp.area = 0;
      for (uint32_t k = 0; k < n; ++k) {
        const uint32_t f = faceAt(k);
        groupNormals.push_back(normals[f]);
        grp.area += areas[f];
        for (uint32_t v : mesh.faces[f]) grp.box.Add(mesh.positions[v]);
      }
      grp.cone = MinimalCone(groupNormals);
      grp.faceCount = int(n);
      const vcg::Point3d c = vcg::Point3d::Construct(grp.box.Center());
      double r2 = 0;
      for (uint32_t k = 0; k < n; ++k)
        for (uint32_t v : mesh.faces[faceAt(k)])
          r2 = std::max(r2, (vcg::Point3d::Construct(mesh.positions[v]) - c).SquaredNorm());
      grp.center = grp.box.Center();
      // Pad so that rounding the radius to float cannot leave a vertex out.
      grp.radius = float(std::sqrt(r2) * (1 + 1e-6) + 1e-6 * grp.box.Diag());
    }
    // Children: faces at level 1, the groups of the level below above it.
    std::vector<std::vector<int>> kids(cut.size());
    if (h.levels.empty()) {
      for (size_t f = 0; f < level.faceGroup.size(); ++f) kids[size_t(level.faceGroup[f])].push_back(int(f));
    } else {
      GroupLevel& below = h.levels.back();
      std::vector<int> firstFace(below.groups.size(), -1);
      for (size_t f = 0; f < below.faceGroup.size(); ++f)
        if (firstFace[size_t(below.faceGroup[f])] < 0) firstFace[size_t(below.faceGroup[f])] = int(f);
      for (size_t g = 0; g < below.groups.size(); ++g) {
        const int parent = level.faceGroup[size_t(firstFace[g])];
        below.groups[g].parent = parent;
        kids[size_t(parent)].push_back(int(g));
      }
    }
    for (size_t g = 0; g < cut.size(); ++g) {
      level.groups[g].firstChild = int(level.children.size());
      level.groups[g].childCount = int(kids[g].size());
      level.children.insert(level.children.end(), kids[g].begin(), kids[g].end());
    }
    h.levels.push_back(std::move(level));
  }
  out = std::move(h);
  return Status::Ok();
}

}  // namespace conelod
