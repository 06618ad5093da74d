// ConeLOD CLI — `conelod budget`: the face budget from screen pixels (Mizuno,
// Okumoto, Takata, Joe), optionally simplifying to it with the feature-preserving simplifier.
#include <cstdio>

#include "cli_common.h"
#include "commands.h"
#include "conelod/mesh/safe_file.h"
#include "conelod/feature/feature_simplify.h"
#include "conelod/budget/pixel_budget.h"
#include "conelod/simplify_bridge.h"

namespace conelod {
namespace cli {

const char* kBudgetUsage =
    "conelod budget IN.ply [--width W --height H --factor F] [--view V] [--fill S] [-o OUT.ply] [--mask M.pgm]\n"
    "               [--json]\n"
    "  Counts the pixels the model covers at W x H [1920 x 1080] (orthographic, framed on its\n"
    "  bounding sphere: the bounding-box diagonal spans S x min(W, H) pixels [1]) and prints the\n"
    "  face budget F x pixels [50] (Mizuno-Okumoto-Takata-Joe). V: worst [default: the most pixels\n"
    "  over the six axis directions], +x, -x, +y, -y, +z, -z, or a direction X,Y,Z (eye -> model).\n"
    "  -o: simplifies to the budget with feature-simplify (defaults) and writes OUT.ply.\n"
    "  --mask: writes the covered pixels of the view used as a W x H image (PGM, covered = black).\n";

int CmdBudget(int argc, char** argv) {
  Args a(argc, argv, {"--width", "--height", "--factor", "--view", "--fill", "-o", "--mask"}, {"--json"});
  PixelBudgetParams p;
  p.width = a.integer("--width", p.width);
  p.height = a.integer("--height", p.height);
  p.pixelFactor = a.num("--factor", p.pixelFactor);
  p.fill = a.num("--fill", p.fill);
  if (!a.ok()) return Fail(kUsage, a.error() + "\n" + kBudgetUsage);
  if (a.positional().size() != 1) return Fail(kUsage, std::string("expected one input mesh\n") + kBudgetUsage);
  if (a.has("--view") && !ParseBudgetView(a.str("--view"), p.view, p.direction))
    return Fail(kUsage, "--view expects worst, +x, -x, +y, -y, +z, -z or X,Y,Z; got '" + a.str("--view") + "'");
  Status s = ValidateParams(p);
  if (!s.ok()) return Fail(kUsage, s.message);

  CMesh mesh;
  IndexedMesh im;
  std::vector<size_t> faceOf;
  std::string err = LoadInput(a.positional()[0], mesh, im, faceOf);
  if (!err.empty()) return FailLoad(err);
  PixelBudgetResult r;
  Timer timer;
  s = ComputePixelBudget(im, p, r);
  const double seconds = timer.seconds();
  if (!s.ok()) return Fail(kBadInput, a.positional()[0] + ": " + s.message);

  // Both outputs are written and synced before either replaces its target: both or neither.
  SafeFile maskOut, meshOut;
  if (a.has("--mask")) {
    std::vector<uint8_t> mask;
    CountCoveredPixels(im, FramedView(im, r.viewDirection, p.width, p.height, p.fill), &mask);
    std::string err = maskOut.open(a.str("--mask"));
    if (!err.empty()) return Fail(kIoError, err);
    std::fprintf(maskOut.file(), "P5\n%d %d\n255\n", p.width, p.height);
    for (uint8_t& m : mask) m = m ? 0 : 255;
    std::fwrite(mask.data(), 1, mask.size(), maskOut.file());
    err = maskOut.sync();  // checks every write above
    if (!err.empty()) return Fail(kIoError, err);
  }

  FeatureSimplifyResult fr;
  bool simplified = false;
  if (a.has("-o")) {
    if (!r.aboveCurrent) {
      FeatureSimplifyParams fp;
      fp.targetFaceCount = std::max<size_t>(1, r.targetFaces);
      s = FeatureSimplify(im, fp, fr);
      if (!s.ok()) return Fail(kBadInput, a.positional()[0] + ": " + s.message);
      WriteSimplifiedMesh(mesh, faceOf, fr, false);
      simplified = true;
    }
    err = SavePlyUncommitted(mesh, a.str("-o"), meshOut);
    if (!err.empty()) return Fail(kIoError, err);
  }
  if (a.has("--mask")) {
    err = maskOut.commit();
    if (!err.empty()) return Fail(kIoError, err);
  }
  if (a.has("-o")) {
    err = meshOut.commit();
    if (!err.empty()) return Fail(kIoError, err);
  }

  const std::string view = BudgetViewName(p.view, p.direction);
  if (a.has("--json")) {
    Json j;
    j.BeginObject()
        .field("input", a.positional()[0])
        .field("covered_pixels", r.coveredPixels)
        .field("target_faces", r.targetFaces)
        .field("faces", r.currentFaces)
        .field("above_current", r.aboveCurrent)
        .field("width", p.width)
        .field("height", p.height)
        .field("factor", p.pixelFactor)
        .field("fill", p.fill)
        .field("view", view)
        .field("view_direction_x", r.viewDirection[0])
        .field("view_direction_y", r.viewDirection[1])
        .field("view_direction_z", r.viewDirection[2])
        .field("screen_fraction", double(r.coveredPixels) / (double(p.width) * p.height))
        .field("seconds", seconds);
    if (p.view == BudgetView::WorstAxis) {
      j.key("axis_pixels").BeginArray();
      for (size_t v : r.axisPixels) j.value(v);
      j.endArray();
    }
    if (a.has("-o")) j.field("output", a.str("-o")).field("faces_out", simplified ? fr.facesOut : r.currentFaces);
    j.EndObject();
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("%s at %d x %d, view %s: %zu covered pixels (%.1f %% of the screen)\n", a.positional()[0].c_str(),
                p.width, p.height, view.c_str(), r.coveredPixels,
                100.0 * double(r.coveredPixels) / (double(p.width) * p.height));
    std::printf("face budget %g x %zu = %zu faces; the mesh has %zu", p.pixelFactor, r.coveredPixels, r.targetFaces,
                r.currentFaces);
    if (r.aboveCurrent)
      std::printf(": the budget is ABOVE the current face count, no reduction is needed\n");
    else
      std::printf(" (reduce to %.1f %%)\n", 100.0 * double(r.targetFaces) / double(r.currentFaces));
    if (a.has("-o"))
      std::printf("wrote %s (%zu faces%s)\n", a.str("-o").c_str(), simplified ? fr.facesOut : r.currentFaces,
                  simplified ? "" : ", unchanged");
  }
  return kOk;
}

}  // namespace cli
}  // namespace conelod
