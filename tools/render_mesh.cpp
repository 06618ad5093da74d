// ConeLOD doc tool — the one renderer of the pictures in docs/ (meshlabserver has no snapshot
// filter): flat-shaded triangles with a z-buffer, headless; per-face colours when the PLY has them
// (--colors: group and cluster colourings), the feature edges (dihedral angle <= A, border edges;
// feature_simplify.h) drawn in red on top, optionally every edge in grey (--wire). Orthographic
// view framed as pixel_budget.h frames a model, along --view X,Y,Z or, with --azimuth/--elevation,
// along -Z of the model rotated about Y by the azimuth and then about X by the elevation. Writes a
// PNG (zlib) when OUT ends in .png, else a binary PPM.
//
//   render_mesh IN.ply OUT.png|OUT.ppm [--size W H] [--view X,Y,Z | --azimuth DEG --elevation DEG]
//               [--colors] [--angle DEG] [--wire] [--no-features] [--zoom Z] [--supersample S]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <zlib.h>

#include "conelod/feature/feature_simplify.h"
#include "conelod/budget/pixel_budget.h"
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

// Writes an 8-bit RGB PNG: one IDAT chunk, filter 0 on every row.
bool WritePng(const char* path, int w, int h, const std::vector<unsigned char>& rgb) {
  std::vector<unsigned char> raw;
  raw.reserve(size_t(h) * (size_t(w) * 3 + 1));
  for (int y = 0; y < h; ++y) {
    raw.push_back(0);
    raw.insert(raw.end(), rgb.begin() + long(y) * w * 3, rgb.begin() + long(y + 1) * w * 3);
  }
  uLongf zbytes = compressBound(uLong(raw.size()));
  std::vector<unsigned char> z(zbytes);
  if (compress2(z.data(), &zbytes, raw.data(), uLong(raw.size()), 9) != Z_OK) return false;
  z.resize(zbytes);
  FILE* out = std::fopen(path, "wb");
  if (!out) return false;
  auto be32 = [](std::vector<unsigned char>& v, uint32_t x) {
    for (int k = 3; k >= 0; --k) v.push_back((unsigned char)(x >> (8 * k)));
  };
  auto chunk = [&](const char* type, const std::vector<unsigned char>& data) {
    std::vector<unsigned char> c;
    be32(c, uint32_t(data.size()));
    c.insert(c.end(), type, type + 4);
    c.insert(c.end(), data.begin(), data.end());
    std::vector<unsigned char> crc;
    be32(crc, uint32_t(crc32(0, c.data() + 4, uInt(c.size() - 4))));
    c.insert(c.end(), crc.begin(), crc.end());
    std::fwrite(c.data(), 1, c.size(), out);
  };
  static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::fwrite(sig, 1, 8, out);
  std::vector<unsigned char> ihdr;
  be32(ihdr, uint32_t(w));
  be32(ihdr, uint32_t(h));
  ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0});
  chunk("IHDR", ihdr);
  chunk("IDAT", z);
  chunk("IEND", {});
  return std::fclose(out) == 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: render_mesh IN.ply OUT.png|OUT.ppm [--size W H] [--view X,Y,Z | --azimuth DEG "
                 "--elevation DEG] [--colors] [--angle DEG] [--wire] [--no-features] [--zoom Z] [--supersample S]\n");
    return 1;
  }
  int W = 640, H = 480, ss = 3;
  P3 dir(-1, -1, -1);
  double angle = 135, zoom = 1;
  double azimuth = 0, elevation = 0;
  bool wire = false, features = true, colors = false, rotated = false;
  for (int i = 3; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--size" && i + 2 < argc) {
      W = std::atoi(argv[++i]);
      H = std::atoi(argv[++i]);
    } else if (a == "--view" && i + 1 < argc) {
      double x, y, z;
      if (std::sscanf(argv[++i], "%lf,%lf,%lf", &x, &y, &z) != 3) {
        std::fprintf(stderr, "bad --view\n");
        return 1;
      }
      dir = P3(x, y, z);
    } else if (a == "--angle" && i + 1 < argc)
      angle = std::atof(argv[++i]);
    else if (a == "--zoom" && i + 1 < argc)
      zoom = std::atof(argv[++i]);
    else if (a == "--supersample" && i + 1 < argc)
      ss = std::max(1, std::atoi(argv[++i]));
    else if (a == "--azimuth" && i + 1 < argc) {
      azimuth = std::atof(argv[++i]);
      rotated = true;
    } else if (a == "--elevation" && i + 1 < argc) {
      elevation = std::atof(argv[++i]);
      rotated = true;
    } else if (a == "--colors")
      colors = true;
    else if (a == "--wire")
      wire = true;
    else if (a == "--no-features")
      features = false;
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 1;
    }
  }
  if (rotated) {  // -Z of the rotated model, in model coordinates: Ry(-az) Rx(-el) (0, 0, -1)
    const double az = azimuth * M_PI / 180, el = elevation * M_PI / 180;
    const double y = -std::sin(el), z = -std::cos(el);
    dir = P3(-std::sin(az) * z, y, std::cos(az) * z);
  }
  CMesh mesh;
  int mask = 0;
  const std::string err = LoadPly(mesh, argv[1], &mask);
  if (!err.empty()) {
    std::fprintf(stderr, "%s\n", err.c_str());
    return 2;
  }
  const IndexedMesh im = ToIndexedMesh(mesh);
  std::vector<vcg::Color4b> faceColor;
  if (colors && (mask & vcg::tri::io::Mask::IOM_FACECOLOR))
    for (const auto& f : mesh.face)
      if (!f.IsD()) faceColor.push_back(f.cC());
  if (faceColor.size() != im.faceCount()) faceColor.clear();
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
  for (size_t fi = 0; fi < im.faces.size(); ++fi) {
    const auto& t = im.faces[fi];
    const P3 a = P3::Construct(im.positions[t[0]]), b = P3::Construct(im.positions[t[1]]),
             c = P3::Construct(im.positions[t[2]]);
    P3 n = (b - a) ^ (c - a);
    if (!(n.Norm() > 0)) continue;
    n.Normalize();
    const float shade = float(0.22 + 0.78 * std::abs(n * light));
    float col[3] = {0.80f * shade, 0.83f * shade, 0.88f * shade};
    if (!faceColor.empty())
      for (int k = 0; k < 3; ++k) col[k] = shade * float(faceColor[fi][k]) / 255.0f;
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
  // Box-filter down to W x H.
  std::vector<unsigned char> rgb(size_t(W) * size_t(H) * 3);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      for (int k = 0; k < 3; ++k) {
        double s = 0;
        for (int dy = 0; dy < ss; ++dy)
          for (int dx = 0; dx < ss; ++dx)
            s += img.rgb[(size_t(y * ss + dy) * size_t(SW) + size_t(x * ss + dx)) * 3 + size_t(k)];
        rgb[(size_t(y) * size_t(W) + size_t(x)) * 3 + size_t(k)] = (unsigned char)std::lround(255.0 * s / (ss * ss));
      }
  const std::string outPath = argv[2];
  bool written;
  if (outPath.size() > 4 && outPath.compare(outPath.size() - 4, 4, ".png") == 0) {
    written = WritePng(argv[2], W, H, rgb);
  } else {
    FILE* out = std::fopen(argv[2], "wb");
    written = out && std::fprintf(out, "P6\n%d %d\n255\n", W, H) > 0 &&
              std::fwrite(rgb.data(), 1, rgb.size(), out) == rgb.size();
    written = out && std::fclose(out) == 0 && written;
  }
  if (!written) {
    std::fprintf(stderr, "cannot write %s\n", argv[2]);
    return 3;
  }
  std::printf("%s: %zu faces, %zu feature edges drawn\n", argv[1], im.faceCount(), featureCount);
  return 0;
}
