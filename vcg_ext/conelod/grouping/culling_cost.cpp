// ConeLOD — culling cost of a group hierarchy (see culling_cost.h).
#include "conelod/grouping/culling_cost.h"

#include <algorithm>
#include <cmath>

#include <vcg/space/box3.h>

namespace conelod {

std::vector<vcg::Point3d> ViewDirections(int count) {
  std::vector<vcg::Point3d> dirs;
  dirs.reserve(size_t(std::max(0, count)));
  const double golden = NormalCone::kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / count;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * (i + 0.5);  // the half step keeps i = 0 off the plane y = 0
    dirs.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
  }
  return dirs;
}

namespace {

struct ViewCounts {
  long tests2 = 0, tests3 = 0, rejected = 0, frontAccepted = 0, groupTests = 0;
};

class Traversal {
 public:
  Traversal(const GroupHierarchy& h, bool perspective) : h_(h), perspective_(perspective) {}

  ViewCounts run(const vcg::Point3d& viewDir, const vcg::Point3d& eye) {
    viewDir_ = viewDir;
    eye_ = eye;
    ViewCounts c;
    const int top = h_.levelCount();
    const auto& groups = h_.level(top).groups;
    for (size_t g = 0; g < groups.size(); ++g) visit(top, int(g), true, c);
    return c;
  }

 private:
  void visit(int level, int g, bool counting3, ViewCounts& c) {
    const GroupLevel& lv = h_.level(level);
    const Group& grp = lv.groups[size_t(g)];
    ++c.tests2;
    ++c.groupTests;
    if (counting3) ++c.tests3;
    const Facing f = perspective_ ? ClassifyPerspective(grp.cone, vcg::Point3d::Construct(grp.center), grp.radius, eye_)
                                  : ClassifyOrtho(grp.cone, viewDir_);
    if (f == Facing::Back) {
      c.rejected += grp.faceCount;
      return;
    }
    if (f == Facing::Front && counting3) {
      c.frontAccepted += grp.faceCount;
      counting3 = false;
    }
    if (level == 1) {
      c.tests2 += grp.childCount;
      if (counting3) c.tests3 += grp.childCount;
      return;
    }
    for (int i = 0; i < grp.childCount; ++i) visit(level - 1, lv.children[size_t(grp.firstChild + i)], counting3, c);
  }

  const GroupHierarchy& h_;
  const bool perspective_;
  vcg::Point3d viewDir_, eye_;
};

void Accumulate(CostStats& s, double x, int i) {
  if (i == 0) {
    s.min = s.max = x;
  }
  s.min = std::min(s.min, x);
  s.max = std::max(s.max, x);
  s.mean += x;
}

}  // namespace

Status EvaluateCullingCost(const IndexedMesh& mesh, const GroupHierarchy& h, const CullingCostParams& p,
                           CullingCostResult& out, const Progress& progress) {
  out = CullingCostResult();
  if (h.levelCount() == 0 || size_t(h.faceCount) != mesh.faces.size())
    return Status::Invalid("the group hierarchy does not belong to this mesh");
  if (p.views < 1 || p.views > 10000000) return Status::Invalid("the number of views must be between 1 and 10^7");
  const bool perspective = p.cameraDistance != 0;
  if (perspective && !(p.cameraDistance > 1.0 && std::isfinite(p.cameraDistance)))
    return Status::Invalid("the camera distance must be > 1 (in bounding-sphere radii), or 0 for orthographic views");

  std::vector<vcg::Point3d> normals;
  std::vector<double> areas;
  ComputeFaceNormalsAndAreas(mesh, normals, areas);
  std::vector<vcg::Point3d> anchor(mesh.faces.size());  // a point of each face, for perspective
  const vcg::Box3d box = UsedVertexBox(mesh);
  for (size_t f = 0; f < mesh.faces.size(); ++f) anchor[f] = vcg::Point3d::Construct(mesh.positions[mesh.faces[f][0]]);
  const vcg::Point3d centre = box.Center();
  const double radius = 0.5 * box.Diag();

  const double n = double(mesh.faces.size());
  const auto dirs = ViewDirections(p.views);
  Traversal traversal(h, perspective);
  double ideal = 0, rejected = 0, front = 0, groupTests = 0;
  for (int i = 0; i < p.views; ++i) {
    const vcg::Point3d viewDir = -dirs[size_t(i)];  // the eye sits at +dirs[i], looking inwards
    const vcg::Point3d eye = centre + dirs[size_t(i)] * (p.cameraDistance * radius);
    const ViewCounts c = traversal.run(viewDir, eye);
    long nothing = 0;  // faces that draw nothing for this view
    if (perspective) {
      for (size_t f = 0; f < normals.size(); ++f) nothing += ((anchor[f] - eye) * normals[f] >= 0) ? 1 : 0;
    } else {
      for (size_t f = 0; f < normals.size(); ++f) nothing += (normals[f] * viewDir >= 0) ? 1 : 0;
    }
    Accumulate(out.twoState, double(c.tests2) / n, i);
    Accumulate(out.threeState, double(c.tests3) / n, i);
    ideal += double(nothing) / n;
    rejected += double(c.rejected) / n;
    front += double(c.frontAccepted) / n;
    groupTests += double(c.groupTests);
    if (progress && (i & 63) == 63 && !progress(100 * (i + 1) / p.views, "evaluating culling cost"))
      return Status::Cancelled();
  }
  out.views = p.views;
  out.perspective = perspective;
  out.cameraDistance = p.cameraDistance;
  out.twoState.mean /= p.views;
  out.threeState.mean /= p.views;
  out.idealFraction = ideal / p.views;
  out.rejectedFraction = rejected / p.views;
  out.frontAcceptedFraction = front / p.views;
  out.meanGroupTests = groupTests / p.views;
  return Status::Ok();
}

}  // namespace conelod
