// ConeLOD benchmark — the .clod LOD file (lod_build.h, lod_read.h) of a mesh welded by position as `conelod lod build`
// welds it: build time, file size, time to the first image,
// resident memory of the on-demand reader against loading the whole mesh with vcglib.
//
//   bench_lod [MESH.ply...] [--budget-fraction F] [--keep DIR]
//   bench_lod --decode FILE.clod...   decode speed of existing files only (best of 5, one core)
//   default meshes: the bunny and the dragon from CONELOD_TEST_MESHES
//
// Times are CPU seconds of this process (the machine is shared; wall seconds in brackets). The
// cluster DAG is built with one thread per core (groups simplified side by side): its wall time is
// what a user waits for, and the build target is judged on it.
// Memory is measured in fresh processes (this program re-executes itself), so that one
// measurement cannot reuse pages another freed:
//   vcglib   RSS growth (VmRSS after - before) of LoadPly into the project's vcg mesh (vcg_mesh.h);
//   reader   RSS growth after LodReader::Open (roots = coarsest level loaded), then after refining
//            at F x the input's faces (default 10%), and the reader's own residentBytes() figure.
// First image = open the file + refine nothing (the coarsest cut) + extract it + rasterise it at
// 1024x768 with a z-buffer (perspective, flat shading), in a fresh process.
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "conelod/lod/lod_build.h"
#include "conelod/lod/lod_read.h"
#include "conelod/process_memory.h"
#include "conelod/mesh/sorted_faces.h"
#include "conelod/vcg_bridge.h"
#include "conelod/vcg_mesh.h"

using namespace conelod;

namespace {

double CpuSeconds() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}
double WallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// A tiny perspective rasteriser: flat-shaded triangles into a z-buffer. Returns covered pixels.
size_t Rasterise(const IndexedMesh& m, const vcg::Point3d& eye, const vcg::Point3d& target, int w, int h,
                 std::vector<float>& depth, std::vector<uint8_t>& rgb) {
  depth.assign(size_t(w) * size_t(h), 1e30f);
  rgb.assign(size_t(w) * size_t(h) * 3, 255);
  vcg::Point3d fwd = target - eye;
  fwd.Normalize();
  vcg::Point3d up(0, 1, 0);
  if (std::abs(fwd * up) > 0.99) up = vcg::Point3d(1, 0, 0);
  vcg::Point3d right = fwd ^ up;
  right.Normalize();
  up = right ^ fwd;
  const double focal = 0.5 * h / std::tan(0.5 * 40.0 * NormalCone::kPi / 180.0);  // 40 degrees vertical
  struct P {
    double x, y, z;
  };
  std::vector<P> proj(m.positions.size());
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const vcg::Point3d d = vcg::Point3d::Construct(m.positions[i]) - eye;
    const double z = d * fwd;
    proj[i] = {0.5 * w + focal * (d * right) / std::max(z, 1e-9), 0.5 * h - focal * (d * up) / std::max(z, 1e-9), z};
  }
  size_t covered = 0;
  for (const auto& t : m.faces) {
    const P &a = proj[t[0]], &b = proj[t[1]], &c = proj[t[2]];
    if (a.z <= 1e-6 || b.z <= 1e-6 || c.z <= 1e-6) continue;
    const double area = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
    if (area >= 0) continue;  // back-facing (counter-clockwise seen from outside, y down)
    const vcg::Point3d pa = vcg::Point3d::Construct(m.positions[t[0]]);
    vcg::Point3d n =
        (vcg::Point3d::Construct(m.positions[t[1]]) - pa) ^ (vcg::Point3d::Construct(m.positions[t[2]]) - pa);
    n.Normalize();
    const uint8_t shade = uint8_t(40 + 215 * std::max(0.0, -(n * fwd)));
    const int x0 = std::max(0, int(std::floor(std::min({a.x, b.x, c.x})))),
              x1 = std::min(w - 1, int(std::ceil(std::max({a.x, b.x, c.x}))));
    const int y0 = std::max(0, int(std::floor(std::min({a.y, b.y, c.y})))),
              y1 = std::min(h - 1, int(std::ceil(std::max({a.y, b.y, c.y}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double w0 = ((b.x - px) * (c.y - py) - (c.x - px) * (b.y - py)) / area;
        const double w1 = ((c.x - px) * (a.y - py) - (a.x - px) * (c.y - py)) / area;
        const double w2 = 1 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const float z = float(w0 * a.z + w1 * b.z + w2 * c.z);
        const size_t p = size_t(y) * size_t(w) + size_t(x);
        if (z >= depth[p]) continue;
        if (depth[p] == 1e30f) ++covered;
        depth[p] = z;
        rgb[3 * p] = rgb[3 * p + 1] = rgb[3 * p + 2] = shade;
      }
  }
  return covered;
}

vcg::Point3d EyeFor(const vcg::Box3f& box) {
  const vcg::Point3f c = box.Center();
  return vcg::Point3d(c[0], c[1], c[2]) + vcg::Point3d(0.3, 0.25, 1).Normalize() * (1.6 * box.Diag());
}

// --- The measurements made in fresh processes (this program re-executed) ---------------------

int ChildVcg(const std::string& mesh) {
  const size_t before = ProcessStatusBytes("VmRSS");
  CMesh m;
  if (!LoadPly(m, mesh).empty()) return 1;
  const size_t after = ProcessStatusBytes("VmRSS");
  std::printf("vcg_rss_growth=%zu vcg_hwm=%zu faces=%zu\n", after - before, ProcessStatusBytes("VmHWM"), m.face.size());
  return 0;
}

int ChildReader(const std::string& file, double fraction) {
  const size_t before = ProcessStatusBytes("VmRSS");
  const double c0 = CpuSeconds(), w0 = WallSeconds();
  std::unique_ptr<LodReader> r;
  Status s = LodReader::Open(file, r);
  if (!s.ok()) {
    std::fprintf(stderr, "%s\n", s.message.c_str());
    return 1;
  }
  const double openCpu = CpuSeconds() - c0;
  const size_t rssOpen = ProcessStatusBytes("VmRSS") - before;
  const size_t residentOpen = r->residentBytes();
  // First image: the coarsest cut (budget 0: the roots), extracted and rasterised.
  LodView view;
  view.eye = EyeFor(r->info().box);
  view.faceBudget = 0;
  LodCut cut;
  s = RefineLod(*r, view, cut);
  IndexedMesh first;
  if (s.ok()) s = ExtractCutMesh(*r, cut, false, first);
  if (!s.ok()) return 1;
  std::vector<float> depth;
  std::vector<uint8_t> rgb;
  const vcg::Point3f c = r->info().box.Center();
  const size_t pixels = Rasterise(first, view.eye, vcg::Point3d(c[0], c[1], c[2]), 1024, 768, depth, rgb);
  const double firstCpu = CpuSeconds() - c0, firstWall = WallSeconds() - w0;
  depth = std::vector<float>();
  rgb = std::vector<uint8_t>();
  // Refined at the budget.
  view.faceBudget = size_t(fraction * double(r->info().inputFaces));
  const double c1 = CpuSeconds();
  s = RefineLod(*r, view, cut);
  if (!s.ok()) return 1;
  const double refineCpu = CpuSeconds() - c1;
  const size_t rssBudget = ProcessStatusBytes("VmRSS") - before;
  std::printf(
      "open_cpu=%.6f first_image_cpu=%.6f first_image_wall=%.6f first_faces=%zu first_pixels=%zu "
      "resident_open=%zu rss_open=%zu resident_budget=%zu rss_budget=%zu budget_faces=%zu cut_faces=%zu "
      "refine_cpu=%.6f max_level_difference=%d hwm=%zu\n",
      openCpu, firstCpu, firstWall, first.faces.size(), pixels, residentOpen, rssOpen, r->residentBytes(), rssBudget,
      view.faceBudget, cut.faces, refineCpu, cut.maxLevelDifference, ProcessStatusBytes("VmHWM"));
  return 0;
}

std::map<std::string, double> RunChild(const std::string& args) {
  char exe[4096];
  const ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  std::map<std::string, double> out;
  if (n <= 0) return out;
  exe[n] = 0;
  FILE* p = popen((std::string("'") + exe + "' " + args).c_str(), "r");
  if (!p) return out;
  char buf[4096];
  std::string text;
  while (std::fgets(buf, sizeof buf, p)) text += buf;
  pclose(p);
  size_t at = 0;
  while (at < text.size()) {
    const size_t eq = text.find('=', at), end = text.find_first_of(" \n", at);
    if (eq == std::string::npos || end == std::string::npos || eq > end) break;
    out[text.substr(at, eq - at)] = std::atof(text.substr(eq + 1, end - eq - 1).c_str());
    at = end + 1;
  }
  return out;
}

std::string Shell(const std::string& s) { return "'" + s + "'"; }

// Every node's geometry read once, in id order (records loaded first, not timed): the bytes of the
// decoded buffers (positions 12, global ids 4 a vertex, faces 12) and the CPU seconds.
std::pair<double, double> DecodeSpeed(const std::string& file) {
  std::unique_ptr<LodReader> r;
  if (!LodReader::Open(file, r).ok()) return {0, 1};
  const uint64_t nodes = r->info().nodeCount;
  for (uint64_t id = 0; id < nodes; ++id)
    if (!r->LoadNode(uint32_t(id)).ok()) return {0, 1};
  for (uint32_t id : r->roots()) r->EvictGeometry(id);
  double bytes = 0;
  const double c = CpuSeconds();
  for (uint64_t id = 0; id < nodes; ++id) {
    if (!r->LoadGeometry(uint32_t(id)).ok()) return {0, 1};
    const LodGeometry* g = r->geometry(uint32_t(id));
    bytes += 16.0 * double(g->positions.size()) + 12.0 * double(g->faces.size());
    r->EvictGeometry(uint32_t(id));
  }
  return {bytes, CpuSeconds() - c};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 3 && !std::strcmp(argv[1], "--child-vcg")) return ChildVcg(argv[2]);
  if (argc >= 4 && !std::strcmp(argv[1], "--child-reader")) return ChildReader(argv[2], std::atof(argv[3]));
  if (argc >= 3 && !std::strcmp(argv[1], "--decode")) {  // decode speed of existing files, best of 5
    for (int i = 2; i < argc; ++i) {
      std::unique_ptr<LodReader> r;
      const Status s = LodReader::Open(argv[i], r);
      if (!s.ok()) {
        std::fprintf(stderr, "bench_lod: %s\n", s.message.c_str());
        return 1;
      }
      std::pair<double, double> best{0, 1e30};
      for (int k = 0; k < 5; ++k) {
        const auto d = DecodeSpeed(argv[i]);
        if (d.first <= 0) return 1;
        if (d.second < best.second) best = d;
      }
      std::printf("%s: version %u, %llu bytes: %.1f MB decoded in %.3f s CPU (best of 5): %.0f MB/s\n", argv[i],
                  r->info().version, (unsigned long long)r->info().fileBytes, best.first / 1e6, best.second,
                  best.first / 1e6 / best.second);
    }
    return 0;
  }
  double fraction = 0.1;
  std::string keep;
  std::vector<std::string> meshes;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--budget-fraction") && i + 1 < argc)
      fraction = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--keep") && i + 1 < argc)
      keep = argv[++i];
    else
      meshes.push_back(argv[i]);
  }
  if (meshes.empty()) {
    const char* env = std::getenv("CONELOD_TEST_MESHES");
    const std::string dir = env ? env : CONELOD_TEST_MESHES;
    meshes = {dir + "/stanford_bunny_bun_zipper.ply", dir + "/stanford_dragon_vrip_binary.ply"};
  }
  for (const std::string& path : meshes) {
    CMesh cm;
    if (!LoadPly(cm, path).empty()) {
      std::fprintf(stderr, "bench_lod: cannot read %s\n", path.c_str());
      return 1;
    }
    // Welded by position as `conelod lod build` and the filter weld it (BuildLodFile, weld.h).
    const IndexedMesh mesh = WeldByPosition(ToIndexedMesh(cm)).mesh;
    cm.Clear();
    const std::string name = path.substr(path.find_last_of('/') + 1);
    const std::string file =
        (keep.empty() ? std::string("/tmp") : keep) + "/bench_lod_" + std::to_string(getpid()) + "_" + name + ".clod";

    // Build: the DAG (clusters, groups simplified side by side), then the file.
    LodBuildParams params;
    double c = CpuSeconds(), w = WallSeconds();
    const int threads = SimplificationThreads(params.simplification);
    LodDag dag;
    if (!BuildLodDag(mesh, params, dag).ok()) return 1;
    const double simplifyCpu = CpuSeconds() - c, simplifyWall = WallSeconds() - w;
    c = CpuSeconds(), w = WallSeconds();
    LodBuildStats st;
    const Status ws = WriteLodFile(mesh, dag, file, &st);
    if (!ws.ok()) {
      std::fprintf(stderr, "bench_lod: %s\n", ws.message.c_str());
      return 1;
    }
    const double writeCpu = CpuSeconds() - c, writeWall = WallSeconds() - w;
    const size_t writeHwm = ProcessStatusBytes("VmHWM");
    dag = LodDag();

    // Round trip: the full budget gives back the input's faces (positions compared exactly).
    bool exact = false;
    size_t roundTripVertices = 0;
    double quantization = 0, quantizationBound = 0;
    {
      std::unique_ptr<LodReader> r;
      LodCut cut;
      IndexedMesh back;
      LodView all;
      all.eye = EyeFor(vcg::Box3f(vcg::Point3f(0, 0, 0), vcg::Point3f(1, 1, 1)));
      all.faceBudget = mesh.faces.size();
      if (LodReader::Open(file, r).ok() && RefineLod(*r, all, cut).ok() && ExtractCutMesh(*r, cut, true, back).ok()) {
        IndexedMesh onGrid = mesh;  // the input as the file stores it: positions on its grid
        for (auto& p : onGrid.positions) p = r->info().grid.Round(p);
        exact = SortedFacePositions(back) == SortedFacePositions(onGrid);
        roundTripVertices = back.positions.size();
        for (const auto& t : mesh.faces)  // the used vertices (the file has no others)
          for (uint32_t v : t)
            quantization = std::max(quantization, double((onGrid.positions[v] - mesh.positions[v]).Norm()));
        quantizationBound = r->info().quantizationError;
      }
    }
    auto decode = DecodeSpeed(file);

    auto vcg = RunChild("--child-vcg " + Shell(path));
    auto rd = RunChild("--child-reader " + Shell(file) + " " + std::to_string(fraction));
    if (vcg.empty() || rd.empty()) {
      std::fprintf(stderr, "bench_lod: a measuring process failed\n");
      return 1;
    }
    const double vcgBytes = vcg["vcg_rss_growth"];
    const double buildWall = simplifyWall + writeWall;
    std::printf("\n== %s: %zu faces, %zu vertices\n", name.c_str(), mesh.faces.size(), mesh.positions.size());
    std::printf(
        "build, %d threads: %.2f s wall = cluster DAG %.2f + writing %.3f s wall "
        "(DAG %.2f s CPU, writing %.3f s CPU); process peak %.1f MiB\n",
        threads, buildWall, simplifyWall, writeWall, simplifyCpu, writeCpu, double(writeHwm) / 1048576.0);
    std::printf("file: %llu bytes (%.2f bytes/input face), %d node levels, %zu nodes; faces per level (0 = input):",
                (unsigned long long)st.fileBytes, double(st.fileBytes) / double(mesh.faces.size()), st.levels,
                st.nodes);
    for (size_t f : st.levelFaces) std::printf(" %zu", f);
    std::printf(
        "\nround trip at full budget: %s up to quantization (%zu vertices welded); largest move of an input "
        "vertex %.3g (%.3g of the diagonal), bound %.3g: %s",
        exact ? "EXACT" : "DIFFERS", roundTripVertices, quantization, quantization / UsedVertexBox(mesh).Diag(),
        quantizationBound, quantization <= quantizationBound ? "within" : "EXCEEDED");
    std::printf(
        "\ndecode, every node's geometry once (one core): %.1f MB decoded (positions, ids, faces) from "
        "%.1f MB of file in %.3f s CPU: %.0f MB/s",
        decode.first / 1e6, double(st.fileBytes) / 1e6, decode.second, decode.first / 1e6 / decode.second);
    std::printf(
        "\nfirst image (open + coarsest cut + extract + rasterise 1024x768): %.4f s CPU [%.4f s wall], "
        "%.0f faces, %.0f pixels; open alone %.4f s CPU\n",
        rd["first_image_cpu"], rd["first_image_wall"], rd["first_faces"], rd["first_pixels"], rd["open_cpu"]);
    std::printf("vcglib LoadPly: RSS growth %.2f MiB\n", vcgBytes / 1048576.0);
    std::printf("reader, coarsest level: residentBytes %.1f KiB (%.2f%% of vcglib), RSS growth %.1f KiB (%.2f%%)\n",
                rd["resident_open"] / 1024, 100 * rd["resident_open"] / vcgBytes, rd["rss_open"] / 1024,
                100 * rd["rss_open"] / vcgBytes);
    std::printf(
        "reader, %.0f%% budget (%.0f faces, cut %.0f, refined in %.3f s CPU, max level difference %.0f): "
        "residentBytes %.2f MiB (%.2f%%), RSS growth %.2f MiB (%.2f%%)\n",
        100 * fraction, rd["budget_faces"], rd["cut_faces"], rd["refine_cpu"], rd["max_level_difference"],
        rd["resident_budget"] / 1048576, 100 * rd["resident_budget"] / vcgBytes, rd["rss_budget"] / 1048576,
        100 * rd["rss_budget"] / vcgBytes);
    const bool memOpen = std::max(rd["resident_open"], rd["rss_open"]) <= 0.05 * vcgBytes;
    const bool memBudget = std::max(rd["resident_budget"], rd["rss_budget"]) <= 0.20 * vcgBytes;
    const bool firstFast = rd["first_image_cpu"] < 0.2;
    const bool buildFast = buildWall < 10;
    std::printf(
        "targets: coarsest <= 5%% %s, %.0f%% budget <= 20%% %s, first image < 0.2 s %s, build < 10 s (wall) %s\n",
        memOpen ? "MET" : "NOT MET", 100 * fraction, memBudget ? "MET" : "NOT MET", firstFast ? "MET" : "NOT MET",
        buildFast ? "MET" : "NOT MET");
    if (keep.empty()) std::remove(file.c_str());
  }
  return 0;
}
