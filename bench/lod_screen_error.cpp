// The worst screen-space error of a drawn node after refinement, for eyes all around a .clod model
// and zoomed in (issue 24, item 17's table in docs/lod_viewer.md): the camera of conelod-viewer
// (35 degree vertical field of view, framed so that the bounding sphere fills the view, the zoom
// dividing that distance), refined with the screen-space error (LodRefiner) to one pixel within
// the face budget. A still cut must meet the pixel error wherever it is drawn, or have spent its
// budget. Uses only what the file and the refiner give (so that it builds against older trees).
//
//   lod_screen_error FILE.clod [--budget F] [--pixel-error PX] [--height H]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include "conelod/lod/lod_read.h"

using namespace conelod;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: lod_screen_error FILE.clod [--budget F] [--pixel-error PX] [--height H]\n");
    return 1;
  }
  size_t budget = 500000;
  double pixelError = 1, height = 600;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--budget")) budget = size_t(std::atof(argv[i + 1]));
    if (!std::strcmp(argv[i], "--pixel-error")) pixelError = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--height")) height = std::atof(argv[i + 1]);
  }
  std::unique_ptr<LodReader> r;
  const Status s = LodReader::Open(argv[1], r);
  if (!s.ok()) {
    std::fprintf(stderr, "%s: %s\n", argv[1], s.message.c_str());
    return 2;
  }
  const double fov = 35 * std::acos(-1.0) / 180;
  const vcg::Point3d c = vcg::Point3d::Construct(r->info().box.Center());
  const double radius = r->info().box.Diag() / 2;
  const double scale = height / (2 * std::tan(fov / 2));
  const struct {
    const char* name;
    vcg::Point3d dir;
  } eyes[] = {{"front (+z)", {0, 0, 1}},        {"back (-z)", {0, 0, -1}},       {"side (+x)", {1, 0, 0}},
              {"side (-x)", {-1, 0, 0}},        {"top (+y)", {0, 1, 0}},         {"diagonal (1,1,1)", {1, 1, 1}},
              {"(-1,0.3,0.6)", {-1, 0.3, 0.6}}, {"(0.4,-1,0.2)", {0.4, -1, 0.2}}};
  const double zooms[] = {1, 2, 4, 8};
  std::printf("%s: budget %zu faces, pixel error %g, %g pixels high\n", argv[1], budget, pixelError, height);
  std::printf("| eye | zoom | faces in the cut | levels drawn | worst drawn error (px) |\n|---|---|---|---|---|\n");
  for (const auto& e : eyes)
    for (double zoom : zooms) {
      vcg::Point3d dir = e.dir;
      dir.Normalize();
      LodView v;
      v.eye = c + dir * (radius / std::sin(fov / 2) * 1.05 / zoom);
      v.faceBudget = budget;
      v.projectionScale = scale;
      v.maxPixelError = pixelError;
      LodCut cut;
      const Status rs = RefineLod(*r, v, cut);
      if (!rs.ok()) {
        std::fprintf(stderr, "%s\n", rs.message.c_str());
        return 2;
      }
      double worst = 0;
      int lo = 99, hi = -1;
      for (size_t i = 0; i < cut.nodes.size(); ++i) {
        if (cut.culled[i]) continue;
        const LodNode& n = r->node(cut.nodes[i]);
        const double d = (v.eye - vcg::Point3d::Construct(n.center)).Norm() - double(n.radius);
        worst = std::max(worst, d > 0 ? double(n.error) * scale / d : (n.error > 0 ? HUGE_VAL : 0.0));
        lo = std::min(lo, n.level);
        hi = std::max(hi, n.level);
      }
      std::printf("| %s | %gx | %zu%s | %d-%d | %.2f |\n", e.name, zoom, cut.faces,
                  cut.faces + 4096 > budget ? " (near the budget)" : "", lo, hi, worst);
    }
  return 0;
}
