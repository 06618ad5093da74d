// Splits every triangle of a binary PLY into four at its edge midpoints: the inputs of
// scripts/bench_scale.sh (the dragon subdivided 1, 2 and 3 times). The output is the one the
// script's Python writes: the input's vertices, then one new vertex per edge in the order the faces
// first meet them (faces in order, edges ab, bc, ca), each at the float of the double midpoint; per
// face the triangles (a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca).
//   subdivide_ply IN.ply OUT.ply
// IN: binary little-endian, vertex x y z floats only, faces as `list uchar int|uint vertex_indices`
// of triangles. OUT is written as OUT.part and renamed over OUT when complete.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

bool Fail(const std::string& why) {
  std::fprintf(stderr, "subdivide_ply: %s\n", why.c_str());
  return false;
}

bool Read(const char* path, std::vector<float>& pos, std::vector<uint32_t>& tri) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Fail(std::string("cannot read ") + path);
  std::string line, header;
  size_t nv = 0, nf = 0;
  while (std::getline(in, line)) {
    header += line + "\n";
    std::istringstream ls(line);
    std::string a, b;
    ls >> a >> b;
    if (a == "element" && b == "vertex") ls >> nv;
    if (a == "element" && b == "face") ls >> nf;
    if (line == "end_header") break;
  }
  const char* want[] = {"format binary_little_endian 1.0\n",
                        "property float x\nproperty float y\nproperty float z\n"
                        "element face"};
  for (const char* w : want)
    if (header.find(w) == std::string::npos)
      return Fail(std::string(path) + ": not a binary little-endian PLY of x y z floats only");
  const bool uint = header.find("property list uchar uint vertex_indices") != std::string::npos;
  if (!uint && header.find("property list uchar int vertex_indices") == std::string::npos)
    return Fail(std::string(path) + ": faces are not `list uchar int vertex_indices`");
  pos.resize(3 * nv);
  if (!in.read(reinterpret_cast<char*>(pos.data()), std::streamsize(12 * nv))) return Fail("short vertex data");
  tri.resize(3 * nf);
  std::vector<char> buf(13 * 65536);
  for (size_t f = 0; f < nf;) {
    const size_t n = std::min<size_t>(65536, nf - f);
    if (!in.read(buf.data(), std::streamsize(13 * n))) return Fail("short face data");
    for (size_t i = 0; i < n; ++i) {
      if (buf[13 * i] != 3) return Fail("a face is not a triangle");
      std::memcpy(&tri[3 * (f + i)], &buf[13 * i + 1], 12);
    }
    f += n;
  }
  for (uint32_t v : tri)
    if (v >= nv) return Fail("a face refers to a vertex that does not exist");
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: subdivide_ply IN.ply OUT.ply\n");
    return 1;
  }
  std::vector<float> pos;
  std::vector<uint32_t> tri;
  if (!Read(argv[1], pos, tri)) return 1;
  const size_t nv = pos.size() / 3, nf = tri.size() / 3;
  // Every face corner's edge (corner c of face f: the edge from it to the next corner), sorted by
  // edge and then by corner: each edge's first corner numbers it.
  std::vector<std::pair<uint64_t, uint32_t>> edges(3 * nf);
  for (size_t c = 0; c < 3 * nf; ++c) {
    uint64_t a = tri[c], b = tri[c - c % 3 + (c + 1) % 3];
    if (a > b) std::swap(a, b);
    edges[c] = {a << 32 | b, uint32_t(c)};
  }
  std::sort(edges.begin(), edges.end());
  std::vector<uint32_t> firstCorner(3 * nf);  // per corner: the first corner of its edge
  std::vector<uint8_t> isFirst(3 * nf, 0);
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    for (size_t k = i; k < j; ++k) firstCorner[edges[k].second] = edges[i].second;
    isFirst[edges[i].second] = 1;
    i = j;
  }
  std::vector<std::pair<uint64_t, uint32_t>>().swap(edges);
  std::vector<uint32_t> mid(3 * nf, 0);  // per first corner: its midpoint's id
  uint32_t next = uint32_t(nv);
  for (size_t c = 0; c < 3 * nf; ++c)
    if (isFirst[c]) {
      mid[c] = next++;
      const uint32_t a = tri[c], b = tri[c - c % 3 + (c + 1) % 3];
      for (int i = 0; i < 3; ++i) pos.push_back(float((double(pos[3 * a + i]) + double(pos[3 * b + i])) / 2));
    }
  const std::string part = std::string(argv[2]) + ".part";
  FILE* out = std::fopen(part.c_str(), "wb");
  if (!out) {
    std::fprintf(stderr, "subdivide_ply: cannot write %s\n", part.c_str());
    return 1;
  }
  const size_t outV = pos.size() / 3, outF = 4 * nf;
  std::fprintf(out,
               "ply\nformat binary_little_endian 1.0\nelement vertex %zu\nproperty float x\nproperty float y\n"
               "property float z\nelement face %zu\nproperty list uchar int vertex_indices\nend_header\n",
               outV, outF);
  bool ok = std::fwrite(pos.data(), 12, outV, out) == outV;
  std::vector<char> buf;
  for (size_t f = 0; ok && f < nf; ++f) {
    const uint32_t a = tri[3 * f], b = tri[3 * f + 1], c = tri[3 * f + 2];
    const uint32_t ab = mid[firstCorner[3 * f]], bc = mid[firstCorner[3 * f + 1]], ca = mid[firstCorner[3 * f + 2]];
    const std::array<std::array<uint32_t, 3>, 4> t = {{{{a, ab, ca}}, {{ab, b, bc}}, {{ca, bc, c}}, {{ab, bc, ca}}}};
    for (const auto& x : t) {
      buf.push_back(3);
      const char* p = reinterpret_cast<const char*>(x.data());
      buf.insert(buf.end(), p, p + 12);
    }
    if (buf.size() >= (1u << 20) || f + 1 == nf) {
      ok = std::fwrite(buf.data(), 1, buf.size(), out) == buf.size();
      buf.clear();
    }
  }
  ok = std::fclose(out) == 0 && ok;
  if (!ok || std::rename(part.c_str(), argv[2]) != 0) {
    std::remove(part.c_str());
    std::fprintf(stderr, "subdivide_ply: cannot write %s\n", argv[2]);
    return 1;
  }
  std::printf("subdivide_ply: wrote %s: %zu vertices, %zu faces\n", argv[2], outV, outF);
  return 0;
}
