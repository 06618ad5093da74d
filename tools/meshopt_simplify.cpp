// ConeLOD comparison tool — meshoptimizer's meshopt_simplify (Kapoulkine, meshoptimizer 0.18,
// Debian's libmeshoptimizer-dev) as a peer of our group-preserving quadric edge collapse, run to an
// exact face count so that errors are compared at equal faces (scripts/compare_qem.py).
//
//   meshopt_simplify IN.ply OUT.ply --target-faces N [--max-probes K]
//
// meshopt_simplify collapses edges onto existing vertices under a quadric error and stops once the
// index count is at most the target; a collapse removes one or two faces, so a call may land one
// face below N. The tool asks for N, N+1, ... and, when no answer has exactly N faces, simplifies
// the answers above N once more (at most K calls in all, default 16); it keeps the first result
// with exactly N faces, or else the closest one and says so (a closed mesh has an even face count:
// an odd N is out of reach). target_error = 1 (relative to the mesh's extent): no error limit, the
// face count decides. Prints one JSON object: faces, target_faces, exact, time_ms (the call, or
// the two chained calls, that made OUT.ply), search_ms (every call), calls, result_error
// (meshoptimizer's relative error of the last call, and the same as a fraction of the
// bounding-box diagonal).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <meshoptimizer.h>

#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"

using namespace conelod;

namespace {

int Fail(int code, const std::string& message) {
  std::fprintf(stderr, "meshopt_simplify: %s\n", message.c_str());
  return code;
}

// The path as a JSON string's contents.
std::string JsonEscaped(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if ((unsigned char)c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out;
}

const char* kUsage = "usage: meshopt_simplify IN.ply OUT.ply --target-faces N [--max-probes K]\n";

struct Run {
  std::vector<unsigned int> indices;
  float error = 0;  // meshoptimizer's relative error
  double ms = 0;    // wall time of the call
  size_t faces() const { return indices.size() / 3; }
};

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> positional;
  long long target = -1;
  int maxProbes = 16;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--target-faces" || arg == "--max-probes") {
      char* end = nullptr;
      const long long v = i + 1 < argc ? std::strtoll(argv[i + 1], &end, 10) : 0;
      if (i + 1 >= argc || !*argv[i + 1] || *end) return Fail(1, arg + " needs an integer\n" + kUsage);
      ++i;
      if (arg == "--target-faces")
        target = v;
      else
        maxProbes = v < 1 || v > 1000 ? 0 : int(v);
    } else if (arg.size() > 1 && arg[0] == '-') {
      return Fail(1, "unknown option " + arg + "\n" + kUsage);
    } else {
      positional.push_back(arg);
    }
  }
  if (positional.size() != 2) return Fail(1, std::string("expected IN.ply and OUT.ply\n") + kUsage);
  if (target < 1) return Fail(1, std::string("--target-faces N must be given, N >= 1\n") + kUsage);
  if (maxProbes < 1) return Fail(1, "--max-probes must be in 1..1000");

  CMesh mesh;
  const std::string err = LoadPly(mesh, positional[0]);
  if (!err.empty()) return Fail(2, err);
  IndexedMesh in = ToIndexedMesh(mesh);
  for (const auto& t : in.faces)
    for (uint32_t v : t)
      if (v >= in.positions.size()) return Fail(2, "'" + positional[0] + "' has a face with a missing vertex");
  if (in.faceCount() == 0) return Fail(2, "'" + positional[0] + "' has no faces");
  if (size_t(target) > in.faceCount())
    return Fail(2, "--target-faces " + std::to_string(target) + " is above the input's " +
                       std::to_string(in.faceCount()) + " faces");

  std::vector<unsigned int> indices;
  indices.reserve(in.faceCount() * 3);
  for (const auto& t : in.faces) indices.insert(indices.end(), t.begin(), t.end());
  const float* positions = &in.positions[0][0];
  static_assert(sizeof(vcg::Point3f) == 3 * sizeof(float), "Point3f must be three packed floats");

  // Stage 1: probes asking for N, N+1, ... faces of the input; the first with exactly N faces
  // wins. Stage 2, when none has: each stage-1 result above N (fewest faces first) simplified again,
  // asked for N, N+1, ...: its one or two last collapses then differ. `best`: closest to N so far.
  Run best;
  bool haveBest = false;
  int calls = 0;
  double searchMs = 0;
  std::vector<Run> above;  // stage-1 results with more than N faces
  auto probe = [&](const Run* from, long long ask) {
    const std::vector<unsigned int>& source = from ? from->indices : indices;
    Run run;
    run.indices.resize(source.size());
    const auto t0 = std::chrono::steady_clock::now();
    const size_t n = meshopt_simplify(run.indices.data(), source.data(), source.size(), positions, in.vertexCount(),
                                      sizeof(vcg::Point3f), size_t(ask) * 3, 1.0f, 0, &run.error);
    run.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    searchMs += run.ms;
    ++calls;
    run.indices.resize(n);
    if (from) run.ms += from->ms;  // the result took both calls
    const long long d = std::llabs((long long)run.faces() - target);
    if (!haveBest || d < std::llabs((long long)best.faces() - target)) {
      best = run;
      haveBest = true;
    }
    if (!from && (long long)run.faces() > target) above.push_back(run);
    return (long long)run.faces() == target;
  };
  bool exact = false;
  const int stage1 = std::max(1, maxProbes / 2);
  for (long long ask = target; !exact && calls < stage1 && ask <= (long long)in.faceCount(); ++ask)
    exact = probe(nullptr, ask);
  std::sort(above.begin(), above.end(), [](const Run& x, const Run& y) { return x.faces() < y.faces(); });
  for (size_t i = 0; !exact && i < above.size() && calls < maxProbes; ++i)
    for (long long ask = target; !exact && ask < (long long)above[i].faces() && calls < maxProbes; ++ask)
      exact = probe(&above[i], ask);

  // The output: the used vertices, compacted, in their input order.
  std::vector<uint32_t> newIndex(in.vertexCount(), UINT32_MAX);
  IndexedMesh out;
  out.faces.resize(best.faces());
  for (size_t f = 0; f < best.faces(); ++f)
    for (size_t k = 0; k < 3; ++k) {
      const uint32_t v = best.indices[3 * f + k];
      if (newIndex[v] == UINT32_MAX) {
        newIndex[v] = uint32_t(out.positions.size());
        out.positions.push_back(in.positions[v]);
      }
      out.faces[f][k] = newIndex[v];
    }
  CMesh result;
  AppendIndexedMesh(result, out);
  const std::string werr = SavePly(result, positional[1]);
  if (!werr.empty()) return Fail(3, werr);

  // meshoptimizer's error is relative to its scale (the largest extent of the box).
  const float scale = meshopt_simplifyScale(positions, in.vertexCount(), sizeof(vcg::Point3f));
  const vcg::Box3d box = UsedVertexBox(in);
  const double diagonal = box.IsNull() ? 0 : box.Diag();
  std::printf(
      "{\"input\": \"%s\", \"faces_in\": %zu, \"target_faces\": %lld, \"faces\": %zu, \"exact\": %s, "
      "\"time_ms\": %.3f, \"search_ms\": %.3f, \"calls\": %d, \"result_error\": %.9g, "
      "\"result_error_diagonal\": %.9g, \"meshoptimizer_version\": %d}\n",
      JsonEscaped(positional[0]).c_str(), in.faceCount(), target, best.faces(), exact ? "true" : "false", best.ms,
      searchMs, calls, double(best.error), diagonal > 0 ? double(best.error) * scale / diagonal : 0.0,
      MESHOPTIMIZER_VERSION);
  return 0;
}
