// ConeLOD — PLY in and out of a vcg mesh: reading through the checked reader (ply_format.h) and
// writing through vcglib's exporter into a SafeFile (safe_file.h), checked to be complete before
// it replaces the target.
#pragma once

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/complex.h>
#include <wrap/io_trimesh/export_ply.h>
#include <wrap/io_trimesh/io_mask.h>

#include "conelod/mesh/indexed_mesh.h"
#include "conelod/mesh/ply_format.h"
#include "conelod/mesh/safe_file.h"

namespace conelod {

// Messages of a file that could not be opened or read (rather than a malformed one) start with this.
inline bool IsReadFailure(const std::string& message) { return message.compare(0, 13, "cannot read '") == 0; }

// The IOM_ bits of the attributes a mesh keeps from its file (what commands that write a mesh pass on).
inline int AttributeMask(int loadMask) {
  return loadMask & (vcg::tri::io::Mask::IOM_VERTCOLOR | vcg::tri::io::Mask::IOM_VERTNORMAL |
                     vcg::tri::io::Mask::IOM_VERTTEXCOORD | vcg::tri::io::Mask::IOM_WEDGTEXCOORD);
}

// A colour channel read as [0, 1] (PlyMesh) as the byte a vcg mesh keeps.
inline unsigned char ColorByte(float c) {
  return (unsigned char)std::lround(std::min(1.0f, std::max(0.0f, c)) * 255.0f);
}

// vcg's IOM_ bits of what `in` holds (coordinates, face indices, face quality, the attributes),
// for a mesh type with per-vertex colour, normal and texture coordinates; `wedge`: its per-face
// texture coordinates were split into per-vertex ones (SplitWedgeTexCoords).
inline int PlyLoadMask(const PlyMesh& in, bool wedge) {
  using vcg::tri::io::Mask;
  return Mask::IOM_VERTCOORD | Mask::IOM_FACEINDEX | (in.faceQuality.empty() ? 0 : Mask::IOM_FACEQUALITY) |
         (in.colors.empty() ? 0 : Mask::IOM_VERTCOLOR) | (in.normals.empty() ? 0 : Mask::IOM_VERTNORMAL) |
         (in.texCoords.empty() ? 0
          : wedge              ? Mask::IOM_WEDGTEXCOORD
                               : Mask::IOM_VERTTEXCOORD);
}

// Per-face texture coordinates as per-vertex ones: each (vertex, u, v) of a corner becomes a vertex
// (a vertex with one pair of coordinates stays one vertex; a texture seam's vertices are repeated
// with their coordinates). New vertices are numbered by their original vertex, then (u, v); a
// vertex no face uses is kept with (0, 0).
inline void SplitWedgeTexCoords(PlyMesh& in) {
  struct Corner {
    uint32_t vertex;
    float u, v;
    size_t at;
  };
  std::vector<Corner> corners;
  corners.reserve(3 * in.triangles.size());
  for (size_t f = 0; f < in.triangles.size(); ++f)
    for (size_t k = 0; k < 3; ++k)
      corners.push_back({in.triangles[f][k], in.wedgeTexCoords[f][2 * k], in.wedgeTexCoords[f][2 * k + 1], 3 * f + k});
  std::sort(corners.begin(), corners.end(), [](const Corner& a, const Corner& b) {
    if (a.vertex != b.vertex) return a.vertex < b.vertex;
    if (a.u != b.u) return a.u < b.u;
    if (a.v != b.v) return a.v < b.v;
    return a.at < b.at;
  });
  PlyMesh out;
  out.triangles = in.triangles;
  out.faceQuality = std::move(in.faceQuality);
  out.polygons = in.polygons;
  out.colorAlpha = in.colorAlpha;
  out.colorIsFloat = in.colorIsFloat;
  out.textureFiles = std::move(in.textureFiles);
  auto addVertex = [&](uint32_t v, float u, float t) {
    out.positions.push_back(in.positions[v]);
    if (!in.colors.empty()) out.colors.push_back(in.colors[v]);
    if (!in.normals.empty()) out.normals.push_back(in.normals[v]);
    out.texCoords.push_back({{u, t}});
  };
  size_t i = 0;
  for (uint32_t v = 0; v < in.positions.size(); ++v) {
    if (i == corners.size() || corners[i].vertex != v) {
      addVertex(v, 0, 0);
      continue;
    }
    while (i < corners.size() && corners[i].vertex == v) {
      const size_t first = i;
      addVertex(v, corners[i].u, corners[i].v);
      const uint32_t id = uint32_t(out.positions.size() - 1);
      while (i < corners.size() && corners[i].vertex == v && corners[i].u == corners[first].u &&
             corners[i].v == corners[first].v)
        out.triangles[corners[i].at / 3][corners[i].at % 3] = id, ++i;
    }
  }
  in = std::move(out);
}

// Replaces `m` by the mesh in `path` (ReadPly). `loadMask` gets vcg's IOM_ bits of what was read
// (coordinates, face indices, and IOM_FACEQUALITY when the faces had a quality; IOM_VERTCOLOR,
// IOM_VERTNORMAL, IOM_VERTTEXCOORD or IOM_WEDGTEXCOORD for the attributes the file has and the
// mesh type holds; per-face texture coordinates are split into per-vertex ones,
// SplitWedgeTexCoords, and m.textures gets the file's texture names). "" or the error; `m` is
// untouched on error.
template <class MeshType>
void MeshFromPlyData(const PlyMesh& in, bool wedge, MeshType& m, int* loadMask = nullptr);

template <class MeshType>
std::string LoadPlyChecked(MeshType& m, const std::string& path, int* loadMask = nullptr) {
  using VertexType = typename MeshType::VertexType;
  PlyMesh in;
  std::string err = ReadPly(path, in);
  if (!err.empty()) return err;
  const bool wedge = !in.wedgeTexCoords.empty() && VertexType::HasTexCoord();
  if (wedge) SplitWedgeTexCoords(in);
  MeshFromPlyData(in, wedge, m, loadMask);
  return "";
}

// The part of LoadPlyChecked after the reading: `m` becomes the mesh of `in` (its per-face texture
// coordinates already split, SplitWedgeTexCoords, when `wedge`), `loadMask` gets its bits. For
// commands that read with LoadPlyData and need the vcg mesh in some cases only.
template <class MeshType>
void MeshFromPlyData(const PlyMesh& in, bool wedge, MeshType& m, int* loadMask) {
  using VertexType = typename MeshType::VertexType;
  m.Clear();
  auto vi = vcg::tri::Allocator<MeshType>::AddVertices(m, in.positions.size());
  for (const auto& p : in.positions) (vi++)->P() = typename MeshType::CoordType(p[0], p[1], p[2]);
  int attributeBits = 0;
  if (!in.colors.empty() && VertexType::HasColor()) {
    for (size_t v = 0; v < in.colors.size(); ++v) {
      unsigned char c[4];
      for (size_t k = 0; k < 4; ++k) c[k] = ColorByte(in.colors[v][k]);
      m.vert[v].C() = vcg::Color4b(c[0], c[1], c[2], c[3]);
    }
    attributeBits |= vcg::tri::io::Mask::IOM_VERTCOLOR;
  }
  if (!in.normals.empty() && VertexType::HasNormal()) {
    for (size_t v = 0; v < in.normals.size(); ++v)
      m.vert[v].N() = typename VertexType::NormalType(in.normals[v][0], in.normals[v][1], in.normals[v][2]);
    attributeBits |= vcg::tri::io::Mask::IOM_VERTNORMAL;
  }
  if (!in.texCoords.empty() && VertexType::HasTexCoord()) {
    for (size_t v = 0; v < in.texCoords.size(); ++v) {
      m.vert[v].T().U() = in.texCoords[v][0];
      m.vert[v].T().V() = in.texCoords[v][1];
      m.vert[v].T().N() = 0;
    }
    attributeBits |= wedge ? vcg::tri::io::Mask::IOM_WEDGTEXCOORD : vcg::tri::io::Mask::IOM_VERTTEXCOORD;
    m.textures = in.textureFiles;
  }
  auto fi = vcg::tri::Allocator<MeshType>::AddFaces(m, in.triangles.size());
  for (size_t f = 0; f < in.triangles.size(); ++f, ++fi) {
    for (int k = 0; k < 3; ++k) fi->V(k) = &m.vert[in.triangles[f][size_t(k)]];
    if (!in.faceQuality.empty() && MeshType::FaceType::HasQuality()) fi->Q() = in.faceQuality[f];
  }
  vcg::tri::UpdateBounding<MeshType>::Box(m);  // as vcglib's importer leaves it
  if (loadMask)
    *loadMask = vcg::tri::io::Mask::IOM_VERTCOORD | vcg::tri::io::Mask::IOM_FACEINDEX |
                (in.faceQuality.empty() ? 0 : vcg::tri::io::Mask::IOM_FACEQUALITY) | attributeBits;
}

// Reads `path` as LoadPlyChecked does for a mesh type with per-vertex colour, normal and texture
// coordinates (CMesh), without building the vcg mesh (`simplify` works on the indexed mesh and
// builds a vcg mesh of its output only, SimplifiedMeshFromPly): `in` holds what that mesh would
// (per-face texture coordinates split into per-vertex ones), `loadMask` gets LoadPlyChecked's bits.
// "" or the error.
inline std::string LoadPlyData(const std::string& path, PlyMesh& in, int* loadMask = nullptr) {
  std::string err = ReadPly(path, in);
  if (!err.empty()) return err;
  const bool wedge = !in.wedgeTexCoords.empty();
  if (wedge) SplitWedgeTexCoords(in);
  if (loadMask) *loadMask = PlyLoadMask(in, wedge);
  return "";
}

// `m` = what ApplySimplifiedMesh (vcg_bridge.h) leaves of LoadPlyChecked's mesh of the file `in`
// was read from (after SplitWedgeTexCoords, as LoadPlyChecked does), built from the simplified mesh
// alone, so that the whole input need not be kept as a vcg mesh: the input vertices `sourceVertex`
// lists (an input vertex per vertex of `simplified`, distinct) at their new positions with their
// colour, normal and texture coordinates, in input order; the input faces `sourceFace` lists, in
// input order, with their quality and `simplified`'s corners. `in.positions` and `in.triangles`
// are not read (they may have been freed).
template <class MeshType>
void SimplifiedMeshFromPly(const PlyMesh& in, const IndexedMesh& simplified, const std::vector<uint32_t>& sourceFace,
                           const std::vector<uint32_t>& sourceVertex, MeshType& m) {
  using VertexType = typename MeshType::VertexType;
  m.Clear();
  std::vector<std::pair<uint32_t, uint32_t>> byInput(sourceVertex.size());  // input vertex, simplified vertex
  for (size_t o = 0; o < sourceVertex.size(); ++o) byInput[o] = {sourceVertex[o], uint32_t(o)};
  std::sort(byInput.begin(), byInput.end());
  std::vector<uint32_t> at(sourceVertex.size());
  auto vi = vcg::tri::Allocator<MeshType>::AddVertices(m, byInput.size());
  const bool colour = !in.colors.empty() && VertexType::HasColor();
  const bool normal = !in.normals.empty() && VertexType::HasNormal();
  const bool tex = !in.texCoords.empty() && VertexType::HasTexCoord();
  for (size_t j = 0; j < byInput.size(); ++j, ++vi) {
    const uint32_t v = byInput[j].first, o = byInput[j].second;
    at[o] = uint32_t(j);
    const auto& p = simplified.positions[o];
    vi->P() = typename MeshType::CoordType(p[0], p[1], p[2]);
    if (colour) {
      const auto& c = in.colors[v];
      vi->C() = vcg::Color4b(ColorByte(c[0]), ColorByte(c[1]), ColorByte(c[2]), ColorByte(c[3]));
    }
    if (normal) vi->N() = typename VertexType::NormalType(in.normals[v][0], in.normals[v][1], in.normals[v][2]);
    if (tex) {
      vi->T().U() = in.texCoords[v][0];
      vi->T().V() = in.texCoords[v][1];
      vi->T().N() = 0;
    }
  }
  if (tex) m.textures = in.textureFiles;
  std::vector<uint32_t> order(sourceFace.size());
  for (size_t o = 0; o < order.size(); ++o) order[o] = uint32_t(o);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return sourceFace[a] < sourceFace[b]; });
  auto fi = vcg::tri::Allocator<MeshType>::AddFaces(m, order.size());
  for (size_t j = 0; j < order.size(); ++j, ++fi) {
    const uint32_t o = order[j];
    for (size_t k = 0; k < 3; ++k) fi->V(int(k)) = &m.vert[at[simplified.faces[o][k]]];
    if (!in.faceQuality.empty() && MeshType::FaceType::HasQuality()) fi->Q() = in.faceQuality[sourceFace[o]];
  }
}

// Writes `m` as binary PLY (vcglib's exporter, `mask` as for ExporterPLY::Save) into `out`'s
// temporary file for `path`, checks it and syncs it (SafeFile::sync): `out.commit()` then puts it
// in place. vcglib does not check its writes, so the temporary file's size is checked against its
// own header; when vcglib reports a write error the system's reason is given ("No space left on
// device", "File too large"). "" or the error; `path` is untouched on error.
template <class MeshType>
std::string WritePlyUncommitted(MeshType& m, const std::string& path, int mask, SafeFile& out) {
  std::string err = out.open(path);
  if (!err.empty()) return err;
  const std::string& temp = out.ReleaseForWriter();
  errno = 0;
  const int e = vcg::tri::io::ExporterPLY<MeshType>::Save(m, temp.c_str(), mask, true);
  const int writeErrno = errno;
  if (e != 0) {
    out.discard();
    const bool streamError = e == vcg::ply::E_STREAMERROR && writeErrno != 0;
    return "cannot write '" + path + "': " +
           (streamError ? std::string(std::strerror(writeErrno)) : vcg::tri::io::ExporterPLY<MeshType>::ErrorMsg(e));
  }
  std::FILE* f = std::fopen(temp.c_str(), "rb");
  if (!f) return "cannot write '" + path + "': the written file cannot be read back";
  std::vector<char> head(1 << 16);
  const size_t n = std::fread(head.data(), 1, head.size(), f);
  std::fseek(f, 0, SEEK_END);
  const long size = std::ftell(f);
  std::fclose(f);
  PlyHeader h;
  if (size < 0 || !ParsePlyHeader(head.data(), n, h, uint64_t(size)).empty() || PlyTriangleFileBytes(h) == 0 ||
      uint64_t(size) < PlyTriangleFileBytes(h))
    return "cannot write '" + path + "': the file came out incomplete (disk full or file size limit?)";
  return out.sync();
}

// Whether SavePlyFaceValues can write `in` with `attributeMask`: it holds no texture coordinates
// (those go through vcglib's exporter) and every attribute the mask names.
inline bool PlyFaceValuesWritable(const PlyMesh& in, int attributeMask) {
  using vcg::tri::io::Mask;
  if (!in.texCoords.empty() || !in.wedgeTexCoords.empty() ||
      (attributeMask & (Mask::IOM_VERTTEXCOORD | Mask::IOM_WEDGTEXCOORD)))
    return false;
  if ((attributeMask & Mask::IOM_VERTCOLOR) && in.colors.size() != in.positions.size()) return false;
  if ((attributeMask & Mask::IOM_VERTNORMAL) && in.normals.size() != in.positions.size()) return false;
  return true;
}

// Writes the mesh `in` (as LoadPlyData gives it; PlyFaceValuesWritable) to `path` with per-face
// colour valueColor[faceValue[f]] and quality valueQuality[faceValue[f]]: the same bytes as SavePly
// (vcg_mesh.h) writes for LoadPlyChecked's mesh of the same file with those face colours and
// qualities and extra mask `attributeMask` (AttributeMask of its load mask: vertex colours and
// normals), without building that mesh: vcglib's header, then its binary records (vertex: x y z
// [nx ny nz] [r g b a]; face: 3, three int indices, r g b a, float quality), formatted here into
// a buffer rather than one fwrite a field. Replaces `path` only when the file is complete
// (SafeFile). "" or the error.
inline std::string SavePlyFaceValues(const PlyMesh& in, int attributeMask, const std::vector<int>& faceValue,
                                     const std::vector<vcg::Color4b>& valueColor,
                                     const std::vector<float>& valueQuality, const std::string& path) {
  using vcg::tri::io::Mask;
  if (!PlyFaceValuesWritable(in, attributeMask) || faceValue.size() != in.triangles.size())
    return "cannot write '" + path + "': the mesh does not match its attributes (an internal error)";
  const bool normals = attributeMask & Mask::IOM_VERTNORMAL, colours = attributeMask & Mask::IOM_VERTCOLOR;
  if (in.positions.size() > size_t(std::numeric_limits<int>::max()) ||
      in.triangles.size() > size_t(std::numeric_limits<int>::max()))
    return "cannot write '" + path + "': too many vertices or faces for a PLY of 32-bit indices";
  for (const int v : faceValue)
    if (v < 0 || size_t(v) >= valueColor.size() || size_t(v) >= valueQuality.size())
      return "cannot write '" + path + "': a face value out of range (an internal error)";
  SafeFile out;
  std::string err = out.open(path);
  if (!err.empty()) return err;
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment VCGLIB generated\nelement vertex " +
                       std::to_string(in.positions.size()) + "\nproperty float x\nproperty float y\nproperty float z\n";
  if (normals) header += "property float nx\nproperty float ny\nproperty float nz\n";
  if (colours) header += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
  header += "element face " + std::to_string(in.triangles.size()) +
            "\nproperty list uchar int vertex_indices\nproperty uchar red\nproperty uchar green\nproperty uchar "
            "blue\nproperty uchar alpha\nproperty float quality\nend_header\n";
  std::FILE* f = out.file();
  std::fwrite(header.data(), 1, header.size(), f);
  // Records are little-endian floats and ints as in memory (vcglib writes them so; x86 and ARM).
  std::vector<unsigned char> buffer;
  constexpr size_t kBufferBytes = size_t(1) << 20;
  buffer.reserve(kBufferBytes + 64);
  auto put = [&](const void* p, size_t n) {
    const unsigned char* b = static_cast<const unsigned char*>(p);
    buffer.insert(buffer.end(), b, b + n);
  };
  auto flush = [&](bool always) {
    if (buffer.size() >= kBufferBytes || (always && !buffer.empty())) {
      std::fwrite(buffer.data(), 1, buffer.size(), f);
      buffer.clear();
    }
  };
  for (size_t v = 0; v < in.positions.size(); ++v) {
    put(in.positions[v].data(), 12);
    if (normals) put(in.normals[v].data(), 12);
    if (colours) {
      const unsigned char c[4] = {ColorByte(in.colors[v][0]), ColorByte(in.colors[v][1]), ColorByte(in.colors[v][2]),
                                  ColorByte(in.colors[v][3])};
      put(c, 4);
    }
    flush(false);
  }
  for (size_t t = 0; t < in.triangles.size(); ++t) {
    unsigned char record[21];
    record[0] = 3;
    for (size_t k = 0; k < 3; ++k) {
      const int32_t index = int32_t(in.triangles[t][k]);
      std::memcpy(record + 1 + 4 * k, &index, 4);
    }
    const vcg::Color4b& c = valueColor[size_t(faceValue[t])];
    for (int k = 0; k < 4; ++k) record[13 + k] = c[k];
    std::memcpy(record + 17, &valueQuality[size_t(faceValue[t])], 4);
    put(record, sizeof record);
    flush(false);
  }
  flush(true);
  return out.commit();  // flushes and checks the stream (a short write: "No space left on device")
}

// WritePlyUncommitted, then the temporary file replaces `path`. "" or the error.
template <class MeshType>
std::string SavePlySafely(MeshType& m, const std::string& path, int mask) {
  SafeFile out;
  const std::string err = WritePlyUncommitted(m, path, mask, out);
  return err.empty() ? out.commit() : err;
}

}  // namespace conelod
