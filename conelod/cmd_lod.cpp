// ConeLOD CLI — `conelod lod`: build the streamable .clod LOD file, extract a view-dependent cut of
// it, describe it (Kamiya, Suzuki, Kawachi §7-9; vcg_ext/conelod/lod/).
#include <cctype>
#include <cerrno>
#include <csignal>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include <unistd.h>

#include "cli_common.h"
#include "commands.h"
#include "conelod/grouping/group_colors.h"
#include "conelod/lod/lod_build.h"
#include "conelod/lod/lod_read.h"
#include "conelod/lod/lod_spill.h"
#include "conelod/mesh/mesh_check.h"
#include "conelod/mesh/ply_format.h"
#include "conelod/mesh/safe_file.h"

namespace conelod {
namespace cli {
namespace {

// "colour, normals, texture coordinates" (those the streams have).
std::string AttributeNames(const LodAttributes& a) {
  std::string s;
  auto add = [&](const char* what) { s += (s.empty() ? "" : ", ") + std::string(what); };
  if (!a.colors.empty()) add("colour");
  if (!a.normals.empty()) add("normals");
  if (!a.texCoords.empty()) add("texture coordinates");
  return s;
}

bool ParsePoint(const std::string& text, vcg::Point3d& p) {
  double v[3];
  const char* s = text.c_str();
  for (int i = 0; i < 3; ++i) {
    char* end = nullptr;
    v[i] = std::strtod(s, &end);
    if (end == s || !std::isfinite(v[i])) return false;
    s = end;
    if (i < 2) {
      if (*s != ',') return false;
      ++s;
    }
  }
  if (*s) return false;
  p = vcg::Point3d(v[0], v[1], v[2]);
  return true;
}

// The folder part of a path ("" for a bare name), with its final slash.
std::string FolderOf(const std::string& path) {
  const size_t slash = path.rfind('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

// A whole file's bytes; false when it cannot be read (a missing texture image).
bool ReadFileBytes(const std::string& path, std::vector<uint8_t>& out) {
  out.clear();
  if (!CheckInputPath(path).empty()) return false;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  uint8_t buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) out.insert(out.end(), buf, buf + n);
  const bool ok = !std::ferror(f);
  std::fclose(f);
  return ok;
}

// --memory SIZE: a whole number of bytes, or one followed by K, M, G or T (powers of 1024).
bool ParseMemory(const std::string& text, uint64_t& bytes) {
  size_t i = 0;
  uint64_t n = 0;
  for (; i < text.size() && text[i] >= '0' && text[i] <= '9'; ++i) {
    if (n > (uint64_t(1) << 50)) return false;
    n = n * 10 + uint64_t(text[i] - '0');
  }
  if (i == 0) return false;
  int shift = 0;
  if (i + 1 == text.size()) {
    const char* units = "KMGT";
    const char* u = std::strchr(units, std::toupper(static_cast<unsigned char>(text[i])));
    if (!u || !*u) return false;
    shift = 10 * int(u - units + 1);
  } else if (i != text.size()) {
    return false;
  }
  if (n > (uint64_t(1) << (62 - shift))) return false;
  bytes = n << shift;
  return true;
}

int LodBuild(int argc, char** argv) {
  Args a(argc, argv,
         With(kGroupingOptions, {"-o", "--level-ratio", "--threads", "--faces-per-part", "--cluster-faces",
                                 "--group-clusters", "--quality-thr", "--boundary-weight", "--precision", "--memory",
                                 "--attribute-weight", "--refresh-ratio"}),
         {"--json", "--strict-greedy", "--no-optimal-placement", "--preserve-boundary", "--no-preserve-normal",
          "--no-attributes"});
  LodBuildParams params;
  params.grouping = ReadGroupingParams(a);
  params.simplification.levelRatio = a.num("--level-ratio", params.simplification.levelRatio);
  // The collapse options of every group (those of conelod simplify and of the Export LOD File filter).
  GroupQemParams& qem = params.simplification.qem;
  qem.qualityThr = a.num("--quality-thr", qem.qualityThr);
  qem.boundaryWeight = a.num("--boundary-weight", qem.boundaryWeight);
  qem.optimalPlacement = !a.has("--no-optimal-placement");
  qem.preserveBoundary = a.has("--preserve-boundary");
  qem.preserveNormal = !a.has("--no-preserve-normal");
  params.refreshRatio = a.num("--refresh-ratio", params.refreshRatio);
  if (!(params.refreshRatio >= 0 && params.refreshRatio < 1)) return Fail(kUsage, "--refresh-ratio must be in [0, 1)");
  const double clusterFaces = a.num("--cluster-faces", double(params.clusterFaces));
  const double groupClusters = a.num("--group-clusters", double(params.groupClusters));
  if (!(clusterFaces >= 4 && clusterFaces <= 65536) || clusterFaces != std::floor(clusterFaces))
    return Fail(kUsage, "--cluster-faces must be a whole number in [4, 65536]");
  if (!(groupClusters >= 2 && groupClusters <= 64) || groupClusters != std::floor(groupClusters))
    return Fail(kUsage, "--group-clusters must be a whole number in [2, 64]");
  params.precision = a.num("--precision", params.precision);
  if (!(params.precision >= kMinLodPrecision && params.precision <= kMaxLodPrecision))
    return Fail(kUsage, "--precision must be in [1e-9, 0.01] (a fraction of the diagonal)");
  params.clusterFaces = size_t(clusterFaces);
  params.groupClusters = int(groupClusters);
  params.attributeWeight = a.num("--attribute-weight", params.attributeWeight);
  if (!(params.attributeWeight >= 0) || !std::isfinite(params.attributeWeight))
    return Fail(kUsage, "--attribute-weight must be >= 0");
  const bool keepAttributes = !a.has("--no-attributes");
  // Without --memory the DAG is built whole, as the Export LOD File filter builds it: the file
  // does not depend on the machine. The chunks and the streamed read lower the peak but do not
  // bound it yet (docs/scale.md).
  uint64_t memory = 0;
  if (a.has("--memory")) {
    if (!ParseMemory(a.str("--memory"), memory))
      return Fail(kUsage, "--memory must be a size like 512M or 2G (bytes, or K, M, G, T: powers of 1024)");
    if (memory < kLodMinMemoryBytes)  // a size, but too small: bad input, nothing written
      return Fail(kBadInput, "--memory " + a.str("--memory") + " is below the minimum budget, " +
                                 std::to_string(kLodMinMemoryBytes >> 20) + "M");
    params.chunkFaces = LodChunkFacesForMemory(memory);
  }
  const std::string partsError = ReadPartsOptions(a, params.simplification);
  if (!a.ok()) return Fail(kUsage, a.error() + "\n" + kLodUsage);
  if (!partsError.empty()) return Fail(kUsage, partsError);
  if (a.positional().size() != 1 || !a.has("-o"))
    return Fail(kUsage, std::string("expected IN.ply and -o OUT.clod\n") + kLodUsage);
  const double ratio = params.simplification.levelRatio;
  if (!(ratio > 0 && ratio < 1)) return Fail(kUsage, "--level-ratio must be in (0, 1)");
  const std::string input = a.positional()[0], output = a.str("-o");
  // Read straight into the indexed mesh (the same positions and faces as LoadInput's, without its
  // vcglib mesh: about 100 bytes a face less at the peak).
  IndexedMesh im;
  LodAttributes attributes;  // per-vertex colour, normals and UVs, carried into the file (versions 5, 6)
  std::string textureNote;   // why the texture image is not stored, when it is not
  Timer timer;
  // --memory with more faces than one chunk, geometry only: the PLY is read streaming and its faces
  // go to chunk files (BuildLodFileFromPly): neither the input's faces nor level 0 are held whole.
  bool vertexAttributes = false;
  const bool streamed = params.chunkFaces > 0 && PlyFaceCount(input, &vertexAttributes) > params.chunkFaces &&
                        (!vertexAttributes || !keepAttributes);
  if (!streamed) {
    PlyMesh ply;
    const std::string err = ReadPly(input, ply, nullptr, unsigned(SimplificationThreads(params.simplification)));
    if (!err.empty()) return FailLoad(err);
    if (keepAttributes && !ply.wedgeTexCoords.empty())
      SplitWedgeTexCoords(ply);  // per-face texcoord lists: one vertex per (vertex, UV)
    if (keepAttributes) {
      attributes.colors.reserve(ply.colors.size());
      for (const auto& c : ply.colors) {
        std::array<uint8_t, 4> q;
        for (size_t i = 0; i < 4; ++i) q[i] = uint8_t(std::lround(std::min(1.f, std::max(0.f, c[i])) * 255.f));
        attributes.colors.push_back(q);
      }
      attributes.normals.reserve(ply.normals.size());
      for (const auto& n : ply.normals) attributes.normals.push_back(EncodeLodNormal(vcg::Point3f(n[0], n[1], n[2])));
      if (!ply.texCoords.empty()) {
        // The UV box of the used vertices; the coordinates as u16 codes over it.
        std::vector<uint8_t> used(ply.texCoords.size(), 0);
        for (const auto& t : ply.triangles)
          for (uint32_t v : t)
            if (v < used.size()) used[v] = 1;
        bool any = false;
        for (size_t v = 0; v < ply.texCoords.size(); ++v) {
          if (!used[v]) continue;
          for (int c = 0; c < 2; ++c) {
            const float x = ply.texCoords[v][size_t(c)];
            if (!std::isfinite(x))
              return Fail(kBadInput, input + ": vertex " + std::to_string(v) + " has a non-finite texture coordinate");
            attributes.uvMin[c] = any ? std::min(attributes.uvMin[c], x) : x;
            attributes.uvMax[c] = any ? std::max(attributes.uvMax[c], x) : x;
          }
          any = true;
        }
        attributes.texCoords.reserve(ply.texCoords.size());
        for (const auto& t : ply.texCoords)
          attributes.texCoords.push_back(EncodeLodTexCoord(t.data(), attributes.uvMin, attributes.uvMax));
        // The texture image beside the input, stored in the file as it is.
        if (ply.textureFiles.empty()) {
          textureNote = "the file names no texture image (comment TextureFile)";
        } else {
          const std::string& named = ply.textureFiles[0];
          const std::string base =
              named.substr(named.find_last_of("/\\") == std::string::npos ? 0 : named.find_last_of("/\\") + 1);
          const std::string at = named.size() && named[0] == '/' ? named : FolderOf(input) + named;
          LodTexture& tex = attributes.texture;
          if (!CheckLodTextureName(base).empty()) {
            textureNote = "its texture name '" + named + "' is not a plain file name";
          } else if (!ReadFileBytes(at, tex.bytes) || tex.bytes.empty()) {
            tex.bytes.clear();
            textureNote = "cannot read its texture image '" + at + "'";
          } else {
            tex.name = base;
            tex.mime = LodTextureMime(base, tex.bytes);
          }
          if (ply.textureFiles.size() > 1)
            std::fprintf(stderr, "conelod: %s: %zu texture images named; only the first, %s, is stored\n",
                         input.c_str(), ply.textureFiles.size(), named.c_str());
        }
      }
    }
    im.positions.reserve(ply.positions.size());
    for (const auto& p : ply.positions) im.positions.emplace_back(p[0], p[1], p[2]);
    std::vector<std::array<float, 3>>().swap(ply.positions);
    im.faces.swap(ply.triangles);
  }
  const double loadSeconds = streamed ? 0.0 : timer.seconds();
  Status s = ValidateParams(params.grouping);
  if (!s.ok()) return Fail(kUsage, s.message);
  if (!streamed) s = RequireValidForFaces(im);
  if (!s.ok()) return Fail(kBadInput, input + ": " + s.message);
  if (!textureNote.empty())
    std::fprintf(stderr, "conelod: %s: texture coordinates are stored without the image: %s\n", input.c_str(),
                 textureNote.c_str());
  LodBuildStats st;
  size_t inputVertices = im.vertexCount();
  // The mesh is handed over (welded in place, it becomes the DAG's level 0). An interrupted build
  // removes its temporary folder (--memory) before it ends as the signal would end it.
  struct SpillSignals {
    SpillSignals() {
      for (int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, &SpillSignals::Handle);
    }
    ~SpillSignals() {
      for (int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, SIG_DFL);
    }
    static void Handle(int sig) {
      RemoveLodSpillsOnSignal();
      std::signal(sig, SIG_DFL);
      std::raise(sig);
    }
  };
  {
    SpillSignals handlers;
    if (streamed) {
#ifdef __GLIBC__
      // Blocks of 256 KiB and more are mapped on their own, so that what a stage frees goes back to
      // the system rather than staying in the heap for the next stage (glibc raises its threshold as
      // large blocks are freed, and a heap only shrinks from its top): the bound of --memory is on
      // the process's resident memory.
      mallopt(M_MMAP_THRESHOLD, 256 * 1024);
#endif
      std::string readError;
      s = BuildLodFileFromPly(input, params, output, &st, Progress(), &readError);
      if (!readError.empty()) return FailLoad(readError);
      inputVertices = st.inputVertices + st.mergedVertices + st.droppedVertices;  // as the file has them
    } else {
      s = BuildLodFile(std::move(im), params, output, &st, Progress(), attributes.empty() ? nullptr : &attributes);
    }
  }
  if (!s.ok() && s.message.compare(0, 14, "cannot write '") == 0) return Fail(kIoError, s.message);
  if (!s.ok()) return Fail(kBadInput, input + ": " + s.message);
  if (a.has("--json")) {
    Json j;
    j.BeginObject()
        .field("input", input)
        .field("output", output)
        .field("vertices", inputVertices)
        .field("welded_vertices", st.mergedVertices)         // merged into another at the same position
        .field("unreferenced_vertices", st.droppedVertices)  // left out
        .field("faces", st.inputFaces)
        .field("levels", st.levels)
        .field("nodes", st.nodes)
        .field("memory_bytes", size_t(memory))
        .field("chunks", st.chunks)
        .field("file_bytes", size_t(st.fileBytes))
        .field("record_bytes", size_t(st.recordBytes))
        .field("position_bytes", size_t(st.positionBytes))
        .field("triangle_bytes", size_t(st.triangleBytes))
        .field("vertex_id_bytes", size_t(st.vertexIdBytes))
        .field("color_bytes", size_t(st.colorBytes))
        .field("normal_bytes", size_t(st.normalBytes))
        .field("texcoord_bytes", size_t(st.texCoordBytes))
        .field("texture_bytes", size_t(st.textureBytes))
        .field("texture", attributes.texture.name)
        .field("attributes", AttributeNames(attributes))
        .field("attribute_conflicts", st.attributeConflicts)
        .field("quantization_error", st.quantizationError)
        .field("load_seconds", loadSeconds)
        .field("grouping_seconds", st.groupingSeconds)
        .field("simplify_seconds", st.simplifySeconds)
        .field("write_seconds", st.writeSeconds)
        .field("seconds", st.seconds);
    j.key("level_faces").BeginArray();
    for (size_t f : st.levelFaces) j.value(f);
    j.endArray().key("level_nodes").BeginArray();
    for (size_t n : st.levelNodes) j.value(n);
    j.endArray().EndObject();
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf(
        "%s: %zu faces -> %s: %d node levels, %zu nodes, %llu bytes in %.3f s "
        "(grouping %.3f s, simplification %.3f s, writing %.3f s)\n",
        input.c_str(), st.inputFaces, output.c_str(), st.levels, st.nodes, (unsigned long long)st.fileBytes, st.seconds,
        st.groupingSeconds, st.simplifySeconds, st.writeSeconds);
    std::printf(
        "%.2f bytes per input face: records %llu, positions %llu, triangles %llu, vertex ids %llu bytes; "
        "positions within %.3g of the input (%.3g of the diagonal)\n",
        double(st.fileBytes) / double(st.inputFaces), (unsigned long long)st.recordBytes,
        (unsigned long long)st.positionBytes, (unsigned long long)st.triangleBytes,
        (unsigned long long)st.vertexIdBytes, st.quantizationError, params.precision);
    if (!attributes.texCoords.empty())
      std::printf("texture coordinates: %llu bytes (16 bits over the UV box, within %.2g)%s%s%s\n",
                  (unsigned long long)st.texCoordBytes, LodTexCoordErrorBound(attributes.uvMin, attributes.uvMax),
                  attributes.texture.empty() ? "" : ("; texture " + attributes.texture.name + ", ").c_str(),
                  attributes.texture.empty() ? "" : std::to_string(st.textureBytes).c_str(),
                  attributes.texture.empty() ? "" : " bytes");
    if (!attributes.colors.empty() || !attributes.normals.empty())
      std::printf(
          "attributes: %s%s%s, %llu + %llu bytes (colour, normals; normals within %.2g rad)%s\n",
          attributes.colors.empty() ? "" : "colour",
          !attributes.colors.empty() && !attributes.normals.empty() ? ", " : "",
          attributes.normals.empty() ? "" : "normals", (unsigned long long)st.colorBytes,
          (unsigned long long)st.normalBytes, kLodNormalErrorBound,
          st.attributeConflicts
              ? (", " + std::to_string(st.attributeConflicts) + " welded vertices took another's values").c_str()
              : "");
    if (st.chunks > 1)
      std::printf("built in %zu spatial chunks of at most %zu faces (--memory %lluM)\n", st.chunks, params.chunkFaces,
                  (unsigned long long)(memory >> 20));
    if (st.mergedVertices || st.droppedVertices)
      std::printf("vertices at one position welded: %zu; unreferenced vertices left out: %zu\n", st.mergedVertices,
                  st.droppedVertices);
    std::printf("%5s %8s %10s\n", "level", "nodes", "faces");
    for (int k = st.levels - 1; k >= 0; --k)
      std::printf("%5d %8zu %10zu\n", k, st.levelNodes[size_t(k)], st.levelFaces[size_t(k)]);
  }
  return kOk;
}

int LodExtract(int argc, char** argv) {
  Args a(argc, argv, {"-o", "--eye", "--budget", "--priority"}, {"--json", "--no-cull", "--drop-culled"});
  if (!a.ok()) return Fail(kUsage, a.error() + "\n" + kLodUsage);
  if (a.positional().size() != 1) return Fail(kUsage, std::string("expected one .clod file\n") + kLodUsage);
  if (!a.has("--eye") || !a.has("--budget")) return Fail(kUsage, std::string("give --eye and --budget\n") + kLodUsage);
  LodView view;
  if (!ParsePoint(a.str("--eye"), view.eye)) return Fail(kUsage, "--eye must be X,Y,Z (three numbers)");
  const std::string budget = a.str("--budget");
  bool percent = !budget.empty() && budget.back() == '%';
  char* end = nullptr;
  const double b = std::strtod(budget.c_str(), &end);
  if (end == budget.c_str() || *end != (percent ? '%' : '\0') || !(b >= 0) || !std::isfinite(b) || (percent && b > 100))
    return Fail(kUsage, "--budget must be a face count N >= 0 or a percentage P% (0-100)");
  view.cullBackFacing = !a.has("--no-cull");
  if (a.has("--priority")) {
    const std::string p = a.str("--priority");
    if (p == "screen")
      view.priority = LodPriority::ScreenError;
    else if (p == "error")
      view.priority = LodPriority::ObjectError;
    else if (p == "fg")
      view.priority = LodPriority::ConeFg;
    else
      return Fail(kUsage, "--priority must be screen, error or fg");
  }
  const bool drop = a.has("--drop-culled");
  const std::string input = a.positional()[0];

  const std::string notRegular = CheckInputPath(input, true);  // a FIFO would block the open
  if (!notRegular.empty()) return Fail(kIoError, notRegular);
  Timer timer;
  std::unique_ptr<LodReader> reader;
  Status s = LodReader::Open(input, reader);
  if (!s.ok()) return Fail(kBadInput, s.message);
  const double openSeconds = timer.seconds();
  view.faceBudget = percent ? size_t(std::floor(double(reader->info().inputFaces) * b / 100.0)) : size_t(b);
  LodCut cut;
  s = RefineLod(*reader, view, cut);
  if (!s.ok()) return Fail(kBadInput, input + ": " + s.message);
  const size_t resident = reader->residentBytes();
  IndexedMesh out;
  std::vector<int> faceLevel;
  LodAttributes attributes;
  s = ExtractCutMesh(*reader, cut, !drop, out, &faceLevel, nullptr, &attributes);
  if (!s.ok()) return Fail(kBadInput, input + ": " + s.message);
  const double seconds = timer.seconds();

  if (a.has("-o")) {
    CMesh m;
    AppendIndexedMesh(m, out);
    for (size_t f = 0; f < m.face.size(); ++f) {
      m.face[f].Q() = float(faceLevel[f]);
      m.face[f].C() = GroupColor(faceLevel[f]);
    }
    // The file's attributes per vertex (AppendIndexedMesh keeps the vertex order).
    int mask = 0;
    if (!attributes.colors.empty()) {
      mask |= vcg::tri::io::Mask::IOM_VERTCOLOR;
      for (size_t v = 0; v < m.vert.size(); ++v) {
        const auto& c = attributes.colors[v];
        m.vert[v].C() = vcg::Color4b(c[0], c[1], c[2], c[3]);
      }
    }
    if (!attributes.normals.empty()) {
      mask |= vcg::tri::io::Mask::IOM_VERTNORMAL;
      for (size_t v = 0; v < m.vert.size(); ++v) m.vert[v].N() = DecodeLodNormal(attributes.normals[v]);
    }
    // Texture coordinates: per face corner (`texcoord` lists, as MeshLab writes them), the image
    // beside the output under its stored name (`comment TextureFile NAME`). An existing file of that
    // name is left as it is: kept when it holds the same bytes, else the command stops before
    // writing anything.
    SafeFile textureOut;
    std::string texturePath;
    if (!attributes.texCoords.empty()) {
      mask |= vcg::tri::io::Mask::IOM_WEDGTEXCOORD;
      for (size_t v = 0; v < m.vert.size(); ++v) {
        float uv[2];
        DecodeLodTexCoord(attributes.texCoords[v], attributes.uvMin, attributes.uvMax, uv);
        m.vert[v].T().U() = uv[0];
        m.vert[v].T().V() = uv[1];
        m.vert[v].T().N() = 0;
      }
      if (reader->info().textureBytes) {
        LodTexture tex;
        s = reader->LoadTexture(tex);
        if (!s.ok()) return Fail(kBadInput, input + ": " + s.message);
        m.textures.push_back(tex.name);
        texturePath = FolderOf(a.str("-o")) + tex.name;
        std::vector<uint8_t> existing;
        if (CheckInputPath(texturePath).empty() || access(texturePath.c_str(), F_OK) == 0) {
          if (!ReadFileBytes(texturePath, existing) || existing != tex.bytes)
            return Fail(kIoError, "'" + texturePath + "' exists and is not the texture image stored in " + input +
                                      ": it is left as it is and nothing was written (move it away, or write -o "
                                      "into another folder)");
          texturePath.clear();  // the same image is there already
        } else {
          std::string err = textureOut.open(texturePath);
          if (err.empty() && std::fwrite(tex.bytes.data(), 1, tex.bytes.size(), textureOut.file()) != tex.bytes.size())
            err = "cannot write '" + texturePath + "': " + std::strerror(errno);
          if (err.empty()) err = textureOut.sync();
          if (!err.empty()) return Fail(kIoError, err);
        }
      }
    }
    SafeFile meshOut;
    std::string err = SavePlyUncommitted(m, a.str("-o"), meshOut, mask);
    if (err.empty() && !texturePath.empty()) err = textureOut.commit();
    if (err.empty()) err = meshOut.commit();
    if (!err.empty()) return Fail(kIoError, err);
  }
  const int levels = reader->info().levels;
  std::vector<size_t> levelFaces(size_t(levels), 0), levelNodes(size_t(levels), 0);
  for (size_t i = 0; i < cut.nodes.size(); ++i) {
    const LodNode& n = reader->node(cut.nodes[i]);
    levelFaces[size_t(n.level)] += n.faceCount;
    ++levelNodes[size_t(n.level)];
  }
  if (a.has("--json")) {
    Json j;
    j.BeginObject()
        .field("input", input)
        .field("faces", out.faces.size())
        .field("cut_faces", cut.faces)
        .field("budget", view.faceBudget)
        .field("groups_drawn", cut.groupsDrawn)
        .field("groups_culled", cut.groupsCulled)
        .field("culled_faces", cut.faces - cut.drawnFaces)
        .field("max_level_difference", cut.maxLevelDifference)
        .field("refinements", cut.refinements)
        .field("resident_bytes", resident)
        .field("open_seconds", openSeconds)
        .field("seconds", seconds);
    j.key("levels").BeginArray();
    for (int k = 0; k < levels; ++k)
      j.BeginObject()
          .field("level", k)
          .field("nodes", levelNodes[size_t(k)])
          .field("faces", levelFaces[size_t(k)])
          .EndObject();
    j.endArray();
    if (a.has("-o")) j.field("output", a.str("-o"));
    j.EndObject();
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf(
        "%s: cut of %zu faces (budget %zu), %zu groups drawn, %zu culled, max level difference %d, "
        "%zu bytes resident, %.3f s\n",
        input.c_str(), cut.faces, view.faceBudget, cut.groupsDrawn, cut.groupsCulled, cut.maxLevelDifference, resident,
        seconds);
    std::printf("%5s %8s %10s\n", "level", "nodes", "faces");
    for (int k = levels - 1; k >= 0; --k)
      std::printf("%5d %8zu %10zu\n", k, levelNodes[size_t(k)], levelFaces[size_t(k)]);
    if (a.has("-o"))
      std::printf("wrote %s: %zu faces (quality and colour = node level)\n", a.str("-o").c_str(), out.faces.size());
    if (a.has("-o") && reader->info().textureBytes)
      std::printf("its texture: %s%s\n", (FolderOf(a.str("-o")) + reader->info().textureName).c_str(),
                  " (beside it; comment TextureFile)");
  }
  return kOk;
}

int LodInfo(int argc, char** argv) {
  Args a(argc, argv, {}, {"--json"});
  if (!a.ok()) return Fail(kUsage, a.error() + "\n" + kLodUsage);
  if (a.positional().size() != 1) return Fail(kUsage, std::string("expected one .clod file\n") + kLodUsage);
  const std::string notRegular = CheckInputPath(a.positional()[0], true);  // a FIFO would block the open
  if (!notRegular.empty()) return Fail(kIoError, notRegular);
  Timer timer;
  std::unique_ptr<LodReader> reader;
  Status s = LodReader::Open(a.positional()[0], reader);
  if (!s.ok()) return Fail(kBadInput, s.message);
  const double seconds = timer.seconds();
  const LodFileInfo& i = reader->info();
  if (a.has("--json")) {
    Json j;
    j.BeginObject()
        .field("input", a.positional()[0])
        .field("version", int(i.version))
        .field("vertices", size_t(i.inputVertices))
        .field("faces", size_t(i.inputFaces))
        .field("levels", i.levels)
        .field("nodes", size_t(i.nodeCount))
        .field("file_bytes", size_t(i.fileBytes))
        .field("roots", reader->roots().size())
        .field("grid_bits", int(i.grid.bits))
        .field("colors", i.colors)
        .field("normals", i.normals)
        .field("texcoords", i.texCoords)
        .field("texture", i.textureName)
        .field("texture_mime", i.textureMime)
        .field("texture_bytes", size_t(i.textureBytes))
        .field("quantization_error", i.quantizationError);
    if (i.texCoords) {
      j.key("uv_min").BeginArray().precise(i.uvMin[0]).precise(i.uvMin[1]).endArray();
      j.key("uv_max").BeginArray().precise(i.uvMax[0]).precise(i.uvMax[1]).endArray();
      j.field("texcoord_error", LodTexCoordErrorBound(i.uvMin, i.uvMax));
    }
    // The grid exactly: a script can round positions as the file does (lod_read.h, LodGrid).
    j.key("grid_step").precise(i.grid.step);
    j.key("grid_origin").BeginArray();
    for (double o : i.grid.origin) j.precise(o);
    j.endArray();
    j.field("resident_bytes", reader->residentBytes()).field("open_seconds", seconds);
    j.key("level_faces").BeginArray();
    for (auto f : i.levelFaces) j.value(size_t(f));
    j.endArray().key("level_nodes").BeginArray();
    for (auto n : i.levelNodes) j.value(size_t(n));
    j.endArray().EndObject();
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("%s: .clod version %u, %llu vertices, %llu faces, %d node levels, %llu nodes, %llu bytes\n",
                a.positional()[0].c_str(), i.version, (unsigned long long)i.inputVertices,
                (unsigned long long)i.inputFaces, i.levels, (unsigned long long)i.nodeCount,
                (unsigned long long)i.fileBytes);
    std::printf("positions on a %u-bit grid of step %.6g: within %.6g of the DAG's\n", i.grid.bits, i.grid.step,
                i.quantizationError);
    if (i.colors || i.normals)
      std::printf("attributes per vertex: %s%s%s\n", i.colors ? "colour (RGBA8)" : "",
                  i.colors && i.normals ? ", " : "", i.normals ? "normals (octahedral 2 x 16 bits)" : "");
    if (i.texCoords)
      std::printf("texture coordinates per vertex: 2 x 16 bits over u %.6g..%.6g, v %.6g..%.6g (within %.3g)\n",
                  i.uvMin[0], i.uvMax[0], i.uvMin[1], i.uvMax[1], LodTexCoordErrorBound(i.uvMin, i.uvMax));
    if (i.textureBytes)
      std::printf("texture image: %s (%s), %llu bytes\n", i.textureName.c_str(), i.textureMime.c_str(),
                  (unsigned long long)i.textureBytes);
    std::printf("opened in %.4f s, %zu bytes resident (roots and their geometry)\n", seconds, reader->residentBytes());
    std::printf("%5s %8s %10s\n", "level", "nodes", "faces");
    for (int k = i.levels - 1; k >= 0; --k)
      std::printf("%5d %8llu %10llu\n", k, (unsigned long long)i.levelNodes[size_t(k)],
                  (unsigned long long)i.levelFaces[size_t(k)]);
  }
  return kOk;
}

}  // namespace

const char* kLodUsage =
    "conelod lod build IN.ply -o OUT.clod [--threshold T] [--growth F] [--level-ratio R] [--cluster-faces C]\n"
    "                  [--group-clusters G] [collapse options] [--threads N] [--precision E] [--memory SIZE]\n"
    "                  [--attribute-weight W] [--no-attributes] [--json]\n"
    "conelod lod extract IN.clod --eye X,Y,Z --budget N|P% -o OUT.ply [--priority screen|error|fg]\n"
    "                  [--no-cull] [--drop-culled] [--json]\n"
    "conelod lod info IN.clod [--json]\n"
    "  build: writes the streamable .clod file (format: vcg_ext/conelod/lod/lod_format.md), a DAG of\n"
    "  clusters whose every cut is watertight: the input is cut into clusters of about C faces\n"
    "  [128] whose normals stay within --threshold T degrees [15] (x --growth F [1.6] per level,\n"
    "  at most 90), G [12] neighbouring clusters are gathered into a group (24 on the levels\n"
    "  above 3/8 of the input's faces, 64 on those of them with 32 x 64 x C faces or more,\n"
    "  24 on the others with 8 x 24 x C faces or more, 6 on those under 4 x G x C faces), each\n"
    "  group is simplified to R x its faces [0.5] (on the levels of at most 3/8 of the input's\n"
    "  faces: at least 0.6 x) with its border locked, on --threads N threads\n"
    "  [0: one per core], and re-cut into the next level's clusters; at the top each connected\n"
    "  part is simplified as one group. Collapse options (as conelod simplify's, defaults in\n"
    "  brackets): --quality-thr Q [0.3] --no-optimal-placement --preserve-boundary\n"
    "  --boundary-weight W [1] --no-preserve-normal; --refresh-ratio R [0.8]: a group's collapse\n"
    "  builds its quadrics again from its surface each time it is down to R of its faces (0: once).\n"
    "  Positions are quantized on one grid: none moves by more than E x the diagonal [5e-6];\n"
    "  the nodes' vertices and triangles are compressed (meshoptimizer's codecs).\n"
    "  --memory SIZE (512M, 2G; at least 16M): an input of more than SIZE / 2048 faces is split\n"
    "  into spatial chunks of at most that many faces, each built with its border locked until\n"
    "  neighbouring chunks merge; each finished level goes to a temporary folder beside OUT\n"
    "  (removed at the end, also on failure or Ctrl-C) and the file is written from there. Such an\n"
    "  input (without colour or normals, or with --no-attributes) is read streaming into one file\n"
    "  per chunk and every level is built chunk by chunk from the one below in that folder; its\n"
    "  positions stay in memory\n"
    "  (docs/scale.md gives the peaks).\n"
    "  Without it the DAG is built whole, in memory.\n"
    "  Per-vertex colour, normals and texture coordinates (per vertex or per face corner) of\n"
    "  IN.ply are carried into every level (interpolated as in conelod simplify,\n"
    "  --attribute-weight W [1]; texture seams kept) and stored per node (colour exact as RGBA8,\n"
    "  normals within 1e-4 rad, UVs as 16 bits over their box), with the texture image its\n"
    "  `comment TextureFile` names (read beside IN.ply, stored as it is: the .clod moves as one\n"
    "  file); --no-attributes: geometry only. File version 9 (versions 3 to 8 are still read).\n"
    "  The file does not depend on N. The other grouping options and --faces-per-part are\n"
    "  accepted for compatibility and not used.\n"
    "  extract: opens the file, refines for a perspective eye at X,Y,Z under a budget of N faces\n"
    "  (or P% of the input's), expanding first the groups whose error (in model units) divided by\n"
    "  their distance to the eye is largest (--priority error: wherever the eye is, the groups\n"
    "  whose expansion removes the most squared error per face it adds; fg: the paper's f(g)),\n"
    "  back-facing groups last (--no-cull: no back-face test); every cut is crack-free.\n"
    "  Writes the cut as OUT.ply with per-face quality = node level (0 = the input's faces) and a\n"
    "  colour per level, and the file's vertex colours, normals and texture coordinates (per face\n"
    "  corner); the texture image is written beside OUT.ply (`comment TextureFile NAME`), never\n"
    "  over a different file of that name. --drop-culled leaves the back-facing groups out.\n";

int CmdLod(int argc, char** argv) {
  if (argc < 1) return Fail(kUsage, std::string("expected build, extract or info\n") + kLodUsage);
  const std::string sub = argv[0];
  if (sub == "build") return LodBuild(argc - 1, argv + 1);
  if (sub == "extract") return LodExtract(argc - 1, argv + 1);
  if (sub == "info") return LodInfo(argc - 1, argv + 1);
  return Fail(kUsage, "unknown lod command '" + sub + "'\n" + kLodUsage);
}

}  // namespace cli
}  // namespace conelod
