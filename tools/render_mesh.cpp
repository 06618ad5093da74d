// ConeLOD doc tool — a tiny software renderer for the pictures in docs/: flat-shaded triangles
// with a z-buffer, the feature edges (dihedral angle <= A, border edges; feature_simplify.h) drawn
// in red on top, optionally every edge in grey. Orthographic view framed as pixel_budget.h frames
// a model. Writes a binary PPM (convert it with ImageMagick: `convert out.ppm out.png`).
//
//   render_mesh IN.ply OUT.ppm [--size W H] [--view X,Y,Z] [--angle DEG] [--wire] [--no-features]
//               [--zoom Z] [--supersample S]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "conelod/feature_simplify.h"
#include "conelod/pixel_budget.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"

using namespace conelod;
using P3 = vcg::Point3d;

namespace {

struct Image {
  int w, h;
  std::vector<float> rgb, depth;
  Image(int w_, int h_) : w(w_), h(h_), rgb(size_t(w_) * size_t(h_) * 3, 1.0f), depth(size_t(w_) * size_t(h_), 1e30f) {}
};

// Draws a segment with a depth test against the triangles (lines slightly in front win).
void DrawLine(Image& im, double x0, double y0, double z0, double x1, double y1, double z1, const float c[3],
              double width, double eps) {
  const double len = std::max(std::abs(x1 - x0), std::abs(y1 - y0));
  const int steps = std::max(1, int(std::ceil(len * 2)));
  const int r = int(std::ceil(width / 2));
  for (int s = 0; s <= steps; ++s) {
    const double t = double(s) / steps;
    const double x = x0 + (x1 - x0) * t, y = y0 + (y1 - y0) * t, z = z0 + (z1 - z0) * t;
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        if (dx * dx + dy * dy > (width / 2) * (width / 2) + 0.25) continue;
        const int i = int(std::floor(x)) + dx, j = int(std::floor(y)) + dy;
        if (i < 0 || j < 0 || i >= im.w || j >= im.h) continue;
        const size_t p = size_t(j) * size_t(im.w) + size_t(i);
        if (z > im.depth[p] + eps) continue;
        for (int k = 0; k < 3; ++k) im.rgb[p * 3 + size_t(k)] = c[k];
      }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: render_mesh IN.ply OUT.ppm [--size W H] [--view X,Y,Z] [--angle DEG] [--wire] "
                 "[--no-features] [--zoom Z] [--supersample S]\n");
    return 1;
  }
  int W = 640, H = 480, ss = 3;
  P3 dir(-1, -1, -1);
  double angle = 135, zoom = 1;
  bool wire = false, features = true;
  for (int i = 3; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--size" && i + 2 < argc) { W = std::atoi(argv[++i]); H = std::atoi(argv[++i]); }
    else if (a == "--view" && i + 1 < argc) {
      double x, y, z;
      if (std::sscanf(argv[++i], "%lf,%lf,%lf", &x, &y, &z) != 3) { std::fprintf(stderr, "bad --view\n"); return 1; }
      dir = P3(x, y, z);
    } else if (a == "--angle" && i + 1 < argc) angle = std::atof(argv[++i]);
    else if (a == "--zoom" && i + 1 < argc) zoom = std::atof(argv[++i]);
    else if (a == "--supersample" && i + 1 < argc) ss = std::max(1, std::atoi(argv[++i]));
    else if (a == "--wire") wire = true;
    else if (a == "--no-features") features = false;
    else { std::fprintf(stderr, "unknown option %s\n", a.c_str()); return 1; }
  }
  CMesh mesh;
  const std::string err = LoadPly(mesh, argv[1]);
  if (!err.empty()) { std::fprintf(stderr, "%s\n", err.c_str()); return 2; }
  const IndexedMesh im = ToIndexedMesh(mesh);
  const int SW = W * ss, SH = H * ss;
  const OrthoView view = FramedView(im, dir, SW, SH, 0.95 * zoom);
  Image img(SW, SH);
  const double diag = BoundingBoxDiagonal(im);
  std::vector<P3> scr(im.positions.size());
  for (size_t v = 0; v < im.positions.size(); ++v) {
    const P3 d = P3::Construct(im.positions[v]) - view.centre;
    scr[v] = P3(0.5 * SW + view.pixelsPerUnit * (d * view.right), 0.5 * SH - view.pixelsPerUnit * (d * view.up),
                d * view.direction);
  }
  // Key light from the upper left, in front of the model; two-sided.
  P3 light = -view.direction * 1.0 + view.up * 0.6 - view.right * 0.4;
  light.Normalize();
  for (const auto& t : im.faces) {
    const P3 a = P3::Construct(im.positions[t[0]]), b = P3::Construct(im.positions[t[1]]),
             c = P3::Construct(im.positions[t[2]]);
    P3 n = (b - a) ^ (c - a);
    if (!(n.Norm() > 0)) continue;
    n.Normalize();
    const float shade = float(0.22 + 0.78 * std::abs(n * light));
    const float col[3] = {0.80f * shade, 0.83f * shade, 0.88f * shade};
    const P3 &p0 = scr[t[0]], &p1 = scr[t[1]], &p2 = scr[t[2]];
    const double area = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p2[0] - p0[0]) * (p1[1] - p0[1]);
    if (std::abs(area) < 1e-12) continue;
    const int x0 = std::max(0, int(std::floor(std::min({p0[0], p1[0], p2[0]}))));
    const int x1 = std::min(SW - 1, int(std::ceil(std::max({p0[0], p1[0], p2[0]}))));
    const int y0 = std::max(0, int(std::floor(std::min({p0[1], p1[1], p2[1]}))));
    const int y1 = std::min(SH - 1, int(std::ceil(std::max({p0[1], p1[1], p2[1]}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double w0 = ((p1[0] - px) * (p2[1] - py) - (p2[0] - px) * (p1[1] - py)) / area;
        const double w1 = ((p2[0] - px) * (p0[1] - py) - (p0[0] - px) * (p2[1] - py)) / area;
        const double w2 = 1 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const float z = float(w0 * p0[2] + w1 * p1[2] + w2 * p2[2]);
        const size_t p = size_t(y) * size_t(SW) + size_t(x);
        if (z >= img.depth[p]) continue;
        img.depth[p] = z;
        for (int k = 0; k < 3; ++k) img.rgb[p * 3 + size_t(k)] = col[k];
      }
  }
  const double eps = 0.004 * diag;
  if (wire) {
    const float grey[3] = {0.35f, 0.37f, 0.42f};
    for (const auto& t : im.faces)
      for (int k = 0; k < 3; ++k) {
        const P3 &a = scr[t[size_t(k)]], &b = scr[t[size_t((k + 1) % 3)]];
        DrawLine(img, a[0], a[1], a[2], b[0], b[1], b[2], grey, 0.9 * ss / 2, eps);
      }
  }
  size_t featureCount = 0;
  if (features) {
    FeatureSimplifyParams p;
    p.featureAngleDeg = angle;
    p.extendFeatureLines = false;
    FeatureInfo info;
    if (DetectFeatures(im, p, info).ok()) {
      const float red[3] = {0.85f, 0.08f, 0.08f};
      for (const auto& e : info.featureEdges) {
        const P3 &a = scr[e[0]], &b = scr[e[1]];
        DrawLine(img, a[0], a[1], a[2], b[0], b[1], b[2], red, 2.2 * ss / 2, eps);
      }
      featureCount = info.featureEdges.size();
    }
  }
  // Box-filter down to W x H and write a binary PPM.
  FILE* out = std::fopen(argv[2], "wb");
  if (!out) { std::fprintf(stderr, "cannot write %s\n", argv[2]); return 3; }
  std::fprintf(out, "P6\n%d %d\n255\n", W, H);
  std::vector<unsigned char> row(size_t(W) * 3);
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x)
      for (int k = 0; k < 3; ++k) {
        double s = 0;
        for (int dy = 0; dy < ss; ++dy)
          for (int dx = 0; dx < ss; ++dx)
            s += img.rgb[(size_t(y * ss + dy) * size_t(SW) + size_t(x * ss + dx)) * 3 + size_t(k)];
        row[size_t(x) * 3 + size_t(k)] = (unsigned char)std::lround(255.0 * s / (ss * ss));
      }
    std::fwrite(row.data(), 1, row.size(), out);
  }
  std::fclose(out);
  std::printf("%s: %zu faces, %zu feature edges drawn\n", argv[1], im.faceCount(), featureCount);
  return 0;
}
