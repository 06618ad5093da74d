// ConeLOD — normal cones: the minimal cone of a set of unit normals, cone union, and the
// back-face visibility tests for whole groups of faces.
//
// Kamiya, Suzuki, Kawachi, "LODs for efficient displaying triangle meshes", §3 eq. (1): a group
// with cone axis n and half-angle c is invisible for an orthographic view when a - c > pi/2,
// a = angle(n, -view). The paper finds the cone from the mean normal; we compute the true
// minimal cone (smallest enclosing spherical cap) with Welzl's randomized algorithm, through
// the identity: for unit vectors p_i, the centre m of their smallest enclosing *ball* points
// along the minimal cap's axis and |m| = cos(c) (min_m max_i |p_i - m|^2 = 1 + |m|^2 -
// 2|m| min_i <m/|m|, p_i>). When the normals fit in no open hemisphere the ball is centred at
// the origin: such a cone is "uncullable" (half-angle pi: no view ever culls it).
//
// All angles here are in radians; "half-angle" is the paper's c (largest angle between the
// axis and a member normal).
#pragma once

#include <cstddef>
#include <cmath>
#include <cstdint>
#include <vector>

#include <vcg/space/point3.h>

#include "conelod/common.h"

namespace conelod {

struct NormalCone {
  vcg::Point3d axis{0, 0, 1};  // unit
  double halfAngle = -1;       // radians; < 0: empty (no normal), >= pi/2: cannot be culled

  static NormalCone Empty() { return NormalCone(); }
  static NormalCone Uncullable() {
    NormalCone c;
    c.halfAngle = kPi;
    return c;
  }
  static NormalCone Of(const vcg::Point3d& unitNormal) {
    NormalCone c;
    c.axis = unitNormal;
    c.halfAngle = 0;
    return c;
  }

  bool empty() const { return halfAngle < 0; }
  bool cullable() const { return halfAngle < kPi / 2; }  // empty cones are (trivially) cullable
  bool contains(const vcg::Point3d& unitNormal, double tolRad = 1e-9) const;

  static constexpr double kPi = conelod::kPi;
};

// acos(x) for x in [-1,1] to within 2e-8 rad (Abramowitz & Stegun 4.4.46), several times faster
// than std::acos: the grouping's candidate evaluation calls it millions of times.
inline double FastAcos(double x) {
  const bool neg = x < 0;
  const double a = neg ? -x : x;
  const double t = a >= 1 ? 0.0 : std::sqrt(1.0 - a);
  const double p =
      ((((((-0.0012624911 * a + 0.0066700901) * a - 0.0170881256) * a + 0.0308918810) * a - 0.0501743046) * a +
        0.0889789874) *
           a -
       0.2145988016) *
          a +
      1.5707963050;
  const double r = t * p;
  return neg ? NormalCone::kPi - r : r;
}

// The half-angle of UnionCone(a, b) (both non-empty and cullable), without building the axis:
// pi when the union cannot be culled. Uses FastAcos.
inline double UnionHalfAngle(const NormalCone& a, const NormalCone& b) {
  double d = a.axis * b.axis;
  d = d > 1 ? 1 : (d < -1 ? -1 : d);
  const double theta = FastAcos(d);
  if (theta + b.halfAngle <= a.halfAngle) return a.halfAngle;
  if (theta + a.halfAngle <= b.halfAngle) return b.halfAngle;
  const double half = 0.5 * (theta + a.halfAngle + b.halfAngle);
  return half >= NormalCone::kPi / 2 ? NormalCone::kPi : half;
}

// The smallest cone containing both cones (exact for cones; an upper bound of the minimal cone
// of the union of the underlying normals).
NormalCone UnionCone(const NormalCone& a, const NormalCone& b);

// UnionCone with one sine/cosine pair instead of atan2 and three sines, for the hot loops (the
// grouping's merges, the PCA tree's bottom-up pass): the angle between the axes comes from
// FastAcos and is padded by 1e-7 rad for its error, so the cone still holds both cones, at most
// ~2e-7 rad wider than UnionCone's. Two normals (half-angle 0) give their bisector.
NormalCone FastUnionCone(const NormalCone& a, const NormalCone& b);

// The exact minimal cone of the given unit normals (zero vectors are ignored). Expected O(n);
// `normals` is shuffled in place (deterministically, from `seed`).
NormalCone MinimalCone(std::vector<vcg::Point3d>& normals, uint64_t seed = 0x9E3779B97F4A7C15ull);

// At most three of the normals on whose boundary circle a minimal cone lies: the minimal cone
// of these alone is the cone (empty: count 0; an uncullable cone has no support).
struct ConeSupport {
  vcg::Point3d normal[3];
  int count = 0;
};

// MinimalCone, also giving the support of the cone it returns.
NormalCone MinimalCone(std::vector<vcg::Point3d>& normals, ConeSupport& support, uint64_t seed = 0x9E3779B97F4A7C15ull);

// Reference implementation for tests: tries every cap defined by 1, 2 or 3 of the normals.
// O(n^4): only for small sets.
NormalCone MinimalConeBruteForce(const std::vector<vcg::Point3d>& normals);

enum class Facing : uint8_t { Back, Partial, Front };  // all back-facing / mixed / all front-facing

// Orthographic view: viewDir points from the eye into the scene (unit). Back iff a - c > pi/2,
// Front iff a + c < pi/2 (a = angle(axis, -viewDir)). An empty cone (zero-area faces only) is Back.
Facing ClassifyOrtho(const NormalCone& cone, const vcg::Point3d& viewDir);

// Perspective view from `eye`, for a group inside the sphere (center, radius): conservative, the
// angle subtended by the sphere widens the cone. Partial whenever the eye is inside the sphere.
Facing ClassifyPerspective(const NormalCone& cone, const vcg::Point3d& center, double radius, const vcg::Point3d& eye);

}  // namespace conelod
