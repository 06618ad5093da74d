// ConeLOD — the face budget from screen pixels.
//
// Mizuno, Okumoto, Takata, Joe, "Polygon reduction for effective 3D model rendering on different
// platforms" (IPSJ SIG Technical Report 2011-MPS-86), §4-5: a scanned model shown at 1920x1080,
// 1600x900, 1280x720 and 800x600 was reduced with QEM to 1/10, 1, 10, 40, 50, 60 and 100 times
// the number of pixels it covers on screen (Table 1); from 50 times on the reduced model could
// not be told from the original, so the smallest face count that displays without visible loss
// is 50 x the covered pixels.
//
// We count the covered pixels by rasterising the projection of every face at the requested
// resolution: orthographic view along a direction, the model framed on its bounding sphere
// (centre = bounding-box centre, diameter = bounding-box diagonal D spanning fill x min(W, H)
// pixels, as MeshLab's "fit to window" frames a model), a pixel counted when its centre lies in a
// projected face (a coverage mask: no depth test is needed to count the union). The view is one
// axis direction, any direction, or the worst case (most pixels) over the six axis directions.
// Then target faces = factor x pixels.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "conelod/mesh/indexed_mesh.h"
#include "conelod/status.h"

namespace conelod {

enum class BudgetView { WorstAxis, PlusX, MinusX, PlusY, MinusY, PlusZ, MinusZ, Direction };

struct PixelBudgetParams {
  int width = 1920;  // viewport, pixels
  int height = 1080;
  double pixelFactor = 50.0;  // faces per covered pixel (the paper's finding: 50)
  BudgetView view = BudgetView::WorstAxis;
  vcg::Point3d direction = {0.0, 0.0, -1.0};  // view direction (eye -> model) for BudgetView::Direction
  double fill = 1.0;                          // the bounding sphere spans fill x min(width, height) pixels
};

// Checks the parameters; Ok or a message naming the bad one.
Status ValidateParams(const PixelBudgetParams& p);

// An orthographic camera: a point p lands at pixel coordinates
//   x = width/2 + pixelsPerUnit (p - centre).right,  y = height/2 - pixelsPerUnit (p - centre).up
// (pixel (i, j) covers [i, i+1) x [j, j+1), its centre is (i + 0.5, j + 0.5)).
struct OrthoView {
  vcg::Point3d centre = {0.0, 0.0, 0.0}, right = {1.0, 0.0, 0.0}, up = {0.0, 1.0, 0.0}, direction = {0.0, 0.0, -1.0};
  double pixelsPerUnit = 1;
  int width = 0, height = 0;
};

// The view along `direction` framing the mesh's bounding sphere (see above).
OrthoView FramedView(const IndexedMesh& mesh, const vcg::Point3d& direction, int width, int height, double fill = 1.0);

// Pixels whose centre lies inside the projection of at least one face. `mask` (optional)
// receives width x height bytes, row-major from the top, 1 = covered.
size_t CountCoveredPixels(const IndexedMesh& mesh, const OrthoView& view, std::vector<uint8_t>* mask = nullptr);

struct PixelBudgetResult {
  size_t coveredPixels = 0;  // for the view used
  size_t targetFaces = 0;    // round(pixelFactor x coveredPixels)
  size_t currentFaces = 0;
  bool aboveCurrent = false;                     // targetFaces >= currentFaces: no reduction needed
  vcg::Point3d viewDirection = {0.0, 0.0, 0.0};  // the direction used (the worst one for WorstAxis)
  std::array<size_t, 6> axisPixels{};            // +X, -X, +Y, -Y, +Z, -Z (WorstAxis only)
  double pixelsPerUnit = 0;
};

// The mesh must pass RequireValidForFaces (checked here).
Status ComputePixelBudget(const IndexedMesh& mesh, const PixelBudgetParams& params, PixelBudgetResult& out,
                          const Progress& progress = Progress());

// The six axis view directions in the order of PixelBudgetResult::axisPixels.
const std::array<vcg::Point3d, 6>& AxisDirections();

// "worst", "+x", "-x", "+y", "-y", "+z", "-z" or "X,Y,Z"; false if it does not parse.
bool ParseBudgetView(const std::string& text, BudgetView& view, vcg::Point3d& direction);
std::string BudgetViewName(BudgetView view, const vcg::Point3d& direction);

}  // namespace conelod
