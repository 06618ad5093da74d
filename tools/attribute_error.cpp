// ConeLOD doc tool — the colour error of a simplified mesh (issue 26's measure): points sampled
// uniformly by area on the ORIGINAL surface (deterministic), each one's colour interpolated there
// (vertex colours, or the texture at the interpolated texture coordinates), compared with the
// colour interpolated at its closest point on the RESULT. Prints JSON: the RMS of the RGB
// difference over samples and channels (0-255 units), and the RMS and maximum sample distance in
// % of the original's bounding-box diagonal. scripts/compare_attributes.py runs it.
//
//   attribute_error ORIGINAL.ply RESULT.ply [--samples N] [--texture IMAGE.ppm]
//
// --texture: a binary PPM (P6, 8 bit) of the texture both meshes name (convert the JPEG or PNG
// with ImageMagick); texture coordinates per vertex or per face corner; bilinear, wrapped.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <vcg/complex/algorithms/closest.h>
#include <vcg/complex/algorithms/update/normal.h>
#include <vcg/complex/complex.h>
#include <vcg/space/index/grid_static_ptr.h>

#include "conelod/mesh/ply_format.h"

namespace {

class DVertex;
class DFace;
struct DUsedTypes : public vcg::UsedTypes<vcg::Use<DVertex>::AsVertexType, vcg::Use<DFace>::AsFaceType> {};
class DVertex : public vcg::Vertex<DUsedTypes, vcg::vertex::Coord3d, vcg::vertex::BitFlags> {};
class DFace
    : public vcg::Face<DUsedTypes, vcg::face::VertexRef, vcg::face::Normal3d, vcg::face::Mark, vcg::face::BitFlags> {};
class DMesh : public vcg::tri::TriMesh<std::vector<DVertex>, std::vector<DFace>> {};

struct Image {
  int w = 0, h = 0;
  std::vector<unsigned char> rgb;
  std::array<double, 3> at(double u, double v) const {  // bilinear; v = 0 at the bottom row
    double x = (u - std::floor(u)) * w - 0.5, y = (1 - (v - std::floor(v))) * h - 0.5;
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    std::array<double, 3> c{{0, 0, 0}};
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) {
        const int xi = ((x0 + dx) % w + w) % w, yi = ((y0 + dy) % h + h) % h;
        const double wgt = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy);
        for (int k = 0; k < 3; ++k) c[size_t(k)] += wgt * rgb[(size_t(yi) * size_t(w) + size_t(xi)) * 3 + size_t(k)];
      }
    return c;
  }
};

bool ReadPpm(const std::string& path, Image& im) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  int maxv = 0;
  const bool ok = std::fscanf(f, "P6 %d %d %d", &im.w, &im.h, &maxv) == 3 && maxv == 255 && std::fgetc(f) != EOF;
  if (ok) {
    im.rgb.resize(size_t(im.w) * size_t(im.h) * 3);
    const bool full = std::fread(im.rgb.data(), 1, im.rgb.size(), f) == im.rgb.size();
    std::fclose(f);
    return full;
  }
  std::fclose(f);
  return false;
}

// The colour of face f of `m` at barycentric coordinates b.
std::array<double, 3> ColourAt(const conelod::PlyMesh& m, size_t f, const double b[3], const Image* texture) {
  std::array<double, 3> c{{0, 0, 0}};
  const auto& t = m.triangles[f];
  if (texture) {
    double u = 0, v = 0;
    for (size_t k = 0; k < 3; ++k) {
      const double tu = m.wedgeTexCoords.empty() ? m.texCoords[t[k]][0] : m.wedgeTexCoords[f][2 * k];
      const double tv = m.wedgeTexCoords.empty() ? m.texCoords[t[k]][1] : m.wedgeTexCoords[f][2 * k + 1];
      u += b[k] * tu;
      v += b[k] * tv;
    }
    return texture->at(u, v);
  }
  for (size_t k = 0; k < 3; ++k)
    for (size_t ch = 0; ch < 3; ++ch) c[ch] += b[k] * 255.0 * m.colors[t[k]][ch];
  return c;
}

uint64_t Next(uint64_t& s) {  // xorshift64*
  s ^= s >> 12;
  s ^= s << 25;
  s ^= s >> 27;
  return s * 0x2545F4914F6CDD1Dull;
}
double Unit(uint64_t& s) { return double(Next(s) >> 11) * (1.0 / 9007199254740992.0); }

int Fail(const std::string& message) {
  std::fprintf(stderr, "attribute_error: %s\n", message.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) return Fail("usage: attribute_error ORIGINAL.ply RESULT.ply [--samples N] [--texture IMAGE.ppm]");
  long samples = 200000;
  std::string texturePath;
  for (int i = 3; i + 1 < argc; i += 2) {
    if (std::string(argv[i]) == "--samples")
      samples = std::strtol(argv[i + 1], nullptr, 10);
    else if (std::string(argv[i]) == "--texture")
      texturePath = argv[i + 1];
    else
      return Fail(std::string("unknown option ") + argv[i]);
  }
  conelod::PlyMesh a, b;
  std::string err = conelod::ReadPly(argv[1], a);
  if (err.empty()) err = conelod::ReadPly(argv[2], b);
  if (!err.empty()) return Fail(err);
  Image image;
  if (!texturePath.empty() && !ReadPpm(texturePath, image)) return Fail(texturePath + ": not an 8-bit binary PPM");
  const Image* texture = texturePath.empty() ? nullptr : &image;
  for (const conelod::PlyMesh* m : {&a, &b}) {
    if (texture ? (m->texCoords.empty() && m->wedgeTexCoords.empty()) : m->colors.empty())
      return Fail(std::string(m == &a ? argv[1] : argv[2]) +
                  (texture ? " has no texture coordinates" : " has no vertex colour"));
    if (m->triangles.empty()) return Fail("a mesh has no faces");
  }
  DMesh target;
  auto vi = vcg::tri::Allocator<DMesh>::AddVertices(target, b.positions.size());
  for (const auto& p : b.positions) (vi++)->P() = vcg::Point3d(p[0], p[1], p[2]);
  auto fi = vcg::tri::Allocator<DMesh>::AddFaces(target, b.triangles.size());
  for (const auto& t : b.triangles) {
    for (int k = 0; k < 3; ++k) fi->V(k) = &target.vert[t[size_t(k)]];
    ++fi;
  }
  vcg::tri::UpdateNormal<DMesh>::PerFaceNormalized(target);
  vcg::Box3d box;
  for (const auto& p : a.positions) box.Add(vcg::Point3d(p[0], p[1], p[2]));
  for (const auto& p : b.positions) box.Add(vcg::Point3d(p[0], p[1], p[2]));
  const double diag = box.Diag();
  box.Offset(0.01 * diag);
  vcg::GridStaticPtr<DFace, double> grid;
  grid.Set(target.face.begin(), target.face.end(), box);

  // Area-weighted face choice: cumulative areas.
  std::vector<double> cumulative(a.triangles.size());
  double total = 0;
  for (size_t f = 0; f < a.triangles.size(); ++f) {
    const auto& t = a.triangles[f];
    vcg::Point3d p[3];
    for (int k = 0; k < 3; ++k)
      p[k] = vcg::Point3d(a.positions[t[size_t(k)]][0], a.positions[t[size_t(k)]][1], a.positions[t[size_t(k)]][2]);
    total += 0.5 * ((p[1] - p[0]) ^ (p[2] - p[0])).Norm();
    cumulative[f] = total;
  }
  uint64_t seed = 0x9E3779B97F4A7C15ull;
  double sumColour2 = 0, sumDist2 = 0, maxDist = 0;
  long n = 0;
  vcg::tri::FaceTmark<DMesh> marker;
  marker.SetMesh(&target);
  vcg::face::PointDistanceBaseFunctor<double> distance;
  for (long s = 0; s < samples; ++s) {
    const size_t f =
        size_t(std::lower_bound(cumulative.begin(), cumulative.end(), Unit(seed) * total) - cumulative.begin());
    if (f >= a.triangles.size()) continue;
    double r1 = Unit(seed), r2 = Unit(seed);
    if (r1 + r2 > 1) {
      r1 = 1 - r1;
      r2 = 1 - r2;
    }
    const double bs[3] = {1 - r1 - r2, r1, r2};
    vcg::Point3d p(0, 0, 0);
    for (size_t k = 0; k < 3; ++k) {
      const auto& q = a.positions[a.triangles[f][k]];
      p += vcg::Point3d(q[0], q[1], q[2]) * bs[k];
    }
    double dist = diag;
    vcg::Point3d closest(0, 0, 0);
    DFace* hit = grid.GetClosest(distance, marker, p, diag, dist, closest);
    if (!hit) continue;
    vcg::Point3d bary;
    vcg::InterpolationParameters(*hit, hit->cN(), closest, bary);
    double bb[3] = {std::max(0.0, bary[0]), std::max(0.0, bary[1]), std::max(0.0, bary[2])};
    const double sum = bb[0] + bb[1] + bb[2];
    for (double& x : bb) x = sum > 0 ? x / sum : 1.0 / 3;
    const auto want = ColourAt(a, f, bs, texture);
    const auto got = ColourAt(b, size_t(hit - &target.face[0]), bb, texture);
    for (size_t c = 0; c < 3; ++c) sumColour2 += (want[c] - got[c]) * (want[c] - got[c]);
    sumDist2 += dist * dist;
    maxDist = std::max(maxDist, dist);
    ++n;
  }
  if (n == 0) return Fail("no sample found a closest point");
  std::printf("{\"samples\":%ld,\"colour_rms\":%.4f,\"distance_rms_pct\":%.5f,\"distance_max_pct\":%.5f}\n", n,
              std::sqrt(sumColour2 / (3.0 * double(n))), 100 * std::sqrt(sumDist2 / double(n)) / diag,
              100 * maxDist / diag);
  return 0;
}
