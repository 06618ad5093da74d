// ConeLOD — the checked PLY reader (ply_format.h).
#include "conelod/mesh/ply_format.h"

#include "conelod/mesh/safe_file.h"

#include <algorithm>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "conelod/parallel.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

namespace conelod {
namespace {

// Scalar type codes: index into kTypes.
struct TypeInfo {
  const char* name;
  const char* alias;
  int bytes;
};
const TypeInfo kTypes[] = {{"", "", 0},           {"char", "int8", 1},     {"uchar", "uint8", 1},
                           {"short", "int16", 2}, {"ushort", "uint16", 2}, {"int", "int32", 4},
                           {"uint", "uint32", 4}, {"float", "float32", 4}, {"double", "float64", 8}};
enum { kInt8 = 1, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };
const size_t kMaxHeaderBytes = 1 << 20;
const uint64_t kMaxCount = UINT32_MAX;   // vertex indices are 32-bit
const size_t kMaxPolygonCorners = 4096;  // ear clipping and the crossing test are quadratic

int TypeCode(const std::string& s) {
  for (int t = 1; t <= kFloat64; ++t)
    if (s == kTypes[t].name || s == kTypes[t].alias) return t;
  return 0;
}

std::vector<std::string> Split(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  std::string w;
  while (in >> w) out.push_back(w);
  return out;
}

// What a file that is not PLY is, by its first bytes (for "only PLY is read").
std::string NotPlyMessage(const char* d, size_t n) {
  auto starts = [&](const char* p) { return n >= std::strlen(p) && std::memcmp(d, p, std::strlen(p)) == 0; };
  if (n >= 2 && (unsigned char)d[0] == 0x1f && (unsigned char)d[1] == 0x8b)
    return "is gzip-compressed: only PLY is read (decompress it first)";
  if (starts("OFF") || starts("COFF") || starts("NOFF") || starts("CNOFF") || starts("STOFF") || starts("4OFF"))
    return "is an OFF file: only PLY is read (convert it, e.g. with MeshLab's File > Export Mesh)";
  if (starts("solid"))
    return "is an ASCII STL file: only PLY is read (convert it, e.g. with MeshLab's File > Export Mesh)";
  if (n >= 84) {
    uint32_t triangles = 0;
    std::memcpy(&triangles, d + 80, 4);  // binary STL: 80-byte header, count, 50 bytes a triangle
    if (uint64_t(84) + uint64_t(triangles) * 50 == n)
      return "is a binary STL file: only PLY is read (convert it, e.g. with MeshLab's File > Export Mesh)";
  }
  size_t i = 0;  // OBJ: the first line that is not blank starts with a known keyword
  while (i < n && (d[i] == ' ' || d[i] == '\t' || d[i] == '\r' || d[i] == '\n')) ++i;
  for (const char* k : {"# ", "#\n", "v ", "vn ", "vt ", "f ", "o ", "g ", "mtllib ", "usemtl "})
    if (n - i >= std::strlen(k) && std::memcmp(d + i, k, std::strlen(k)) == 0)
      return "looks like an OBJ file: only PLY is read (convert it, e.g. with MeshLab's File > Export Mesh)";
  return "is not a PLY file (it does not start with 'ply'): only PLY is read";
}

// Reads records after the header; every read is bounds-checked.
class Cursor {
 public:
  Cursor(const char* p, const char* end, PlyEncoding e) : p_(p), end_(end), enc_(e) {}
  size_t left() const { return size_t(end_ - p_); }
  const char* at() const { return p_; }
  void skip(size_t n) { p_ += n; }  // n <= left()
  // Binary data in the host's byte order (the records can be read as they are).
  bool native() const { return enc_ != PlyEncoding::Ascii && (enc_ == PlyEncoding::BinaryBigEndian) == kBigEndianHost; }

  // One scalar of `type` as a double. False at the end of the data or on a malformed ASCII token.
  bool scalar(int type, double& v) {
    if (enc_ == PlyEncoding::Ascii) return token(type, v);
    const int n = kTypes[type].bytes;
    if (left() < size_t(n)) return false;
    unsigned char b[8];
    std::memcpy(b, p_, size_t(n));
    p_ += n;
    const bool swap = (enc_ == PlyEncoding::BinaryBigEndian) != kBigEndianHost;
    if (swap)
      for (int i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
    switch (type) {
      case kInt8: {
        int8_t x;
        std::memcpy(&x, b, 1);
        v = x;
        break;
      }
      case kUint8:
        v = b[0];
        break;
      case kInt16: {
        int16_t x;
        std::memcpy(&x, b, 2);
        v = x;
        break;
      }
      case kUint16: {
        uint16_t x;
        std::memcpy(&x, b, 2);
        v = x;
        break;
      }
      case kInt32: {
        int32_t x;
        std::memcpy(&x, b, 4);
        v = x;
        break;
      }
      case kUint32: {
        uint32_t x;
        std::memcpy(&x, b, 4);
        v = x;
        break;
      }
      case kFloat32: {
        float x;
        std::memcpy(&x, b, 4);
        v = x;
        break;
      }
      default: {
        double x;
        std::memcpy(&x, b, 8);
        v = x;
        break;
      }
    }
    return true;
  }
  // An ASCII token that is not a number, for messages.
  const std::string& badToken() const { return bad_; }

 private:
  bool token(int type, double& v) {
    while (p_ < end_ && (*p_ == ' ' || *p_ == '\t' || *p_ == '\r' || *p_ == '\n')) ++p_;
    const char* s = p_;
    while (p_ < end_ && !(*p_ == ' ' || *p_ == '\t' || *p_ == '\r' || *p_ == '\n')) ++p_;
    const size_t n = size_t(p_ - s);
    if (n == 0) return false;
    char buf[72];
    if (n >= sizeof buf) {
      bad_.assign(s, 40);
      bad_ += "...";
      return false;
    }
    std::memcpy(buf, s, n);
    buf[n] = '\0';
    char* e = nullptr;
    errno = 0;
    if (type == kFloat32)
      v = std::strtof(buf, &e);  // as vcglib reads floats: no double rounding
    else if (type == kFloat64)
      v = std::strtod(buf, &e);
    else
      v = double(std::strtoll(buf, &e, 10));
    if (e != buf + n || (type < kFloat32 && errno == ERANGE)) {
      bad_ = buf;
      return false;
    }
    return true;
  }

  static const bool kBigEndianHost;
  const char* p_;
  const char* end_;
  PlyEncoding enc_;
  std::string bad_;
};
const bool Cursor::kBigEndianHost = [] {
  const uint16_t x = 1;
  unsigned char c;
  std::memcpy(&c, &x, 1);
  return c == 0;
}();

double Orient(const double a[2], const double b[2], const double c[2]) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

}  // namespace

std::string ParsePlyHeader(const char* data, size_t size, PlyHeader& h, uint64_t fileBytes) {
  h = PlyHeader();
  if (size == 0) return "is empty";
  if (!(size >= 4 && std::memcmp(data, "ply", 3) == 0 && (data[3] == '\n' || data[3] == '\r')))
    return NotPlyMessage(data, size);
  size_t pos = 0;
  bool haveFormat = false, ended = false;
  PlyElement* current = nullptr;
  int lineNo = 0;
  while (!ended) {
    const size_t limit = std::min(size, kMaxHeaderBytes);
    const char* nl = static_cast<const char*>(std::memchr(data + pos, '\n', limit - pos));
    if (!nl)
      return size > kMaxHeaderBytes ? "has a PLY header longer than 1 MiB"
                                    : "ends inside its PLY header (no end_header line)";
    std::string line(data + pos, size_t(nl - (data + pos)));
    pos = size_t(nl - data) + 1;
    ++lineNo;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::vector<std::string> w = Split(line);
    const std::string where = "PLY header line " + std::to_string(lineNo) + " ('" + line.substr(0, 60) + "')";
    if (lineNo == 1) continue;                                          // "ply"
    if (w.size() >= 3 && w[0] == "comment" && w[1] == "TextureFile") {  // MeshLab's texture names
      const size_t at = line.find("TextureFile") + 11;
      const size_t from = line.find_first_not_of(" \t", at);
      const size_t to = line.find_last_not_of(" \t");
      h.textureFiles.push_back(line.substr(from, to + 1 - from));
      continue;
    }
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") {
      ended = true;
    } else if (w[0] == "format") {
      if (w.size() < 2) return where + ": no format";
      if (w[1] == "ascii")
        h.encoding = PlyEncoding::Ascii;
      else if (w[1] == "binary_little_endian")
        h.encoding = PlyEncoding::BinaryLittleEndian;
      else if (w[1] == "binary_big_endian")
        h.encoding = PlyEncoding::BinaryBigEndian;
      else
        return where + ": unknown format '" + w[1] + "'";
      haveFormat = true;
    } else if (w[0] == "element") {
      if (w.size() != 3) return where + ": expected 'element NAME COUNT'";
      const std::string& c = w[2];
      if (c.empty() || c.size() > 12 || c.find_first_not_of("0123456789") != std::string::npos)
        return where + ": the count '" + c + "' is not a whole number >= 0";
      const uint64_t count = std::strtoull(c.c_str(), nullptr, 10);
      if (count > kMaxCount) return where + ": the count " + c + " is over the 2^32 - 1 this reader takes";
      h.elements.push_back(PlyElement());
      current = &h.elements.back();
      current->name = w[1];
      current->count = count;
    } else if (w[0] == "property") {
      if (!current) return where + ": a property before any element";
      PlyProperty p;
      if (w.size() == 5 && w[1] == "list") {
        p.isList = true;
        p.countType = TypeCode(w[2]);
        p.type = TypeCode(w[3]);
        p.name = w[4];
        if (!p.countType || !p.type) return where + ": unknown type '" + (p.countType ? w[3] : w[2]) + "'";
        if (p.countType >= kFloat32) return where + ": a list count must be an integer type";
      } else if (w.size() == 3) {
        p.type = TypeCode(w[1]);
        p.name = w[2];
        if (!p.type) return where + ": unknown type '" + w[1] + "'";
      } else {
        return where + ": expected 'property TYPE NAME' or 'property list COUNTTYPE TYPE NAME'";
      }
      for (const PlyProperty& q : current->properties)
        if (q.name == p.name)
          return where + ": the element '" + current->name + "' declares a property '" + p.name +
                 "' twice (which one holds the values is ambiguous)";
      current->properties.push_back(p);
    } else {
      return where + ": unknown keyword '" + w[0] + "'";
    }
  }
  if (!haveFormat) return "has no 'format' line in its PLY header";
  h.headerBytes = pos;
  // Every record needs at least this many bytes: the counts cannot claim more than the file has.
  const uint64_t body = std::max<uint64_t>(fileBytes, size) - pos;
  uint64_t needed = 0;
  for (const PlyElement& e : h.elements) {
    if (e.count && e.properties.empty())
      return "declares " + std::to_string(e.count) + " '" + e.name + "' records without properties";
    uint64_t record = 0;
    for (const PlyProperty& p : e.properties)
      record += h.encoding == PlyEncoding::Ascii ? 2 : uint64_t(kTypes[p.isList ? p.countType : p.type].bytes);
    const uint64_t bytes = e.count * record;  // <= 2^32 * 2^12 * 8: no overflow
    needed += bytes;
    if (needed > body + (h.encoding == PlyEncoding::Ascii ? 1 : 0))
      return "claims " + std::to_string(e.count) + " " + e.name + " records (at least " + std::to_string(bytes) +
             " bytes) but only " + std::to_string(body) + " bytes follow the header: truncated or corrupt";
  }
  return "";
}

uint64_t PlyTriangleFileBytes(const PlyHeader& h) {
  if (h.encoding == PlyEncoding::Ascii) return 0;
  uint64_t bytes = h.headerBytes;
  for (const PlyElement& e : h.elements) {
    uint64_t record = 0;
    for (const PlyProperty& p : e.properties)
      record +=
          p.isList ? uint64_t(kTypes[p.countType].bytes + 3 * kTypes[p.type].bytes) : uint64_t(kTypes[p.type].bytes);
    bytes += e.count * record;
  }
  return bytes;
}

std::string TriangulatePolygon(const std::vector<std::array<float, 3>>& P, const std::vector<uint32_t>& corners,
                               std::vector<std::array<uint32_t, 3>>& out) {
  const size_t n = corners.size();
  // Newell's normal; the polygon is projected onto the coordinate plane it is most parallel to.
  double N[3] = {0, 0, 0};
  for (size_t i = 0; i < n; ++i) {
    const auto& a = P[corners[i]];
    const auto& b = P[corners[(i + 1) % n]];
    N[0] += (double(a[1]) - b[1]) * (double(a[2]) + b[2]);
    N[1] += (double(a[2]) - b[2]) * (double(a[0]) + b[0]);
    N[2] += (double(a[0]) - b[0]) * (double(a[1]) + b[1]);
  }
  if (!(std::fabs(N[0]) + std::fabs(N[1]) + std::fabs(N[2]) > 0)) {
    // No net area: collinear corners, or a polygon whose lobes cancel (a bow tie). The plane of
    // its largest corner triangle tells them apart below (the crossing test).
    double best = 0;
    for (size_t i = 2; i < n; ++i) {
      const auto& a = P[corners[0]];
      const auto& b = P[corners[1]];
      const auto& c = P[corners[i]];
      const double e[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
      const double f[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
      const double x[3] = {e[1] * f[2] - e[2] * f[1], e[2] * f[0] - e[0] * f[2], e[0] * f[1] - e[1] * f[0]};
      const double len = std::fabs(x[0]) + std::fabs(x[1]) + std::fabs(x[2]);
      if (len > best) {
        best = len;
        N[0] = x[0];
        N[1] = x[1];
        N[2] = x[2];
      }
    }
  }
  const int drop = std::fabs(N[0]) > std::fabs(N[1]) ? (std::fabs(N[0]) > std::fabs(N[2]) ? 0 : 2)
                                                     : (std::fabs(N[1]) > std::fabs(N[2]) ? 1 : 2);
  if (!(std::fabs(N[drop]) > 0)) {  // no area (or NaN): any triangulation is as degenerate; use the fan
    for (size_t i = 1; i + 1 < n; ++i) out.push_back({corners[0], corners[i], corners[i + 1]});
    return "";
  }
  const int u = (drop + 1) % 3, v = (drop + 2) % 3;
  const double sign = N[drop] > 0 ? 1 : -1;  // makes the projected polygon counter-clockwise
  std::vector<std::array<double, 2>> q(n);
  for (size_t i = 0; i < n; ++i) q[i] = {double(P[corners[i]][size_t(u)]), sign * double(P[corners[i]][size_t(v)])};
  // Edges that cross (properly) make the polygon's inside undefined: refuse.
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // adjacent through the closing edge
      const double* a = q[i].data();
      const double* b = q[(i + 1) % n].data();
      const double* c = q[j].data();
      const double* d = q[(j + 1) % n].data();
      if (Orient(a, b, c) * Orient(a, b, d) < 0 && Orient(c, d, a) * Orient(c, d, b) < 0)
        return "is a polygon of " + std::to_string(n) + " corners whose edges cross (edges " + std::to_string(i) +
               " and " + std::to_string(j) + "): it has no well-defined inside to triangulate";
    }
  std::vector<size_t> ring(n);
  for (size_t i = 0; i < n; ++i) ring[i] = i;
  // Whether the corner at ring position k can be clipped. Levels, tried in order until a corner
  // passes, back to 0 after each clip: 0 and 1 refuse a triangle with another corner inside it or
  // on its boundary (a corner on the diagonal a-c pinches what remains, whose later "ears" can
  // then come out reversed and outside the polygon); 2 and 3 only one strictly inside (for a
  // polygon that touches itself, which has no ear by the first test). 1 and 3 also clip a flat
  // corner (a zero-area triangle; the rest keeps its shape).
  auto isEar = [&](size_t k, int level) {
    const size_t m = ring.size();
    const double* a = q[ring[(k + m - 1) % m]].data();
    const double* b = q[ring[k]].data();
    const double* c = q[ring[(k + 1) % m]].data();
    const double o = Orient(a, b, c);
    const bool allowFlat = (level & 1) != 0;
    if (o < 0 || (o == 0 && !allowFlat)) return false;
    if (o == 0) return true;  // a flat corner: clipping it adds a zero-area triangle and keeps the rest
    auto same = [](const double* x, const double* y) { return x[0] == y[0] && x[1] == y[1]; };
    for (size_t j = 0; j < m; ++j) {
      if (j == k || j == (k + 1) % m || j == (k + m - 1) % m) continue;
      const double* p = q[ring[j]].data();
      const double oab = Orient(a, b, p), obc = Orient(b, c, p), oca = Orient(c, a, p);
      if (oab > 0 && obc > 0 && oca > 0) return false;
      if (level >= 2 || oab < 0 || obc < 0 || oca < 0) continue;
      // p is on the triangle's boundary.
      if (same(p, a) || same(p, b) || same(p, c)) continue;  // a repeated position: nothing is inside
      if (oca == 0) {
        // On the diagonal with both its edges along it (a flat run, as in a convex polygon with
        // a corner on an edge): what remains is flat there, not pinched.
        const double* before = q[ring[(j + m - 1) % m]].data();
        const double* after = q[ring[(j + 1) % m]].data();
        if (Orient(c, a, before) == 0 && Orient(c, a, after) == 0) continue;
      }
      return false;
    }
    return true;
  };
  size_t k = 1, misses = 0;
  int level = 0;
  while (ring.size() > 3) {
    const size_t m = ring.size();
    k %= m;
    if (isEar(k, level)) {
      out.push_back({corners[ring[(k + m - 1) % m]], corners[ring[k]], corners[ring[(k + 1) % m]]});
      ring.erase(ring.begin() + long(k));
      misses = 0;
      level = 0;
    } else if (++misses > m) {
      if (level == 3) return "is a polygon of " + std::to_string(n) + " corners that ear clipping cannot triangulate";
      ++level;
      misses = 0;
    } else {
      ++k;
    }
  }
  out.push_back({corners[ring[0]], corners[ring[1]], corners[ring[2]]});
  return "";
}

namespace {

// A whole number read as a double, for a message: 1e+30 where it is too large to be an integer.
std::string WholeNumber(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.15g", v);
  return text;
}

// An integer of an integer type code at p, in the host's byte order.
int64_t NativeInteger(const char* p, int type) {
  switch (type) {
    case kInt8: {
      int8_t x;
      std::memcpy(&x, p, 1);
      return x;
    }
    case kUint8:
      return uint8_t(*p);
    case kInt16: {
      int16_t x;
      std::memcpy(&x, p, 2);
      return x;
    }
    case kUint16: {
      uint16_t x;
      std::memcpy(&x, p, 2);
      return x;
    }
    case kInt32: {
      int32_t x;
      std::memcpy(&x, p, 4);
      return x;
    }
    default: {
      uint32_t x;
      std::memcpy(&x, p, 4);
      return x;
    }
  }
}

// The binary fast path: records of one size, in the host's byte order, read a block at a time
// side by side. Vertices: scalar properties only, x, y, z float32, no colour, normal or texture
// coordinate; faces: a vertex_indices list of integers and nothing else, every record a
// triangle. stride 0: the element has no such layout.
struct FastLayout {
  size_t stride = 0;
  size_t xyz[3] = {0, 0, 0};  // vertices: the coordinates' offsets
  int countType = 0, indexType = 0;
};
constexpr uint64_t kFastBlock = uint64_t(1) << 16;

// Reads the n records at p (n * stride bytes, in the data) of a face element onto the end of
// `triangles`. False, with `triangles` as it was, when one is not a triangle of vertices below
// `vertices` (the general reader then reads them, and says what is wrong).
bool ReadFastFaces(const char* p, uint64_t n, const FastLayout& f, size_t vertices, unsigned threads,
                   std::vector<std::array<uint32_t, 3>>& triangles) {
  const size_t first = triangles.size();
  triangles.resize(first + size_t(n));
  std::atomic<bool> bad(false);
  const size_t countBytes = size_t(kTypes[f.countType].bytes), indexBytes = size_t(kTypes[f.indexType].bytes);
  ParallelChunks(size_t(n), threads, size_t(1) << 13, [&](size_t begin, size_t end, unsigned) {
    for (size_t i = begin; i < end; ++i) {
      const char* r = p + i * f.stride;
      if (NativeInteger(r, f.countType) != 3) {
        bad = true;
        return;
      }
      for (size_t k = 0; k < 3; ++k) {
        const int64_t v = NativeInteger(r + countBytes + k * indexBytes, f.indexType);
        if (v < 0 || uint64_t(v) >= vertices) {
          bad = true;
          return;
        }
        triangles[first + i][k] = uint32_t(v);
      }
    }
  });
  if (bad) triangles.resize(first);
  return !bad;
}

// ParsePly; with `sink`, the triangles go to it in batches (mesh.triangles holds one batch at most;
// faceQuality and wedgeTexCoords are not kept) and `release` is told every so often how far the
// records have been read.
std::string ParsePlyImpl(const char* data, size_t size, const std::string& name, PlyMesh& mesh,
                         const PlyTriangleSink* sink, const std::function<void(const char*)>* release,
                         unsigned threads) {
  mesh = PlyMesh();
  PlyHeader h;
  std::string err = ParsePlyHeader(data, size, h);
  if (!err.empty()) return "'" + name + "' " + err;
  const std::string file = "'" + name + "': ";
  Cursor in(data + h.headerBytes, data + size, h.encoding);
  bool haveVertices = false, haveFaces = false;
  std::vector<uint32_t> corners;
  for (const PlyElement& e : h.elements) {
    const bool isVertex = e.name == "vertex", isFace = e.name == "face";
    if ((isVertex && haveVertices) || (isFace && haveFaces)) return file + "has two '" + e.name + "' elements";
    int xyz[3] = {-1, -1, -1}, quality = -1, indices = -1, texcoord = -1;
    // Per-vertex attributes: the property's index per channel (-1: absent); what each one fills.
    int colour[4] = {-1, -1, -1, -1}, normal[3] = {-1, -1, -1}, uv[2] = {-1, -1};
    double colourScale = 1;
    for (size_t i = 0; i < e.properties.size(); ++i) {
      const PlyProperty& p = e.properties[i];
      if (isVertex && !p.isList && (p.name == "x" || p.name == "y" || p.name == "z")) xyz[p.name[0] - 'x'] = int(i);
      if (isVertex && !p.isList) {
        static const char* const kColour[2][4] = {{"red", "green", "blue", "alpha"},
                                                  {"diffuse_red", "diffuse_green", "diffuse_blue", "diffuse_alpha"}};
        for (int k = 0; k < 2; ++k)
          for (int c = 0; c < 4; ++c)
            if (p.name == kColour[k][c]) {
              if (colour[c] >= 0)
                return file + "its vertex element has two properties for one colour channel ('" + p.name + "')";
              const double scale = p.type == kUint8 ? 255 : p.type == kUint16 ? 65535 : p.type >= kFloat32 ? 1 : 0;
              if (scale == 0)
                return file + "the vertex colour '" + p.name + "' is a " + kTypes[p.type].name +
                       ": colours are read as uchar, ushort or float";
              if (colour[0] >= 0 || colour[1] >= 0 || colour[2] >= 0 || colour[3] >= 0) {
                if (scale != colourScale)
                  return file + "its vertex colour channels are of different types ('" + p.name + "')";
              }
              colourScale = scale;
              colour[c] = int(i);
            }
        if (p.name == "nx" || p.name == "ny" || p.name == "nz") normal[p.name[1] - 'x'] = int(i);
        if (p.name == "texture_u" || p.name == "s") {
          if (uv[0] >= 0) return file + "its vertex element has both texture_u and s";
          uv[0] = int(i);
        }
        if (p.name == "texture_v" || p.name == "t") {
          if (uv[1] >= 0) return file + "its vertex element has both texture_v and t";
          uv[1] = int(i);
        }
      }
      if (isFace && p.isList && p.name == "texcoord") texcoord = int(i);
      if (isFace && !p.isList && p.name == "quality") quality = int(i);
      if (isFace && p.isList && (p.name == "vertex_indices" || p.name == "vertex_index")) {
        if (indices >= 0)
          return file +
                 "its face element has both a vertex_indices and a vertex_index list (which one holds the "
                 "corners is ambiguous)";
        indices = int(i);
      }
    }
    if (isVertex && (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0))
      return file + "its vertex element lacks one of the x, y, z properties (non-list)";
    if (isFace && indices < 0) return file + "its face element has no vertex_indices list";
    const bool hasColour = colour[0] >= 0 || colour[1] >= 0 || colour[2] >= 0;
    if (isVertex && hasColour && (colour[0] < 0 || colour[1] < 0 || colour[2] < 0))
      return file + "its vertex colour lacks one of red, green, blue";
    const bool hasNormal = normal[0] >= 0 || normal[1] >= 0 || normal[2] >= 0;
    if (isVertex && hasNormal && (normal[0] < 0 || normal[1] < 0 || normal[2] < 0))
      return file + "its vertex normal lacks one of nx, ny, nz";
    const bool hasUv = uv[0] >= 0 || uv[1] >= 0;
    if (isVertex && hasUv && (uv[0] < 0 || uv[1] < 0))
      return file + "its vertex texture coordinates lack one of texture_u/s, texture_v/t";
    if (isVertex && hasColour) {
      mesh.colors.reserve(size_t(e.count));
      mesh.colorAlpha = colour[3] >= 0;
      mesh.colorIsFloat = colourScale == 1;
    }
    if (isVertex && hasNormal) mesh.normals.reserve(size_t(e.count));
    if (isVertex && hasUv) mesh.texCoords.reserve(size_t(e.count));
    if (isFace && texcoord >= 0) mesh.wedgeTexCoords.reserve(size_t(e.count));
    if (isFace && !haveVertices && e.count) return file + "its face element comes before the vertex element";
    if (isVertex) mesh.positions.reserve(size_t(e.count));
    if (isFace) mesh.triangles.reserve(size_t(e.count));
    if (isFace && quality >= 0) mesh.faceQuality.reserve(size_t(e.count));
    std::vector<float> cornerUv;  // this face's texcoord list
    FastLayout fast;
    if (in.native() && isVertex && !hasColour && !hasNormal && !hasUv) {
      bool ok = true;
      for (size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& p = e.properties[i];
        ok = ok && !p.isList;
        for (int c = 0; c < 3; ++c)
          if (int(i) == xyz[c]) {
            ok = ok && p.type == kFloat32;
            fast.xyz[c] = fast.stride;
          }
        fast.stride += size_t(kTypes[p.type].bytes);
      }
      if (!ok) fast.stride = 0;
    }
    if (in.native() && isFace && e.properties.size() == 1 && indices == 0 && e.properties[0].type < kFloat32) {
      fast.countType = e.properties[0].countType;
      fast.indexType = e.properties[0].type;
      fast.stride = size_t(kTypes[fast.countType].bytes + 3 * kTypes[fast.indexType].bytes);
    }
    for (uint64_t r = 0; r < e.count; ++r) {
      if (fast.stride && r % kFastBlock == 0) {  // a block read at once, if its records allow
        const uint64_t n = std::min(kFastBlock, e.count - r);
        bool read = n * fast.stride <= in.left();
        if (read && isVertex) {
          const char* p = in.at();
          const size_t first = mesh.positions.size();
          mesh.positions.resize(first + size_t(n));
          ParallelChunks(size_t(n), threads, size_t(1) << 13, [&](size_t begin, size_t end, unsigned) {
            for (size_t i = begin; i < end; ++i)
              for (int c = 0; c < 3; ++c)
                std::memcpy(&mesh.positions[first + i][size_t(c)], p + i * fast.stride + fast.xyz[c], 4);
          });
        } else if (read) {
          read = ReadFastFaces(in.at(), n, fast, mesh.positions.size(), threads, mesh.triangles);
        }
        if (read) {
          in.skip(size_t(n * fast.stride));
          r += n - 1;
          if (isFace && sink && mesh.triangles.size() >= kStreamBatch) {
            err = (*sink)(mesh.triangles);
            if (!err.empty()) return err;
            mesh.triangles.clear();
          }
          if (release) (*release)(in.at());
          continue;
        }
      }
      std::array<float, 3> pos{{0, 0, 0}};
      std::array<float, 4> rgba{{0, 0, 0, 1}};
      std::array<float, 3> nrm{{0, 0, 0}};
      std::array<float, 2> st{{0, 0}};
      float q = 0;
      for (size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& p = e.properties[i];
        auto rec = [&] { return e.name + " " + std::to_string(r); };  // for messages only
        double v = 0;
        if (!p.isList) {
          if (!in.scalar(p.type, v))
            return file + (in.badToken().empty() ? "ends early, in " + rec()
                                                 : rec() + ": '" + in.badToken() + "' is not a number");
          for (int c = 0; c < 3; ++c)
            if (isVertex && int(i) == xyz[c]) {
              if (std::isfinite(v) && std::fabs(v) > FLT_MAX) {
                char text[32];
                std::snprintf(text, sizeof text, "%g", v);
                return file + rec() + " has a coordinate (" + text + ") beyond single precision (3.4e38)";
              }
              pos[size_t(c)] = float(v);
            }
          if (int(i) == quality) q = float(v);
          if (isVertex)
            for (int c = 0; c < 4; ++c) {
              if (int(i) == colour[c]) rgba[size_t(c)] = float(v / colourScale);
              if (c < 3 && int(i) == normal[c]) nrm[size_t(c)] = float(v);
              if (c < 2 && int(i) == uv[c]) st[size_t(c)] = float(v);
            }
          continue;
        }
        double count = 0;
        if (!in.scalar(p.countType, count))
          return file + (in.badToken().empty() ? "ends early, in " + rec()
                                               : rec() + ": '" + in.badToken() + "' is not a number");
        if (count < 0 || count != std::floor(count))
          return file + rec() + ": a list of " + std::to_string(count) + " items";
        const uint64_t items = uint64_t(count);
        const uint64_t minBytes =
            h.encoding == PlyEncoding::Ascii ? 2 * items - (items ? 1 : 0) : items * uint64_t(kTypes[p.type].bytes);
        if (minBytes > in.left()) return file + "ends early: " + rec() + " lists " + std::to_string(items) + " items";
        const bool isCorners = int(i) == indices, isTexcoord = int(i) == texcoord;
        if (isTexcoord) cornerUv.clear();
        if (isCorners) {
          if (items < 3)
            return file + "face " + std::to_string(r) + " has " + std::to_string(items) +
                   (items == 1 ? " corner" : " corners") + " (a face needs at least 3)";
          if (items > kMaxPolygonCorners)
            return file + "face " + std::to_string(r) + " has " + std::to_string(items) + " corners (at most " +
                   std::to_string(kMaxPolygonCorners) + " are read)";
          corners.clear();
        }
        for (uint64_t k = 0; k < items; ++k) {
          if (!in.scalar(p.type, v))
            return file + (in.badToken().empty() ? "ends early, in " + rec()
                                                 : rec() + ": '" + in.badToken() + "' is not a number");
          if (isTexcoord) cornerUv.push_back(float(v));
          if (!isCorners) continue;
          if (!std::isfinite(v) || v != std::floor(v)) {  // a float index list: 2.7 is no vertex
            char text[32];
            std::snprintf(text, sizeof text, "%g", v);
            return file + "face " + std::to_string(r) + " has the vertex index " + text +
                   ", which is not a whole number";
          }
          if (!(v >= 0 && v < double(mesh.positions.size())))
            return file + "face " + std::to_string(r) + " uses vertex " + WholeNumber(v) + " but there are " +
                   std::to_string(mesh.positions.size()) + " vertices";
          corners.push_back(uint32_t(v));
        }
      }
      if (isVertex) {
        mesh.positions.push_back(pos);
        if (hasColour) mesh.colors.push_back(rgba);
        if (hasNormal) mesh.normals.push_back(nrm);
        if (hasUv) mesh.texCoords.push_back(st);
      }
      if (isFace) {
        if (texcoord >= 0 && cornerUv.size() != 2 * corners.size())
          return file + "face " + std::to_string(r) + " has " + std::to_string(corners.size()) + " corners but " +
                 std::to_string(cornerUv.size()) + " texcoord values (two per corner)";
        if (corners.size() == 3) {
          mesh.triangles.push_back({corners[0], corners[1], corners[2]});
          if (texcoord >= 0)
            mesh.wedgeTexCoords.push_back(
                {{cornerUv[0], cornerUv[1], cornerUv[2], cornerUv[3], cornerUv[4], cornerUv[5]}});
        } else if (texcoord < 0) {
          err = TriangulatePolygon(mesh.positions, corners, mesh.triangles);
          if (!err.empty()) return file + "face " + std::to_string(r) + " " + err;
          ++mesh.polygons;
        } else {
          // Triangulated over the polygon's own corner numbers, so that each triangle corner
          // finds its texture coordinates.
          std::vector<std::array<float, 3>> local(corners.size());
          std::vector<uint32_t> order(corners.size());
          for (size_t k = 0; k < corners.size(); ++k) {
            local[k] = mesh.positions[corners[k]];
            order[k] = uint32_t(k);
          }
          std::vector<std::array<uint32_t, 3>> pieces;
          err = TriangulatePolygon(local, order, pieces);
          if (!err.empty()) return file + "face " + std::to_string(r) + " " + err;
          for (const auto& t : pieces) {
            mesh.triangles.push_back({corners[t[0]], corners[t[1]], corners[t[2]]});
            std::array<float, 6> w;
            for (size_t k = 0; k < 3; ++k) {
              w[2 * k] = cornerUv[2 * t[k]];
              w[2 * k + 1] = cornerUv[2 * t[k] + 1];
            }
            mesh.wedgeTexCoords.push_back(w);
          }
          ++mesh.polygons;
        }
        if (sink) {
          mesh.wedgeTexCoords.clear();
          if (mesh.triangles.size() >= kStreamBatch) {
            err = (*sink)(mesh.triangles);
            if (!err.empty()) return err;
            mesh.triangles.clear();
          }
        } else if (quality >= 0) {
          mesh.faceQuality.resize(mesh.triangles.size(), q);
        }
      }
      if (release && (r & 0xFFFF) == 0) (*release)(in.at());
    }
    if (isFace && sink && !mesh.triangles.empty()) {
      err = (*sink)(mesh.triangles);
      if (!err.empty()) return err;
      mesh.triangles.clear();
    }
    haveVertices |= isVertex;
    haveFaces |= isFace;
  }
  if (!haveVertices) return file + "has no vertex element";
  mesh.textureFiles = h.textureFiles;
  return "";
}

}  // namespace

std::string ParsePly(const char* data, size_t size, const std::string& name, PlyMesh& mesh) {
  return ParsePlyImpl(data, size, name, mesh, nullptr, nullptr, 1);
}

std::string ReadPly(const std::string& path, PlyMesh& mesh, bool* ioError, unsigned threads) {
  return ReadPlyStreaming(path, mesh, nullptr, ioError, threads);
}

std::string ReadPlyStreaming(const std::string& path, PlyMesh& mesh, const PlyTriangleSink& sink, bool* ioError,
                             unsigned threads) {
  if (ioError) *ioError = false;
  auto fail = [&](const std::string& what) {
    if (ioError) *ioError = true;
    return "cannot read '" + path + "': " + what;
  };
  const std::string notRegular = CheckInputPath(path);  // before open(): opening a FIFO blocks
  if (!notRegular.empty()) {
    if (ioError) *ioError = true;
    return notRegular;
  }
  // O_NONBLOCK: should the path have become a FIFO since, open() returns and fstat() refuses it.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return fail(std::strerror(errno));
  struct stat st;
  if (fstat(fd, &st) != 0) {
    const int e = errno;
    ::close(fd);
    return fail(std::strerror(e));
  }
  if (S_ISDIR(st.st_mode)) {
    ::close(fd);
    return fail("it is a folder");
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    return fail("not a regular file");
  }
  const size_t size = size_t(st.st_size);
  if (size == 0) {
    ::close(fd);
    if (ioError) *ioError = false;
    return "'" + path + "' is empty";
  }
  void* map = mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
  const int mapErrno = errno;
  ::close(fd);
  if (map == MAP_FAILED) return fail(std::strerror(mapErrno));
  // Streaming: the pages read are dropped as the records go by, so that the mapped file does not
  // stay resident (it would count in the process's memory).
  const char* base = static_cast<const char*>(map);
  const size_t page = size_t(::sysconf(_SC_PAGESIZE));
  size_t dropped = 0;
  const std::function<void(const char*)> release = [&](const char* at) {
    const size_t upTo = size_t(at - base) / page * page;
    if (upTo > dropped + (size_t(2) << 20)) {
      ::madvise(const_cast<char*>(base) + dropped, upTo - dropped, MADV_DONTNEED);
      dropped = upTo;
    }
  };
  std::string err =
      ParsePlyImpl(base, size, path, mesh, sink ? &sink : nullptr, sink ? &release : nullptr, std::max(1u, threads));
  munmap(map, size);
  return err;
}

}  // namespace conelod
