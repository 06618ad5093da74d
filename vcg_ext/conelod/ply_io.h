// ConeLOD — PLY in and out of a vcg mesh: reading through the checked reader (ply_format.h) and
// writing through vcglib's exporter into a SafeFile (safe_file.h), checked to be complete before
// it replaces the target.
#pragma once

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/complex.h>
#include <wrap/io_trimesh/export_ply.h>
#include <wrap/io_trimesh/io_mask.h>

#include "conelod/mesh/ply_format.h"
#include "conelod/mesh/safe_file.h"

namespace conelod {

// Messages of a file that could not be opened or read (rather than a malformed one) start with this.
inline bool IsReadFailure(const std::string& message) { return message.compare(0, 13, "cannot read '") == 0; }

// Replaces `m` by the mesh in `path` (ReadPly). `loadMask` gets vcg's IOM_ bits of what was read
// (coordinates, face indices, and IOM_FACEQUALITY when the faces had a quality). "" or the error;
// `m` is untouched on error.
template <class MeshType>
std::string LoadPlyChecked(MeshType& m, const std::string& path, int* loadMask = nullptr) {
  PlyMesh in;
  std::string err = ReadPly(path, in);
  if (!err.empty()) return err;
  m.Clear();
  auto vi = vcg::tri::Allocator<MeshType>::AddVertices(m, in.positions.size());
  for (const auto& p : in.positions) (vi++)->P() = typename MeshType::CoordType(p[0], p[1], p[2]);
  auto fi = vcg::tri::Allocator<MeshType>::AddFaces(m, in.triangles.size());
  for (size_t f = 0; f < in.triangles.size(); ++f, ++fi) {
    for (int k = 0; k < 3; ++k) fi->V(k) = &m.vert[in.triangles[f][size_t(k)]];
    if (!in.faceQuality.empty() && MeshType::FaceType::HasQuality()) fi->Q() = in.faceQuality[f];
  }
  vcg::tri::UpdateBounding<MeshType>::Box(m);  // as vcglib's importer leaves it
  if (loadMask)
    *loadMask = vcg::tri::io::Mask::IOM_VERTCOORD | vcg::tri::io::Mask::IOM_FACEINDEX |
                (in.faceQuality.empty() ? 0 : vcg::tri::io::Mask::IOM_FACEQUALITY);
  return "";
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

// WritePlyUncommitted, then the temporary file replaces `path`. "" or the error.
template <class MeshType>
std::string SavePlySafely(MeshType& m, const std::string& path, int mask) {
  SafeFile out;
  const std::string err = WritePlyUncommitted(m, path, mask, out);
  return err.empty() ? out.commit() : err;
}

}  // namespace conelod
