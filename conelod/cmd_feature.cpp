// ConeLOD CLI — `conelod feature-simplify` and `conelod feature-edges`: feature-preserving
// simplification by edge operations (Hayano, Matsuoka, Ueda) and its feature lines.
#include <cstdio>
#include <cstdlib>

#include "cli_common.h"
#include "commands.h"
#include "conelod/feature/feature_simplify.h"
#include "conelod/simplify_bridge.h"

namespace conelod {
namespace cli {
namespace {

// "0.5" -> 0.5 (model units); "0.5%" -> 0.5 % of `diagonal`. Returns false if it does not parse.
bool ParseDistance(const std::string& text, double diagonal, double& out) {
  std::string s = text;
  const bool percent = !s.empty() && s.back() == '%';
  if (percent) s.pop_back();
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0' || !(v >= 0) || !std::isfinite(v)) return false;
  out = percent ? v * diagonal / 100.0 : v;
  return true;
}

const std::vector<std::string> kFeatureOptions = {"--angle", "--feature-curvature", "--curvature-threshold"};

FeatureSimplifyParams ReadFeatureParams(Args& a) {
  FeatureSimplifyParams p;
  p.featureAngleDeg = a.num("--angle", p.featureAngleDeg);
  p.featureCurvature = a.num("--feature-curvature", p.featureCurvature);
  p.curvatureThreshold = a.num("--curvature-threshold", p.curvatureThreshold);
  p.extendFeatureLines = !a.has("--no-extend");
  return p;
}

}  // namespace

const char* kFeatureSimplifyUsage =
    "conelod feature-simplify IN.ply (--target-faces N | --target-percent P | --max-error E[%]) [-o OUT.ply]\n"
    "                         [--angle DEG] [--no-extend] [--feature-curvature K] [--curvature-threshold T]\n"
    "                         [--mark] [--line-tolerance PCT] [--threads N] [--faces-per-part P] [--json]\n"
    "  Feature-preserving simplification by edge operations (Hayano-Matsuoka-Ueda): feature edges\n"
    "  (dihedral angle <= DEG [135]; 180 = flat, 90 = cube edge) and feature vertices are kept,\n"
    "  feature lines are simplified only along themselves. Stops at N faces (or P % of the input),\n"
    "  or when no collapse keeps every removed vertex within E of the output (E% = % of the\n"
    "  bounding-box diagonal). --feature-curvature K: vertices with |K| D^2 >= K are feature\n"
    "  vertices; --curvature-threshold T: vertices with |K| D^2 or |M| D >= T are not removed\n"
    "  (D = diagonal; 0 = off). --mark writes vertex colours (red = feature line, blue = feature\n"
    "  vertex) and vertex quality = class (0 smooth, 1 line, 2 feature); otherwise a file's vertex\n"
    "  colour becomes, at each kept vertex, the value there of the attribute quadric of the\n"
    "  vertices it took over; so do its normals (normalised) and, away from texture seams, its\n"
    "  texture coordinates (a seam vertex keeps its own). The report counts\n"
    "  the output's feature edges lying on the input's feature lines (within PCT % of D [0.5]).\n"
    "  --threads N: threads (0 = one per core, at most 8 [0]) for the set-up, the first pass of the\n"
    "  growing bound and the parts; --faces-per-part P [32768; 0: never]: with the growing bound, a\n"
    "  mesh of at least 2P faces is simplified in 2, 4 or 8 parts at the same time, the seams\n"
    "  between them in each round of the bound. The output is the same for any N.\n";

const char* kFeatureEdgesUsage =
    "conelod feature-edges IN.ply [--reference REF.ply] [--angle DEG] [--no-extend] [--line-tolerance PCT] [--json]\n"
    "  Feature edges (dihedral angle <= DEG [135], border and non-manifold edges), extension swaps\n"
    "  and vertex classes of IN.ply; with --reference, how many of IN's feature edges lie on REF's\n"
    "  feature lines (within PCT % of REF's bounding-box diagonal [0.5]) and how much of REF's\n"
    "  feature-line length IN still covers.\n";

int CmdFeatureSimplify(int argc, char** argv) {
  std::vector<std::string> valueOptions = kFeatureOptions;
  valueOptions.insert(valueOptions.end(), {"-o", "--target-faces", "--target-percent", "--max-error",
                                           "--line-tolerance", "--threads", "--faces-per-part"});
  Args a(argc, argv, valueOptions, {"--json", "--no-extend", "--mark", "--no-grow"});
  FeatureSimplifyParams p = ReadFeatureParams(a);
  const double targetPercent = a.num("--target-percent", 0);
  const int targetFaces = a.integer("--target-faces", 0);
  const double lineTolPct = a.num("--line-tolerance", 0.5);
  int threads = int(p.threads);
  const std::string partsError = ReadPartsOptions(a, threads, p.facesPerPart, "never in parts");
  if (!partsError.empty()) return Fail(kUsage, partsError + "\n" + kFeatureSimplifyUsage);
  p.threads = unsigned(threads);
  if (!a.ok()) return Fail(kUsage, a.error() + "\n" + kFeatureSimplifyUsage);
  if (a.positional().size() != 1) return Fail(kUsage, std::string("expected one input mesh\n") + kFeatureSimplifyUsage);
  if (!a.has("--target-faces") && !a.has("--target-percent") && !a.has("--max-error"))
    return Fail(kUsage, std::string("give --target-faces, --target-percent or --max-error\n") + kFeatureSimplifyUsage);
  if (targetFaces < 0 || targetPercent < 0 || targetPercent > 100 || !(lineTolPct > 0))
    return Fail(kUsage, "--target-faces must be >= 0, --target-percent in [0,100], --line-tolerance > 0");

  CMesh mesh;
  IndexedMesh im;
  std::vector<size_t> faceOf;
  int loadMask = 0;
  std::string err = LoadInput(a.positional()[0], mesh, im, faceOf, &loadMask);
  if (!err.empty()) return FailLoad(err);
  const double diagonal = BoundingBoxDiagonal(im);
  if (a.has("--max-error") && !ParseDistance(a.str("--max-error"), diagonal, p.maxErrorDistance))
    return Fail(kUsage,
                "--max-error expects a distance >= 0 or a percentage like 0.5%, got '" + a.str("--max-error") + "'");
  p.targetFaceCount = size_t(targetFaces);
  p.growErrorBound = !a.has("--no-grow");
  if (a.has("--target-percent")) p.targetFaceCount = size_t(double(im.faceCount()) * targetPercent / 100.0 + 0.5);
  if (p.targetFaceCount == 0 && a.has("--target-faces") + a.has("--target-percent") > 0 && !a.has("--max-error"))
    p.targetFaceCount = 1;  // "0 faces": as far as the constraints allow

  FeatureSimplifyResult r;
  Timer timer;
  const Status s = FeatureSimplify(im, p, r);
  const double seconds = timer.seconds();
  if (!s.ok()) return Fail(kBadInput, a.positional()[0] + ": " + s.message);

  FeatureLineAgreement agree;
  const Status sa = CompareFeatureLines(im, r.mesh, p.featureAngleDeg, lineTolPct / 100.0 * diagonal, agree);

  if (a.has("-o")) {
    // The collapses are half-edge collapses: the vertices that stay keep their position; a
    // file's vertex colour and normal, and its texture coordinates away from seams, become the
    // extended quadric's at that position of the vertices each survivor took over (seam vertices
    // keep their own coordinates).
    if (loadMask & vcg::tri::io::Mask::IOM_VERTCOLOR) MeanSurvivorColours(mesh, r);
    MeanSurvivorNormalsAndTexCoords(
        mesh, r, (loadMask & vcg::tri::io::Mask::IOM_VERTNORMAL) != 0,
        (loadMask & (vcg::tri::io::Mask::IOM_VERTTEXCOORD | vcg::tri::io::Mask::IOM_WEDGTEXCOORD)) != 0);
    WriteSimplifiedMesh(mesh, faceOf, r, a.has("--mark"));
    int extra = AttributeMask(loadMask);
    if (a.has("--mark")) {
      auto cls = vcg::tri::Allocator<CMesh>::FindPerVertexAttribute<int>(mesh, VertexClassAttributeName());
      for (auto& v : mesh.vert) v.Q() = float(cls[v]);
      extra |= vcg::tri::io::Mask::IOM_VERTCOLOR | vcg::tri::io::Mask::IOM_VERTQUALITY;
    }
    err = SavePly(mesh, a.str("-o"), extra);
    if (!err.empty()) return Fail(kIoError, err);
  }

  if (a.has("--json")) {
    Json j;
    j.BeginObject()
        .field("input", a.positional()[0])
        .field("faces_in", r.facesIn)
        .field("faces_out", r.facesOut)
        .field("feature_edges", r.featureEdgesIn)
        .field("feature_vertices", r.featureVertices)
        .field("seconds", seconds)
        .field("feature_edges_out", r.featureEdges.size())
        .field("swap_edges", r.swapEdges)
        .field("feature_line_vertices", r.lineVerticesIn)
        .field("smooth_vertices", r.smoothVerticesIn)
        .field("collapses", r.collapses)
        .field("target_faces", p.targetFaceCount)
        .field("target_reached", r.targetReached)
        .field("max_error_distance", p.maxErrorDistance)
        .field("max_collapse_distance", r.maxCollapseDistance)
        .field("max_tracked_error", r.maxTrackedError)
        .field("final_error_bound", r.finalErrorBound)
        .field("grow_error_bound", p.growErrorBound)
        .field("parts", size_t(r.parts))
        .field("diagonal", diagonal)
        .field("feature_angle_deg", p.featureAngleDeg);
    if (sa.ok()) {
      j.field("line_tolerance", lineTolPct / 100.0 * diagonal)
          .field("input_line_edges", agree.referenceEdges)
          .field("output_line_edges", agree.simplifiedEdges)
          .field("output_line_edges_on_input_lines", agree.simplifiedOnReference)
          .field("input_line_length_covered",
                 agree.referenceLength > 0 ? agree.referenceLengthCovered / agree.referenceLength : 1.0);
    }
    if (a.has("-o")) j.field("output", a.str("-o"));
    j.EndObject();
    std::printf("%s\n", j.str().c_str());
  } else {
    const std::string parts = r.parts > 1 ? "; in " + std::to_string(r.parts) + " parts" : "";
    std::printf("%s: %zu -> %zu faces in %.3f s (%zu collapses; %s%s)\n", a.positional()[0].c_str(), r.facesIn,
                r.facesOut, seconds, r.collapses,
                p.targetFaceCount == 0 ? "error-distance stop"
                : r.targetReached      ? "target reached"
                                       : "target NOT reached: no allowed collapse left",
                parts.c_str());
    std::printf(
        "feature edges %zu (%zu made by extension swaps) -> %zu; feature vertices %zu (kept); "
        "feature-line vertices %zu; smooth vertices %zu\n",
        r.featureEdgesIn, r.swapEdges, r.featureEdges.size(), r.featureVertices, r.lineVerticesIn, r.smoothVerticesIn);
    if (p.maxErrorDistance > 0)
      std::printf("error bound %.6g (%.3f %% of the diagonal); largest tracked error %.6g\n", p.maxErrorDistance,
                  100 * p.maxErrorDistance / diagonal, r.maxTrackedError);
    if (sa.ok())
      std::printf(
          "feature lines (A <= %.1f deg): %zu of the output's %zu feature edges lie on the input's lines; "
          "%.1f %% of the input's line length is covered\n",
          p.featureAngleDeg, agree.simplifiedOnReference, agree.simplifiedEdges,
          agree.referenceLength > 0 ? 100 * agree.referenceLengthCovered / agree.referenceLength : 100.0);
    if (a.has("-o")) std::printf("wrote %s\n", a.str("-o").c_str());
  }
  return kOk;
}

int CmdFeatureEdges(int argc, char** argv) {
  std::vector<std::string> valueOptions = kFeatureOptions;
  valueOptions.insert(valueOptions.end(), {"--reference", "--line-tolerance"});
  Args a(argc, argv, valueOptions, {"--json", "--no-extend"});
  const FeatureSimplifyParams p = ReadFeatureParams(a);
  const double lineTolPct = a.num("--line-tolerance", 0.5);
  if (!a.ok()) return Fail(kUsage, a.error() + "\n" + kFeatureEdgesUsage);
  if (a.positional().size() != 1) return Fail(kUsage, std::string("expected one input mesh\n") + kFeatureEdgesUsage);
  if (!(lineTolPct > 0)) return Fail(kUsage, "--line-tolerance must be > 0");

  CMesh mesh;
  IndexedMesh im;
  std::vector<size_t> faceOf;
  std::string err = LoadInput(a.positional()[0], mesh, im, faceOf);
  if (!err.empty()) return FailLoad(err);
  FeatureInfo info;
  Status s = DetectFeatures(im, p, info);
  if (!s.ok()) return Fail(kBadInput, a.positional()[0] + ": " + s.message);

  FeatureLineAgreement agree;
  bool haveRef = false;
  if (a.has("--reference")) {
    CMesh refMesh;
    IndexedMesh ref;
    std::vector<size_t> refFaceOf;
    err = LoadInput(a.str("--reference"), refMesh, ref, refFaceOf);
    if (!err.empty()) return FailLoad(err);
    s = CompareFeatureLines(ref, im, p.featureAngleDeg, lineTolPct / 100.0 * BoundingBoxDiagonal(ref), agree);
    if (!s.ok()) return Fail(kBadInput, s.message);
    haveRef = true;
  }

  if (a.has("--json")) {
    Json j;
    j.BeginObject()
        .field("input", a.positional()[0])
        .field("faces", im.faceCount())
        .field("feature_edges", info.featureEdges.size())
        .field("dihedral_edges", info.dihedralEdges)
        .field("swap_edges", info.swapEdges)
        .field("removed_by_swaps", info.removedBySwaps)
        .field("border_edges", info.borderEdges)
        .field("non_manifold_edges", info.nonManifoldEdges)
        .field("feature_vertices", info.count(VertexClass::Feature))
        .field("feature_line_vertices", info.count(VertexClass::FeatureLine))
        .field("smooth_vertices", info.count(VertexClass::Smooth));
    if (haveRef)
      j.field("reference", a.str("--reference"))
          .field("reference_line_edges", agree.referenceEdges)
          .field("line_edges", agree.simplifiedEdges)
          .field("line_edges_on_reference_lines", agree.simplifiedOnReference)
          .field("reference_line_length_covered",
                 agree.referenceLength > 0 ? agree.referenceLengthCovered / agree.referenceLength : 1.0);
    j.EndObject();
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf(
        "%s: %zu faces; feature edges %zu (dihedral %zu, made by swaps %zu, removed by swaps %zu, border %zu, "
        "non-manifold %zu)\nvertices: feature %zu, feature line %zu, smooth %zu\n",
        a.positional()[0].c_str(), im.faceCount(), info.featureEdges.size(), info.dihedralEdges, info.swapEdges,
        info.removedBySwaps, info.borderEdges, info.nonManifoldEdges, info.count(VertexClass::Feature),
        info.count(VertexClass::FeatureLine), info.count(VertexClass::Smooth));
    if (haveRef)
      std::printf(
          "against %s: %zu of %zu feature edges lie on its %zu feature edges; %.1f %% of its line length "
          "covered\n",
          a.str("--reference").c_str(), agree.simplifiedOnReference, agree.simplifiedEdges, agree.referenceEdges,
          agree.referenceLength > 0 ? 100 * agree.referenceLengthCovered / agree.referenceLength : 100.0);
  }
  return kOk;
}

}  // namespace cli
}  // namespace conelod
