// ConeLOD — normal cones (see normal_cone.h for the papers and the method).
#include "conelod/grouping/normal_cone.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace conelod {

// The out-of-line definition C++14 needs when kPi is bound to a reference (std::min, std::max).
constexpr double NormalCone::kPi;

namespace {

constexpr double kHalfPi = kPi / 2;
// Inside test slack on cosines: normals come from float data, caps from double arithmetic.
constexpr double kCosEps = 1e-10;

double AngleBetween(const vcg::Point3d& a, const vcg::Point3d& b) {
  // atan2 is accurate for small and for near-pi angles, unlike acos(dot).
  return std::atan2((a ^ b).Norm(), a * b);
}

// A cap stored by its cosine while Welzl runs (no trigonometry in the inner loops).
struct Cap {
  vcg::Point3d axis{0, 0, 1};
  double cosHalf = 1;
  bool uncullable = false;
  bool contains(const vcg::Point3d& p) const { return uncullable || p * axis >= cosHalf - kCosEps; }
};

Cap Cap1(const vcg::Point3d& a) { return Cap{a, 1.0, false}; }

// The normals as three columns, for Welzl's scans: two normals per SSE2 operation, with the
// same products and sums as Cap::contains (so the same answers, bit for bit), and most of
// MinimalCone's time is spent in these scans.
class Columns {
 public:
  void assign(const std::vector<vcg::Point3d>& pts) {
    const size_t n = pts.size();
    x_.resize(n);
    y_.resize(n);
    z_.resize(n);
    for (size_t i = 0; i < n; ++i) {
      x_[i] = pts[i][0];
      y_[i] = pts[i][1];
      z_[i] = pts[i][2];
    }
  }
  // The first index in [begin, end) whose normal the (cullable) cap does not contain, or end.
  size_t firstOutside(const Cap& cap, size_t begin, size_t end) const {
    const double ax = cap.axis[0], ay = cap.axis[1], az = cap.axis[2];
    const double minCos = cap.cosHalf - kCosEps;
    size_t i = begin;
#ifdef __SSE2__
    const __m128d vax = _mm_set1_pd(ax), vay = _mm_set1_pd(ay), vaz = _mm_set1_pd(az);
    const __m128d vmin = _mm_set1_pd(minCos);
    for (; i + 2 <= end; i += 2) {
      __m128d d = _mm_mul_pd(_mm_loadu_pd(&x_[i]), vax);
      d = _mm_add_pd(d, _mm_mul_pd(_mm_loadu_pd(&y_[i]), vay));
      d = _mm_add_pd(d, _mm_mul_pd(_mm_loadu_pd(&z_[i]), vaz));
      const int outside = _mm_movemask_pd(_mm_cmpnge_pd(d, vmin));  // not >=: NaN is outside too
      if (outside) return i + ((outside & 1) ? 0 : 1);
    }
#endif
    for (; i < end; ++i)
      if (!(x_[i] * ax + y_[i] * ay + z_[i] * az >= minCos)) return i;
    return end;
  }

 private:
  std::vector<double> x_, y_, z_;
};

Cap Cap2(const vcg::Point3d& a, const vcg::Point3d& b) {
  vcg::Point3d m = a + b;
  double len = m.Norm();
  if (len < 1e-12) return Cap{a, -1, true};  // antipodal pair: no open hemisphere holds both
  m /= len;
  return Cap{m, std::min(m * a, m * b), false};
}

// The smallest cap with a, b, c on its boundary (the circle through them). Falls back to a
// two-point cap when two of the points (nearly) coincide.
Cap Cap3(const vcg::Point3d& a, const vcg::Point3d& b, const vcg::Point3d& c) {
  vcg::Point3d n = (b - a) ^ (c - a);
  double len = n.Norm();
  if (len < 1e-14) {
    // Degenerate: the largest two-point cap holds the third point.
    Cap best = Cap2(a, b);
    for (const Cap& cand : {Cap2(a, c), Cap2(b, c)})
      if (cand.uncullable || (!best.uncullable && cand.cosHalf < best.cosHalf)) best = cand;
    return best;
  }
  n /= len;
  double d = n * a;  // signed distance of the circle's plane from the origin
  if (d < 0) {
    n = -n;
    d = -d;
  }
  if (d < 1e-12) return Cap{n, 0, true};  // a great circle: a full hemisphere, not cullable
  return Cap{n, std::min({n * a, n * b, n * c}), false};
}

uint64_t NextRandom(uint64_t& s) {  // xorshift64*
  s ^= s >> 12;
  s ^= s << 25;
  s ^= s >> 27;
  return s * 0x2545F4914F6CDD1Dull;
}

}  // namespace

bool NormalCone::contains(const vcg::Point3d& n, double tolRad) const {
  if (empty()) return false;
  if (!cullable()) return true;
  return AngleBetween(axis, n) <= halfAngle + tolRad;
}

NormalCone UnionCone(const NormalCone& a, const NormalCone& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  if (!a.cullable() || !b.cullable()) return NormalCone::Uncullable();
  const double theta = AngleBetween(a.axis, b.axis);
  if (theta + b.halfAngle <= a.halfAngle) return a;
  if (theta + a.halfAngle <= b.halfAngle) return b;
  const double half = 0.5 * (theta + a.halfAngle + b.halfAngle);
  if (half >= kHalfPi) return NormalCone::Uncullable();
  // Rotate a's axis towards b's by (half - a.halfAngle): slerp on the great circle.
  const double t = half - a.halfAngle;
  const double s = std::sin(theta);
  NormalCone r;
  r.axis = (a.axis * std::sin(theta - t) + b.axis * std::sin(t)) / s;
  r.axis.Normalize();
  r.halfAngle = half;
  return r;
}

NormalCone FastUnionCone(const NormalCone& a, const NormalCone& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  if (!a.cullable() || !b.cullable()) return NormalCone::Uncullable();
  const double d = std::max(-1.0, std::min(1.0, a.axis * b.axis));
  const double theta = FastAcos(d) + 1e-7;
  if (a.halfAngle == 0 && b.halfAngle == 0 && d > -0.5) {  // two normals: the bisector
    NormalCone r;
    r.axis = a.axis + b.axis;
    r.axis.Normalize();
    r.halfAngle = 0.5 * theta + 1e-7;
    return r;
  }
  if (theta + b.halfAngle <= a.halfAngle) return a;
  if (theta + a.halfAngle <= b.halfAngle) return b;
  const double half = 0.5 * (theta + a.halfAngle + b.halfAngle);
  if (half >= kHalfPi) return NormalCone::Uncullable();
  const vcg::Point3d w = b.axis - a.axis * d;  // towards b, orthogonal to a
  const double len = w.Norm();
  NormalCone r;
  r.halfAngle = half;
  if (len < 1e-12) {
    r.axis = a.axis;
    r.halfAngle = std::max(a.halfAngle, b.halfAngle) + theta;
    return r;
  }
  const double t = half - a.halfAngle;  // rotate a's axis towards b by t
  r.axis = a.axis * std::cos(t) + w * (std::sin(t) / len);
  r.axis.Normalize();
  return r;
}

NormalCone MinimalCone(std::vector<vcg::Point3d>& pts, uint64_t seed) {
  ConeSupport unused;
  return MinimalCone(pts, unused, seed);
}

NormalCone MinimalCone(std::vector<vcg::Point3d>& pts, ConeSupport& support, uint64_t seed) {
  support.count = 0;
  // Drop zero vectors (normals of zero-area faces) in place.
  pts.erase(std::remove_if(pts.begin(), pts.end(), [](const vcg::Point3d& p) { return p.SquaredNorm() < 0.5; }),
            pts.end());
  const size_t n = pts.size();
  if (n == 0) return NormalCone::Empty();
  // Random order gives Welzl's expected linear time.
  uint64_t s = seed ? seed : 1;
  for (size_t i = n - 1; i > 0; --i) std::swap(pts[i], pts[NextRandom(s) % (i + 1)]);

  // Welzl's loops below: each scans a range for the first normal outside the current cap.
  thread_local Columns cols;
  cols.assign(pts);
  Cap cap = Cap1(pts[0]);
  auto supportedBy = [&](std::initializer_list<size_t> at) {
    support.count = 0;
    for (size_t a : at) support.normal[support.count++] = pts[a];
  };
  supportedBy({0});
  for (size_t i = 1; i < n && !cap.uncullable; ++i) {
    i = cols.firstOutside(cap, i, n);
    if (i == n) break;
    cap = Cap1(pts[i]);  // pts[i] is on the boundary of the minimal cap of pts[0..i]
    supportedBy({i});
    for (size_t j = 0; j < i && !cap.uncullable; ++j) {
      j = cols.firstOutside(cap, j, i);
      if (j == i) break;
      cap = Cap2(pts[i], pts[j]);
      supportedBy({i, j});
      for (size_t k = 0; k < j && !cap.uncullable; ++k) {
        k = cols.firstOutside(cap, k, j);
        if (k == j) break;
        cap = Cap3(pts[i], pts[j], pts[k]);
        supportedBy({i, j, k});
        // With three boundary points the cap is fixed: a point of pts[0..k) outside it means a
        // four-point support, i.e. the enclosing ball is centred at the origin (no hemisphere).
        if (!cap.uncullable && cols.firstOutside(cap, 0, k) < k) cap.uncullable = true;
      }
    }
  }
  if (cap.uncullable || cap.cosHalf <= 1e-9) {
    support.count = 0;
    return NormalCone::Uncullable();
  }
  NormalCone out;
  out.axis = cap.axis;
  out.halfAngle = std::acos(std::min(1.0, cap.cosHalf));
  return out;
}

NormalCone MinimalConeBruteForce(const std::vector<vcg::Point3d>& in) {
  std::vector<vcg::Point3d> pts;
  for (const auto& p : in)
    if (p.SquaredNorm() >= 0.5) pts.push_back(p);
  if (pts.empty()) return NormalCone::Empty();
  const size_t n = pts.size();
  Cap best;
  bool found = false;
  auto consider = [&](const Cap& c) {
    if (c.uncullable) return;
    for (const auto& p : pts)
      if (!c.contains(p)) return;
    if (!found || c.cosHalf > best.cosHalf) {
      best = c;
      found = true;
    }
  };
  for (size_t i = 0; i < n; ++i) {
    consider(Cap1(pts[i]));
    for (size_t j = i + 1; j < n; ++j) {
      consider(Cap2(pts[i], pts[j]));
      for (size_t k = j + 1; k < n; ++k) consider(Cap3(pts[i], pts[j], pts[k]));
    }
  }
  if (!found || best.cosHalf <= 1e-9) return NormalCone::Uncullable();
  NormalCone out;
  out.axis = best.axis;
  out.halfAngle = std::acos(std::min(1.0, best.cosHalf));
  return out;
}

Facing ClassifyOrtho(const NormalCone& cone, const vcg::Point3d& viewDir) {
  if (cone.empty()) return Facing::Back;
  if (!cone.cullable()) return Facing::Partial;
  const double a = AngleBetween(cone.axis, -viewDir);
  if (a - cone.halfAngle > kHalfPi) return Facing::Back;
  if (a + cone.halfAngle < kHalfPi) return Facing::Front;
  return Facing::Partial;
}

Facing ClassifyPerspective(const NormalCone& cone, const vcg::Point3d& center, double radius, const vcg::Point3d& eye) {
  if (cone.empty()) return Facing::Back;
  if (!cone.cullable()) return Facing::Partial;
  const vcg::Point3d toEye = eye - center;
  const double d = toEye.Norm();
  if (d <= radius) return Facing::Partial;
  // Every point P of the sphere sees the eye within asin(r/d) of the centre's direction.
  const double widen = std::asin(radius / d);
  const double a = AngleBetween(cone.axis, toEye);  // angle(axis, -(view direction))
  if (a - cone.halfAngle - widen > kHalfPi) return Facing::Back;
  if (a + cone.halfAngle + widen < kHalfPi) return Facing::Front;
  return Facing::Partial;
}

}  // namespace conelod
