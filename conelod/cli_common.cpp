// ConeLOD CLI — shared helpers (see cli_common.h).
#include "cli_common.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <utility>

#include "conelod/mesh/safe_file.h"

namespace conelod {
namespace cli {

Args::Args(int argc, char** argv, const std::vector<std::string>& valueOptions,
           const std::vector<std::string>& flagOptions) {
  auto contains = [](const std::vector<std::string>& v, const std::string& s) {
    for (const auto& x : v)
      if (x == s) return true;
    return false;
  };
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.size() > 1 && a[0] == '-' && !(a.size() > 1 && (std::isdigit((unsigned char)a[1]) || a[1] == '.'))) {
      if (contains(flagOptions, a)) {
        values_[a] = "1";
      } else if (contains(valueOptions, a)) {
        if (i + 1 >= argc) {
          error_ = "option " + a + " needs a value";
          return;
        }
        values_[a] = argv[++i];
      } else {
        error_ = "unknown option " + a;
        return;
      }
    } else {
      positional_.push_back(a);
    }
  }
}

std::string Args::str(const std::string& name, const std::string& def) const {
  auto it = values_.find(name);
  return it == values_.end() ? def : it->second;
}

double Args::num(const std::string& name, double def) {
  auto it = values_.find(name);
  if (it == values_.end()) return def;
  char* end = nullptr;
  const double v = std::strtod(it->second.c_str(), &end);
  if (end == it->second.c_str() || *end != '\0' || !std::isfinite(v)) {
    if (error_.empty()) error_ = "option " + name + " expects a number, got '" + it->second + "'";
    return def;
  }
  return v;
}

int Args::integer(const std::string& name, int def) {
  auto it = values_.find(name);
  if (it == values_.end()) return def;
  char* end = nullptr;
  const long v = std::strtol(it->second.c_str(), &end, 10);
  if (end == it->second.c_str() || *end != '\0' || v < -2147483647L || v > 2147483647L) {
    if (error_.empty()) error_ = "option " + name + " expects an integer, got '" + it->second + "'";
    return def;
  }
  return int(v);
}

void Json::separator() {
  if (afterKey_) {
    afterKey_ = false;
    return;
  }
  if (!first_.back()) out_ += ",";
  first_.back() = false;
}

Json& Json::key(const std::string& k) {
  separator();
  out_ += "\"" + k + "\":";
  afterKey_ = true;
  return *this;
}

Json& Json::precise(double v) {
  separator();
  if (!std::isfinite(v)) {
    out_ += "null";
    return *this;
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  out_ += buf;
  return *this;
}

Json& Json::value(double v) {
  separator();
  if (!std::isfinite(v)) {
    out_ += "null";
    return *this;
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  out_ += buf;
  return *this;
}

Json& Json::value(long long v) {
  separator();
  out_ += std::to_string(v);
  return *this;
}

Json& Json::value(bool v) {
  separator();
  out_ += v ? "true" : "false";
  return *this;
}

Json& Json::value(const std::string& v) {
  separator();
  out_ += "\"";
  for (char c : v) {
    if (c == '"' || c == '\\') {
      out_ += '\\';
      out_ += c;
    } else if ((unsigned char)c < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", c);
      out_ += b;
    } else
      out_ += c;
  }
  out_ += "\"";
  return *this;
}

Json& Json::BeginObject() {
  separator();
  out_ += "{";
  first_.push_back(true);
  return *this;
}
Json& Json::EndObject() {
  out_ += "}";
  first_.pop_back();
  return *this;
}
Json& Json::BeginArray() {
  separator();
  out_ += "[";
  first_.push_back(true);
  return *this;
}
Json& Json::endArray() {
  out_ += "]";
  first_.pop_back();
  return *this;
}

std::string LoadInput(const std::string& path, CMesh& mesh, IndexedMesh& indexed, std::vector<size_t>& faceOfIndex,
                      int* loadMask) {
  const std::string err = LoadPly(mesh, path, loadMask);
  if (!err.empty()) return err;
  indexed = ToIndexedMesh(mesh, &faceOfIndex);
  return "";
}

VertexAttributes AttributesOf(const PlyMesh& ply, int loadMask) {
  using vcg::tri::io::Mask;
  VertexAttributes a;
  const bool colour = (loadMask & Mask::IOM_VERTCOLOR) && !ply.colors.empty();
  bool alpha = false;
  if (colour)
    for (const auto& c : ply.colors) alpha |= ColorByte(c[3]) != 255;
  a.colorChannels = colour ? (alpha ? 4 : 3) : 0;
  a.normals = (loadMask & Mask::IOM_VERTNORMAL) && !ply.normals.empty();
  a.texCoords = (loadMask & (Mask::IOM_VERTTEXCOORD | Mask::IOM_WEDGTEXCOORD)) && !ply.texCoords.empty();
  if (a.empty()) return a;
  const size_t n = std::max({ply.colors.size(), ply.normals.size(), ply.texCoords.size()});  // the vertex count
  a.values.reserve(n * size_t(a.channels()));
  for (size_t v = 0; v < n; ++v) {
    for (int c = 0; c < a.colorChannels; ++c) a.values.push_back(ColorByte(ply.colors[v][size_t(c)]) / 255.0f);
    if (a.normals)
      for (size_t c = 0; c < 3; ++c) a.values.push_back(ply.normals[v][c]);
    if (a.texCoords) {
      a.values.push_back(ply.texCoords[v][0]);
      a.values.push_back(ply.texCoords[v][1]);
    }
  }
  return a;
}

std::vector<float> CornerAttributes(const std::vector<std::array<uint32_t, 3>>& triangles,
                                    const VertexAttributes& perVertex) {
  const size_t C = size_t(perVertex.channels());
  std::vector<float> corner;
  corner.reserve(3 * triangles.size() * C);
  for (const auto& t : triangles)
    for (size_t k = 0; k < 3; ++k) {
      const float* v = perVertex.of(t[k]);
      corner.insert(corner.end(), v, v + C);
    }
  return corner;
}

VertexAttributes AttributesOf(const CMesh& mesh, int loadMask) {
  using vcg::tri::io::Mask;
  VertexAttributes a;
  const bool colour = loadMask & Mask::IOM_VERTCOLOR;
  bool alpha = false;
  if (colour)
    for (const auto& v : mesh.vert) alpha |= !v.IsD() && v.cC()[3] != 255;
  a.colorChannels = colour ? (alpha ? 4 : 3) : 0;
  a.normals = loadMask & Mask::IOM_VERTNORMAL;
  a.texCoords = loadMask & (Mask::IOM_VERTTEXCOORD | Mask::IOM_WEDGTEXCOORD);
  if (a.empty()) return a;
  a.values.reserve(size_t(mesh.vn) * size_t(a.channels()));
  for (const auto& v : mesh.vert) {
    if (v.IsD()) continue;
    for (int c = 0; c < a.colorChannels; ++c) a.values.push_back(v.cC()[c] / 255.0f);
    if (a.normals)
      for (int c = 0; c < 3; ++c) a.values.push_back(v.cN()[c]);
    if (a.texCoords) {
      a.values.push_back(v.cT().U());
      a.values.push_back(v.cT().V());
    }
  }
  return a;
}

std::vector<float> CornerAttributes(const CMesh& mesh, const std::vector<size_t>& faceOf,
                                    const VertexAttributes& perVertex) {
  // perVertex is in ToIndexedMesh's order: the live vertices.
  std::vector<uint32_t> live(mesh.vert.size(), 0);
  for (uint32_t i = 0, n = 0; i < mesh.vert.size(); ++i) live[i] = mesh.vert[i].IsD() ? UINT32_MAX : n++;
  const size_t C = size_t(perVertex.channels());
  std::vector<float> corner;
  corner.reserve(3 * faceOf.size() * C);
  for (size_t f : faceOf)
    for (int k = 0; k < 3; ++k) {
      const float* v = perVertex.of(live[vcg::tri::Index(mesh, mesh.face[f].cV(k))]);
      corner.insert(corner.end(), v, v + C);
    }
  return corner;
}

void SetCornerAttributes(CMesh& mesh, const VertexAttributes& layout, const std::vector<float>& corner) {
  const size_t C = size_t(layout.channels()), V = mesh.vert.size();
  auto set = [&](CMesh::VertexType& x, const float* values) {
    for (int c = 0; c < std::min(layout.colorChannels, 4); ++c)
      x.C()[c] = (unsigned char)std::lround(std::min(1.0f, std::max(0.0f, values[c])) * 255.0f);
    if (layout.normals)
      for (int c = 0; c < 3; ++c) x.N()[c] = values[layout.normalOffset() + c];
    if (layout.texCoords) {
      x.T().U() = values[layout.texCoordOffset()];
      x.T().V() = values[layout.texCoordOffset() + 1];
    }
  };
  // Per vertex, the distinct values its corners want: the first stays on the vertex, the others
  // become copies (appended after all, so that no pointer moves while faces are read).
  std::vector<std::vector<std::pair<const float*, size_t>>> variants(V);  // value, vertex index
  std::vector<std::array<size_t, 3>> target(mesh.face.size());
  size_t copies = 0;
  for (size_t f = 0; f < mesh.face.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const size_t v = vcg::tri::Index(mesh, mesh.face[f].cV(k));
      const float* want = corner.data() + (3 * f + size_t(k)) * C;
      size_t to = SIZE_MAX;
      for (const auto& x : variants[v])
        if (std::equal(want, want + C, x.first)) to = x.second;
      if (to == SIZE_MAX) {
        to = variants[v].empty() ? v : V + copies++;
        variants[v].push_back({want, to});
      }
      target[f][size_t(k)] = to;
    }
  if (copies) vcg::tri::Allocator<CMesh>::AddVertices(mesh, copies);
  for (size_t v = 0; v < V; ++v)
    for (const auto& x : variants[v]) {
      if (x.second != v) {
        mesh.vert[x.second].ImportData(mesh.vert[v]);
        mesh.vert[x.second].P() = mesh.vert[v].P();
      }
      set(mesh.vert[x.second], x.first);
    }
  for (size_t f = 0; f < mesh.face.size(); ++f)
    for (int k = 0; k < 3; ++k) mesh.face[f].V(k) = &mesh.vert[target[f][size_t(k)]];
}

std::string DescribeAttributes(const VertexAttributes& a) {
  std::string s;
  auto add = [&](const char* what) { s += (s.empty() ? "" : ", ") + std::string(what); };
  if (a.colorChannels) add(a.colorChannels == 4 ? "colour (RGBA)" : "colour");
  if (a.normals) add("normals");
  if (a.texCoords) add("texture coordinates");
  return s;
}

namespace {
// The core names its parameters as the MeshLab dialog's keys; on the command line they are options.
const std::pair<const char*, const char*> kOptionOfParameter[] = {{"ConeWeight", "--cone-weight"},
                                                                  {"ShapeWeight", "--shape-weight"},
                                                                  {"SizeWeight", "--size-weight"},
                                                                  {"ConeThresholdDeg", "--threshold"},
                                                                  {"ThresholdGrowth", "--growth"},
                                                                  {"MaxLevels", "--max-levels"},
                                                                  {"MinTopGroups", "--min-top-groups"},
                                                                  {"TargetFaceNum", "--target-faces"},
                                                                  {"TargetPerc", "--target-ratio"},
                                                                  {"QualityThr", "--quality-thr"},
                                                                  {"BoundaryWeight", "--boundary-weight"},
                                                                  {"PixelFactor", "--factor"},
                                                                  {"MinFaces", "--min-faces"},
                                                                  {"MaxErrorDistance", "--max-error"},
                                                                  {"MaxError", "--max-error"},
                                                                  {"MaxDepth", "--max-depth"},
                                                                  {"FeatureCurvature", "--feature-curvature"},
                                                                  {"FeatureAngleDeg", "--angle"},
                                                                  {"CurvatureThreshold", "--curvature-threshold"},
                                                                  {"TargetClusters", "--clusters"}};

std::string WithOptionNames(std::string text) {
  auto isWordChar = [](char ch) { return std::isalnum((unsigned char)ch) || ch == '_'; };
  for (const auto& po : kOptionOfParameter) {
    const std::string name = po.first;
    for (size_t at = text.find(name); at != std::string::npos; at = text.find(name, at + 1)) {
      const size_t end = at + name.size();
      if ((at > 0 && isWordChar(text[at - 1])) || (end < text.size() && isWordChar(text[end]))) continue;
      text.replace(at, name.size(), po.second);
    }
  }
  return text;
}
}  // namespace

int Fail(int code, const std::string& message) {
  std::fprintf(stderr, "conelod: %s\n", WithOptionNames(message).c_str());
  return code;
}

int FailLoad(const std::string& message) { return Fail(IsReadFailure(message) ? kIoError : kBadInput, message); }

std::string CheckOutputs(const std::string& command, int argc, char** argv) {
  bool hierarchy = false;
  for (int i = 0; i < argc; ++i) hierarchy |= std::string(argv[i]) == "--hierarchy";
  for (int i = 0; i + 1 < argc; ++i) {
    const std::string option = argv[i];
    if (option != "-o" && option != "--mask") continue;
    std::string path = argv[i + 1];
    if (command == "simplify" && hierarchy && option == "-o") path += "_L1.ply";
    const std::string err = CheckOutputPath(path);
    if (!err.empty()) return option + ": " + err;
  }
  return "";
}

const std::vector<std::string> kGroupingOptions = {"--cone-weight", "--shape-weight", "--size-weight",   "--threshold",
                                                   "--growth",      "--max-levels",   "--min-top-groups"};

ConeGroupingParams ReadGroupingParams(Args& a) {
  ConeGroupingParams p;
  p.chunkFaces = kGroupingChunkFaces;
  p.strictGreedy = a.has("--strict-greedy");  // a flag: callers list it among their flag options
  p.coneWeight = a.num("--cone-weight", p.coneWeight);
  p.shapeWeight = a.num("--shape-weight", p.shapeWeight);
  p.sizeWeight = a.num("--size-weight", p.sizeWeight);
  p.coneThresholdDeg = a.num("--threshold", p.coneThresholdDeg);
  p.thresholdGrowth = a.num("--growth", p.thresholdGrowth);
  p.maxLevels = a.integer("--max-levels", p.maxLevels);
  p.minTopGroups = a.integer("--min-top-groups", p.minTopGroups);
  return p;
}

std::string ReadThreadsOption(Args& a, int fallback, int& threads) {
  threads = a.integer("--threads", fallback);
  if (!a.ok()) return a.error();
  if (threads < 0 || threads > 1024) return "--threads must be a whole number from 0 (one per core) to 1024";
  return "";
}

std::string ReadPartsOptions(Args& a, int& threads, size_t& facesPerPart, const char* zeroMeans) {
  int t = 0;
  std::string err = ReadThreadsOption(a, threads, t);
  if (!err.empty()) return err;
  const int perPart = a.integer("--faces-per-part", int(facesPerPart));
  if (!a.ok()) return a.error();
  if (perPart < 0) return std::string("--faces-per-part must be a whole number >= 0 (0: ") + zeroMeans + ")";
  threads = t;
  facesPerPart = size_t(perPart);
  return "";
}

std::string ReadPartsOptions(Args& a, HierarchicalSimplificationParams& p) {
  return ReadPartsOptions(a, p.threads, p.facesPerPart, "never cut a level into parts");
}

std::vector<std::string> With(std::vector<std::string> v, const std::vector<std::string>& more) {
  v.insert(v.end(), more.begin(), more.end());
  return v;
}

}  // namespace cli
}  // namespace conelod
