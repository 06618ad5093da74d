// ConeLOD — a checked PLY reader: the one door every mesh of the command-line tool and the tests
// comes in by (the plugin gets its mesh from MeshLab).
//
// PLY (Turk, "The PLY Polygon File Format") is a text header that declares elements (vertex, face,
// ...) with counts and typed properties, followed by the records in ASCII or binary (little or
// big endian). A hostile or broken header can claim any count; this reader checks every count and
// every list length against the bytes actually left in the file *before* allocating, so a 200-byte
// file can never ask for gigabytes, and it never reads past the end of the file.
//
// Read: ASCII, binary little and big endian; vertex x, y, z of any numeric type (double is
// rounded to float, the tool's precision); per-face `quality` when present; the attributes a scan
// carries (PlyMesh): per-vertex colour (red green blue [alpha], or diffuse_red ...; uchar, ushort
// or float), normals (nx ny nz), texture coordinates (texture_u texture_v, or s t), per-face
// `texcoord` lists (two floats a corner) and the `comment TextureFile NAME` lines of the header
// (as MeshLab writes them); faces as
// `vertex_indices` (or `vertex_index`) lists of any count and index type. Every other property
// and element is skipped. Faces with more than three corners are triangulated by ear clipping in
// their own plane (a convex polygon gives the fan from its first corner, as vcglib does); a
// polygon whose edges cross is refused by name, as is a face with fewer than three corners or an
// index outside the vertex array. What would have to be guessed is refused too: a property
// declared twice in one element, a face element with both vertex_indices and vertex_index, a
// fractional index in a float index list. OBJ, OFF, STL and gzip files are recognised and refused
// with "only PLY is read". ReadPly refuses a path that is not a regular file (a FIFO, a device)
// before opening it (CheckInputPath, safe_file.h).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace conelod {

enum class PlyEncoding { Ascii, BinaryLittleEndian, BinaryBigEndian };

struct PlyProperty {
  std::string name;
  int type = 0;       // a scalar type code (see ply_format.cpp); for a list, of its items
  int countType = 0;  // lists only: the type of the item count
  bool isList = false;
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::Ascii;
  std::vector<PlyElement> elements;
  std::vector<std::string> textureFiles;  // `comment TextureFile NAME` lines, in order
  size_t headerBytes = 0;                 // up to and including the end_header line
};

// Parses and checks the header of the `size` bytes at `data`: "" or what is wrong. Checks that
// every element's records can fit in the bytes after the header (exactly for fixed-size binary
// records, a lower bound with lists or ASCII).
// `fileBytes`: the whole file's size when `data` holds only its beginning (0: `size`).
std::string ParsePlyHeader(const char* data, size_t size, PlyHeader& header, uint64_t fileBytes = 0);

// The bytes a binary file with this header has when every list is a triangle (what the tool and
// vcglib's exporter write): used to check that a written file is complete. 0 for ASCII.
uint64_t PlyTriangleFileBytes(const PlyHeader& header);

// A mesh as read: positions, triangles, per-face quality and the attributes the file has (every
// attribute vector is empty when the file lacks it).
struct PlyMesh {
  std::vector<std::array<float, 3>> positions;
  std::vector<std::array<uint32_t, 3>> triangles;
  std::vector<float> faceQuality;  // per triangle (a polygon's triangles share its value), or empty
  size_t polygons = 0;             // faces with more than three corners (triangulated)
  // Per vertex: RGBA in [0, 1] (uchar / 255, ushort / 65535, float as is; alpha 1 when absent).
  std::vector<std::array<float, 4>> colors;
  bool colorAlpha = false;                      // the file has an alpha channel
  bool colorIsFloat = false;                    // stored as float or double (else as integers)
  std::vector<std::array<float, 3>> normals;    // per vertex, as stored (not renormalised)
  std::vector<std::array<float, 2>> texCoords;  // per vertex (texture_u texture_v, or s t)
  // Per triangle: u, v of its three corners (a face's `texcoord` list; a polygon's triangles take
  // the values of their corners).
  std::vector<std::array<float, 6>> wedgeTexCoords;
  std::vector<std::string> textureFiles;  // `comment TextureFile NAME`, in order
  bool hasAttributes() const {
    return !colors.empty() || !normals.empty() || !texCoords.empty() || !wedgeTexCoords.empty();
  }
};

// Reads `path`. "" or a message that names the file and what is wrong with it; `ioError` is set
// when the file could not be opened or read (as opposed to a malformed file). Binary records in
// the host's byte order (positions only, triangles only) are read a block at a time on `threads`
// threads; the result and the messages do not depend on their number.
std::string ReadPly(const std::string& path, PlyMesh& mesh, bool* ioError = nullptr, unsigned threads = 1);
// ReadPly without the faces in memory: the triangles are handed to `sink` in batches of about
// kStreamBatch (in the file's order, polygons triangulated as ReadPly does; mesh.triangles is then
// empty, faceQuality and wedgeTexCoords are not kept) and the file's pages are released from
// memory as they are read. The vertex element is held as ReadPly holds it. The sink returns "" or
// a message that stops the reading (returned as it is). Null sink: ReadPly.
using PlyTriangleSink = std::function<std::string(const std::vector<std::array<uint32_t, 3>>&)>;
constexpr size_t kStreamBatch = size_t(1) << 16;
std::string ReadPlyStreaming(const std::string& path, PlyMesh& mesh, const PlyTriangleSink& sink,
                             bool* ioError = nullptr, unsigned threads = 1);
// The same from bytes in memory (the fuzzer's entry point); `name` is used in messages.
std::string ParsePly(const char* data, size_t size, const std::string& name, PlyMesh& mesh);

// Triangulates the polygon `corners` (indices into `positions`) by ear clipping in its plane,
// appending triangles to `out`: for a simple polygon every triangle lies inside it with its
// orientation (or has no area). "" or why it cannot (its edges cross).
std::string TriangulatePolygon(const std::vector<std::array<float, 3>>& positions, const std::vector<uint32_t>& corners,
                               std::vector<std::array<uint32_t, 3>>& out);

}  // namespace conelod
