// Tests of normal_cone.h: the minimal cone against brute force, degenerate sets, cone union and
// the visibility tests.
#include "conelod/grouping/normal_cone.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace conelod {
namespace {

constexpr double kPi = NormalCone::kPi;
constexpr double kDeg = kPi / 180;

vcg::Point3d Dir(double thetaDeg, double phiDeg) {  // polar angle from +z, azimuth
  const double t = thetaDeg * kDeg, p = phiDeg * kDeg;
  return vcg::Point3d(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
}

double Angle(const vcg::Point3d& a, const vcg::Point3d& b) { return std::atan2((a ^ b).Norm(), a * b); }

// A unit vector orthogonal to the unit vector a.
vcg::Point3d Perpendicular(const vcg::Point3d& a) {
  vcg::Point3d p = (std::abs(a[0]) < 0.9 ? vcg::Point3d(1, 0, 0) : vcg::Point3d(0, 1, 0)) ^ a;
  p.Normalize();
  return p;
}

// 36 normals on the boundary of cone c, 10 degrees apart around its axis.
std::vector<vcg::Point3d> BoundaryNormals(const NormalCone& c) {
  const vcg::Point3d p = Perpendicular(c.axis), q = c.axis ^ p;
  std::vector<vcg::Point3d> ns;
  for (int k = 0; k < 36; ++k) {
    const double phi = k * 10 * kDeg;
    ns.push_back(c.axis * std::cos(c.halfAngle) + (p * std::cos(phi) + q * std::sin(phi)) * std::sin(c.halfAngle));
  }
  return ns;
}

// Every normal inside the cone (with a tolerance).
void ExpectContainsAll(const NormalCone& c, const std::vector<vcg::Point3d>& ns) {
  for (const auto& n : ns) EXPECT_LE(Angle(c.axis, n), c.halfAngle + 1e-9);
}

TEST(MinimalCone, SingleNormalHasZeroAngle) {
  std::vector<vcg::Point3d> ns = {Dir(30, 40)};
  const NormalCone c = MinimalCone(ns);
  EXPECT_NEAR(c.halfAngle, 0, 1e-12);
  EXPECT_NEAR(Angle(c.axis, Dir(30, 40)), 0, 1e-12);
}

TEST(MinimalCone, TwoNormalsGiveTheirBisector) {
  std::vector<vcg::Point3d> ns = {Dir(0, 0), Dir(90, 0)};
  const NormalCone c = MinimalCone(ns);
  EXPECT_NEAR(c.halfAngle, 45 * kDeg, 1e-12);
  EXPECT_NEAR(Angle(c.axis, Dir(45, 0)), 0, 1e-12);
}

TEST(MinimalCone, AntipodalPairCannotBeCulled) {
  std::vector<vcg::Point3d> ns = {Dir(0, 0), Dir(180, 0)};
  EXPECT_FALSE(MinimalCone(ns).cullable());
}

TEST(MinimalCone, GreatCircleCannotBeCulled) {
  // Three normals 120 degrees apart on the equator: the only enclosing caps are hemispheres or
  // larger, so no view culls them all.
  std::vector<vcg::Point3d> ns = {Dir(90, 0), Dir(90, 120), Dir(90, 240)};
  EXPECT_FALSE(MinimalCone(ns).cullable());
}

TEST(MinimalCone, ZeroNormalsAreIgnoredAndAllZeroIsEmpty) {
  std::vector<vcg::Point3d> zeros = {vcg::Point3d(0, 0, 0), vcg::Point3d(0, 0, 0)};
  EXPECT_TRUE(MinimalCone(zeros).empty());
  std::vector<vcg::Point3d> mixed = {vcg::Point3d(0, 0, 0), Dir(10, 0), Dir(10, 180)};
  EXPECT_NEAR(MinimalCone(mixed).halfAngle, 10 * kDeg, 1e-12);
}

TEST(MinimalCone, ManyDuplicatesOfOneNormal) {
  std::vector<vcg::Point3d> ns(1000, Dir(70, 20));
  EXPECT_NEAR(MinimalCone(ns).halfAngle, 0, 1e-9);
}

TEST(MinimalCone, CircleOfNormalsHasItsRadius) {
  // 360 normals on a circle of angular radius 25 degrees around an axis, plus inner ones.
  std::vector<vcg::Point3d> ns;
  for (int i = 0; i < 360; ++i) ns.push_back(Dir(25, i));
  for (int i = 0; i < 100; ++i) ns.push_back(Dir(i % 25, 7 * i));
  const NormalCone c = MinimalCone(ns);
  EXPECT_NEAR(c.halfAngle, 25 * kDeg, 1e-9);
  EXPECT_NEAR(Angle(c.axis, Dir(0, 0)), 0, 1e-7);
}

// Random sets inside caps of growing size, and over the whole sphere: Welzl must agree with the
// O(n^4) reference on the angle, and contain every normal.
TEST(MinimalCone, MatchesBruteForceOnRandomSets) {
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> uni(0, 1);
  for (int trial = 0; trial < 300; ++trial) {
    const double capDeg = 5 + (trial % 10) * 19;  // 5 .. 176 degrees: some sets fit no hemisphere
    const int n = 1 + trial % 25;
    const vcg::Point3d axis = Dir(uni(rng) * 180, uni(rng) * 360);
    vcg::Point3d u = (std::abs(axis[0]) < 0.9 ? vcg::Point3d(1, 0, 0) : vcg::Point3d(0, 1, 0)) ^ axis;
    u.Normalize();
    const vcg::Point3d v = axis ^ u;
    std::vector<vcg::Point3d> ns;
    for (int i = 0; i < n; ++i) {
      const double t = uni(rng) * capDeg * kDeg, p = uni(rng) * 2 * kPi;
      ns.push_back(axis * std::cos(t) + (u * std::cos(p) + v * std::sin(p)) * std::sin(t));
    }
    const NormalCone brute = MinimalConeBruteForce(ns);
    std::vector<vcg::Point3d> copy = ns;
    const NormalCone fast = MinimalCone(copy, 1 + trial);
    ASSERT_EQ(brute.cullable(), fast.cullable()) << "trial " << trial;
    if (!fast.cullable()) continue;
    EXPECT_NEAR(fast.halfAngle, brute.halfAngle, 1e-7) << "trial " << trial;
    ExpectContainsAll(fast, ns);
  }
}

// The support MinimalCone reports: one to three of the input normals whose own minimal cone is
// the cone (cone_grouping.cpp starts exact recomputations from it); none for an uncullable set.
TEST(MinimalCone, SupportDefinesTheCone) {
  std::mt19937 rng(777);
  std::uniform_real_distribution<double> uni(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const double capDeg = 2 + (trial % 8) * 12;  // 2 .. 86 degrees
    const vcg::Point3d axis = Dir(uni(rng) * 180, uni(rng) * 360);
    std::vector<vcg::Point3d> ns;
    for (int i = 0; i < 1 + trial % 40; ++i) {
      vcg::Point3d n = axis + Dir(uni(rng) * 180, uni(rng) * 360) * std::sin(capDeg * kDeg);
      ns.push_back(n.Normalize());
    }
    std::vector<vcg::Point3d> copy = ns;
    ConeSupport support;
    const NormalCone cone = MinimalCone(copy, support, 1 + trial);
    if (!cone.cullable()) {
      EXPECT_EQ(support.count, 0);
      continue;
    }
    ASSERT_GE(support.count, 1);
    ASSERT_LE(support.count, 3);
    std::vector<vcg::Point3d> onlySupport(support.normal, support.normal + support.count);
    for (const auto& s : onlySupport) {  // each is one of the input normals, on the boundary
      EXPECT_TRUE(std::find(ns.begin(), ns.end(), s) != ns.end());
      EXPECT_NEAR(Angle(cone.axis, s), cone.halfAngle, 1e-7);
    }
    const NormalCone again = MinimalConeBruteForce(onlySupport);
    EXPECT_NEAR(again.halfAngle, cone.halfAngle, 1e-7) << "trial " << trial;
    EXPECT_LT(Angle(again.axis, cone.axis), 1e-6) << "trial " << trial;
  }
  std::vector<vcg::Point3d> antipodal = {vcg::Point3d(0, 0, 1), vcg::Point3d(0, 0, -1)};
  ConeSupport support;
  EXPECT_FALSE(MinimalCone(antipodal, support).cullable());
  EXPECT_EQ(support.count, 0);
}

TEST(MinimalCone, IsNeverLargerThanTheMeanNormalCone) {
  // The paper's cone (mean normal as axis) is an upper bound of the minimal one.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uni(0, 1);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<vcg::Point3d> ns;
    for (int i = 0; i < 200; ++i) ns.push_back(Dir(uni(rng) * uni(rng) * 60, uni(rng) * 360));
    vcg::Point3d mean(0, 0, 0);
    for (const auto& n : ns) mean += n;
    mean.Normalize();
    double meanCone = 0;
    for (const auto& n : ns) meanCone = std::max(meanCone, Angle(mean, n));
    std::vector<vcg::Point3d> copy = ns;
    EXPECT_LE(MinimalCone(copy).halfAngle, meanCone + 1e-12);
  }
}

TEST(UnionCone, ContainsBothCones) {
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> uni(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    NormalCone a, b;
    a.axis = Dir(uni(rng) * 180, uni(rng) * 360);
    b.axis = Dir(uni(rng) * 180, uni(rng) * 360);
    a.halfAngle = uni(rng) * 40 * kDeg;
    b.halfAngle = uni(rng) * 40 * kDeg;
    const NormalCone u = UnionCone(a, b);
    if (!u.cullable()) {
      EXPECT_GE(0.5 * (Angle(a.axis, b.axis) + a.halfAngle + b.halfAngle), kPi / 2 - 1e-12);
      continue;
    }
    EXPECT_NEAR(u.halfAngle, UnionHalfAngle(a, b), 1e-7);
    // Sample both cones' boundaries.
    for (const NormalCone* c : {&a, &b})
      for (const vcg::Point3d& n : BoundaryNormals(*c)) EXPECT_TRUE(u.contains(n, 1e-9)) << "trial " << trial;
  }
}

// UnionCone and FastUnionCone alike: a nested cone gives the outer one back unchanged, an empty one
// the other, an uncullable one an uncullable union.
TEST(UnionCone, BothUnionsKeepNestedEmptyAndUncullableCones) {
  NormalCone big, small;
  big.axis = Dir(0, 0);
  big.halfAngle = 30 * kDeg;
  small.axis = Dir(10, 0);
  small.halfAngle = 5 * kDeg;
  for (NormalCone (*unite)(const NormalCone&, const NormalCone&) : {&UnionCone, &FastUnionCone}) {
    const char* name = unite == &UnionCone ? "UnionCone" : "FastUnionCone";
    EXPECT_EQ(unite(big, small).halfAngle, big.halfAngle) << name;
    EXPECT_EQ(unite(small, big).halfAngle, big.halfAngle) << name;
    EXPECT_EQ(unite(small, big).axis, big.axis) << name;
    EXPECT_EQ(unite(NormalCone::Empty(), small).halfAngle, small.halfAngle) << name;
    EXPECT_FALSE(unite(NormalCone::Uncullable(), small).cullable()) << name;
  }
}

// The cheaper bound must hold both cones to the rounding of the boundary samples (1e-12 rad, far
// below its padding; the threshold test relies on it), for wide and tiny angles alike, and stay
// within a few 1e-7 rad of UnionCone.
TEST(FastUnionCone, ContainsBothConesAndStaysCloseToUnionCone) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uni(0, 1);
  int checked = 0;  // cullable pairs, every one checked below
  for (int trial = 0; trial < 3000; ++trial) {
    NormalCone a, b;
    a.axis = Dir(uni(rng) * 180, uni(rng) * 360);
    // Every third pair is close (down to 1e-9 rad apart), every fifth cone a single normal.
    const double apart = trial % 3 == 0 ? std::pow(10.0, -9 + 8 * uni(rng)) : uni(rng) * kPi;
    b.axis = a.axis * std::cos(apart) + Perpendicular(a.axis) * std::sin(apart);
    b.axis.Normalize();
    a.halfAngle = trial % 5 == 0 ? 0 : uni(rng) * 40 * kDeg * (trial % 3 == 0 ? 1e-6 : 1);
    b.halfAngle = trial % 5 == 1 ? 0 : uni(rng) * 40 * kDeg;
    if (trial % 7 == 0) a.halfAngle = b.halfAngle = 0;
    const NormalCone fast = FastUnionCone(a, b), exact = UnionCone(a, b);
    if (!fast.cullable()) {
      EXPECT_GE(exact.halfAngle, kPi / 2 - 1e-6) << "trial " << trial;
      continue;
    }
    ASSERT_TRUE(exact.cullable()) << "trial " << trial;
    EXPECT_GE(fast.halfAngle, exact.halfAngle - 1e-12) << "trial " << trial;
    EXPECT_LE(fast.halfAngle, exact.halfAngle + 3e-7) << "trial " << trial;
    ++checked;
    for (const NormalCone* c : {&a, &b})
      for (const vcg::Point3d& n : BoundaryNormals(*c))
        ASSERT_TRUE(fast.contains(n, 1e-12))
            << "trial " << trial << " angle " << Angle(fast.axis, n) << " > " << fast.halfAngle;
  }
  EXPECT_GT(checked, 2000);
}

TEST(FastAcos, AccurateOverTheWholeRange) {
  for (int i = -100000; i <= 100000; ++i) {
    const double x = i / 100000.0;
    ASSERT_NEAR(FastAcos(x), std::acos(x), 3e-8) << x;
  }
}

TEST(ClassifyOrtho, PaperEquationOne) {
  NormalCone c;
  c.axis = Dir(0, 0);  // normals around +z
  c.halfAngle = 20 * kDeg;
  // Eye on +z looking down (-z): the group faces the eye.
  EXPECT_EQ(ClassifyOrtho(c, vcg::Point3d(0, 0, -1)), Facing::Front);
  // Eye on -z looking up: a = 180 deg, a - c = 160 > 90: invisible.
  EXPECT_EQ(ClassifyOrtho(c, vcg::Point3d(0, 0, 1)), Facing::Back);
  // Grazing view from the side: a = 90, partial.
  EXPECT_EQ(ClassifyOrtho(c, vcg::Point3d(1, 0, 0)), Facing::Partial);
  // a = 111 deg: a - c = 91 > 90 -> Back; a = 109: 89 -> Partial.
  EXPECT_EQ(ClassifyOrtho(c, -Dir(111, 0)), Facing::Back);
  EXPECT_EQ(ClassifyOrtho(c, -Dir(109, 0)), Facing::Partial);
  // a = 69: a + c = 89 < 90 -> Front; a = 71 -> Partial.
  EXPECT_EQ(ClassifyOrtho(c, -Dir(69, 0)), Facing::Front);
  EXPECT_EQ(ClassifyOrtho(c, -Dir(71, 0)), Facing::Partial);
  EXPECT_EQ(ClassifyOrtho(NormalCone::Uncullable(), vcg::Point3d(0, 0, 1)), Facing::Partial);
  EXPECT_EQ(ClassifyOrtho(NormalCone::Empty(), vcg::Point3d(0, 0, 1)), Facing::Back);
}

TEST(ClassifyPerspective, IsConservativeForEveryPointOfTheSphere) {
  // A Back verdict must hold for every face normal in the cone at every point of the sphere;
  // likewise Front. Checked by sampling points and normals.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uni(0, 1);
  int backs = 0, fronts = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    NormalCone c;
    c.axis = Dir(uni(rng) * 180, uni(rng) * 360);
    c.halfAngle = uni(rng) * 30 * kDeg;
    const vcg::Point3d centre(uni(rng), uni(rng), uni(rng));
    const double r = 0.2 * uni(rng);
    const vcg::Point3d eye = centre + Dir(uni(rng) * 180, uni(rng) * 360) * (0.5 + 3 * uni(rng));
    const Facing f = ClassifyPerspective(c, centre, r, eye);
    if (f == Facing::Partial) continue;
    (f == Facing::Back ? backs : fronts)++;
    for (int s = 0; s < 50; ++s) {
      const vcg::Point3d p = centre + Dir(uni(rng) * 180, uni(rng) * 360) * (r * uni(rng));
      vcg::Point3d u = (std::abs(c.axis[0]) < 0.9 ? vcg::Point3d(1, 0, 0) : vcg::Point3d(0, 1, 0)) ^ c.axis;
      u.Normalize();
      const vcg::Point3d v = c.axis ^ u;
      const double t = uni(rng) * c.halfAngle, phi = uni(rng) * 2 * kPi;
      const vcg::Point3d n = c.axis * std::cos(t) + (u * std::cos(phi) + v * std::sin(phi)) * std::sin(t);
      const double side = (p - eye) * n;  // > 0: back-facing
      if (f == Facing::Back)
        EXPECT_GT(side, 0);
      else
        EXPECT_LT(side, 0);
    }
  }
  EXPECT_GT(backs, 100);
  EXPECT_GT(fronts, 100);
}

}  // namespace
}  // namespace conelod
