// ConeLOD — the face budget from screen pixels (see pixel_budget.h).
#include "conelod/budget/pixel_budget.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <vcg/space/box3.h>

#include "conelod/mesh/mesh_check.h"

namespace conelod {

using P3 = vcg::Point3d;

namespace {
constexpr long long kMaxPixels = 1LL << 28;  // 16384 x 16384
}  // namespace

const std::array<P3, 6>& AxisDirections() {
  static const std::array<P3, 6> dirs = {P3(1, 0, 0),  P3(-1, 0, 0), P3(0, 1, 0),
                                         P3(0, -1, 0), P3(0, 0, 1),  P3(0, 0, -1)};
  return dirs;
}

Status ValidateParams(const PixelBudgetParams& p) {
  if (p.width < 1 || p.height < 1 || (long long)p.width * p.height > kMaxPixels)
    return Status::Invalid("Width and Height must be >= 1 and at most 16384 x 16384 pixels in all (got " +
                           std::to_string(p.width) + " x " + std::to_string(p.height) + ")");
  if (!(p.pixelFactor > 0) || !std::isfinite(p.pixelFactor))
    return Status::Invalid("PixelFactor must be > 0 (the paper's finding: 50)");
  if (!(p.fill > 0) || !std::isfinite(p.fill)) return Status::Invalid("the fill fraction must be > 0");
  if (p.view == BudgetView::Direction && !(p.direction.Norm() > 0 && std::isfinite(p.direction.Norm())))
    return Status::Invalid("the view direction must be a non-zero vector");
  return Status::Ok();
}

OrthoView FramedView(const IndexedMesh& mesh, const P3& direction, int width, int height, double fill) {
  const vcg::Box3d box = UsedVertexBox(mesh);
  OrthoView view;
  view.width = width;
  view.height = height;
  view.centre = box.IsNull() ? P3(0, 0, 0) : box.Center();
  const double diag = box.IsNull() ? 0.0 : box.Diag();
  view.pixelsPerUnit = diag > 0 ? fill * double(std::min(width, height)) / diag : 1.0;
  view.direction = direction / direction.Norm();
  // Up is the world axis least aligned with the direction (Y first), made orthogonal to it.
  P3 up = std::abs(view.direction[1]) < 0.9 ? P3(0, 1, 0) : P3(0, 0, 1);
  up = up - view.direction * (up * view.direction);
  view.up = up / up.Norm();
  view.right = view.direction ^ view.up;  // right-handed: right x up = -direction (eye looks along direction)
  return view;
}

size_t CountCoveredPixels(const IndexedMesh& mesh, const OrthoView& view, std::vector<uint8_t>* maskOut) {
  const int W = view.width, H = view.height;
  std::vector<uint8_t> localMask;
  std::vector<uint8_t>& mask = maskOut ? *maskOut : localMask;
  mask.assign(size_t(W) * size_t(H), 0);
  const double hw = 0.5 * W, hh = 0.5 * H, s = view.pixelsPerUnit;
  auto project = [&](const vcg::Point3f& q, double& x, double& y) {
    const P3 d = P3::Construct(q) - view.centre;
    x = hw + s * (d * view.right);
    y = hh - s * (d * view.up);
  };
  for (const auto& t : mesh.faces) {
    double x[3], y[3];
    for (int k = 0; k < 3; ++k) project(mesh.positions[t[size_t(k)]], x[k], y[k]);
    const double area2 = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
    if (!(std::abs(area2) > 1e-12)) continue;  // seen edge-on (or NaN): covers no pixel centre
    const double ymin = std::min({y[0], y[1], y[2]}), ymax = std::max({y[0], y[1], y[2]});
    // Rows whose centre line j + 0.5 crosses [ymin, ymax].
    const int j0 = std::max(0, int(std::ceil(ymin - 0.5)));
    const int j1 = std::min(H - 1, int(std::floor(ymax - 0.5)));
    for (int j = j0; j <= j1; ++j) {
      const double yc = j + 0.5;
      double xl = 1e300, xr = -1e300;
      for (int k = 0; k < 3; ++k) {
        const int n = (k + 1) % 3;
        const double ya = y[k], yb = y[n];
        if ((yc < ya && yc < yb) || (yc > ya && yc > yb)) continue;
        double xi;
        if (ya == yb) {  // horizontal edge on the centre line: both end points
          xl = std::min({xl, x[k], x[n]});
          xr = std::max({xr, x[k], x[n]});
          continue;
        }
        xi = x[k] + (yc - ya) * (x[n] - x[k]) / (yb - ya);
        xl = std::min(xl, xi);
        xr = std::max(xr, xi);
      }
      if (xl > xr) continue;
      // Pixels whose centre i + 0.5 lies in [xl, xr].
      const int i0 = std::max(0, int(std::ceil(xl - 0.5)));
      const int i1 = std::min(W - 1, int(std::floor(xr - 0.5)));
      if (i0 > i1) continue;
      std::fill(mask.begin() + std::ptrdiff_t(size_t(j) * size_t(W) + size_t(i0)),
                mask.begin() + std::ptrdiff_t(size_t(j) * size_t(W) + size_t(i1) + 1), uint8_t(1));
    }
  }
  return size_t(std::count(mask.begin(), mask.end(), uint8_t(1)));
}

Status ComputePixelBudget(const IndexedMesh& mesh, const PixelBudgetParams& p, PixelBudgetResult& out,
                          const Progress& progress) {
  out = PixelBudgetResult();
  Status s = ValidateParams(p);
  if (!s.ok()) return s;
  s = RequireValidForFaces(mesh);
  if (!s.ok()) return s;
  PixelBudgetResult r;
  r.currentFaces = mesh.faceCount();
  auto count = [&](const P3& dir) {
    const OrthoView v = FramedView(mesh, dir, p.width, p.height, p.fill);
    r.pixelsPerUnit = v.pixelsPerUnit;
    return CountCoveredPixels(mesh, v);
  };
  switch (p.view) {
    case BudgetView::WorstAxis: {
      const auto& dirs = AxisDirections();
      for (size_t i = 0; i < dirs.size(); ++i) {
        if (progress && !progress(int(100 * i / dirs.size()), "rasterising the projection")) return Status::Cancelled();
        r.axisPixels[i] = count(dirs[i]);
        if (i == 0 || r.axisPixels[i] > r.coveredPixels) {
          r.coveredPixels = r.axisPixels[i];
          r.viewDirection = dirs[i];
        }
      }
      break;
    }
    case BudgetView::Direction:
      r.viewDirection = p.direction / p.direction.Norm();
      r.coveredPixels = count(r.viewDirection);
      break;
    default:
      r.viewDirection = AxisDirections()[size_t(int(p.view) - int(BudgetView::PlusX))];
      r.coveredPixels = count(r.viewDirection);
      break;
  }
  r.targetFaces = size_t(std::llround(p.pixelFactor * double(r.coveredPixels)));
  r.aboveCurrent = r.targetFaces >= r.currentFaces;
  if (progress && !progress(100, "rasterising the projection")) return Status::Cancelled();
  out = r;
  return Status::Ok();
}

bool ParseBudgetView(const std::string& text, BudgetView& view, P3& direction) {
  static const char* names[] = {"worst", "+x", "-x", "+y", "-y", "+z", "-z"};
  for (int i = 0; i < 7; ++i)
    if (text == names[i]) {
      view = BudgetView(i);
      return true;
    }
  double d[3];
  const char* c = text.c_str();
  for (int k = 0; k < 3; ++k) {
    char* end = nullptr;
    d[k] = std::strtod(c, &end);
    if (end == c) return false;
    c = end;
    if (k < 2) {
      if (*c != ',') return false;
      ++c;
    }
  }
  if (*c != '\0') return false;
  direction = P3(d[0], d[1], d[2]);
  if (!(direction.Norm() > 0) || !std::isfinite(direction.Norm())) return false;
  view = BudgetView::Direction;
  return true;
}

std::string BudgetViewName(BudgetView view, const P3& d) {
  static const char* names[] = {"worst of the six axis directions", "+X", "-X", "+Y", "-Y", "+Z", "-Z"};
  if (view != BudgetView::Direction) return names[int(view)];
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%g, %g, %g)", d[0], d[1], d[2]);
  return buf;
}

}  // namespace conelod
