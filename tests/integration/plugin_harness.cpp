// Drives the built plugin in-process as MeshLab does (its own PluginManager loads it, filters run
// on a MeshDocument with the parameters MeshLab's dialog would show), in any MeshLab version the
// plugin is built for (harness_meshlab.h):
//  - every ConeLOD filter is listed and applied on the bunny, with checks of its results;
//  - a filter that fails (bad parameters, bad input, cancellation, missing files) says why, in the
//    dialog's words, and leaves the mesh exactly as it was, adds no layer and leaves no file;
//  - with --scripts DIR (MeshLab 2022+): every shipped .mlx has the plugin's parameters and
//    defaults and runs the way MeshLab 2022+ runs filter scripts;
//  - --digest OUT writes what each filter produced on the bunny (faces, vertices, groups, a hash of
//    the per-face quality, key figures); --compare REF fails when it differs from REF (the digest
//    of another MeshLab version: the same output everywhere).
//   plugin_harness PLUGIN.so BUNNY.ply NAN.ply [--scripts DIR] [--digest OUT] [--compare REF]
// Exit 0 when every check passes.
#include <QApplication>
#include <QDir>
#include <QFile>
#include <QFileInfo>
#include <QRegularExpression>
#include <QTemporaryDir>
#include <QTextStream>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <set>
#include <vector>

#include "harness_meshlab.h"

#include <wrap/io_trimesh/import_ply.h>

#include <sys/stat.h>
#include <fcntl.h>
#include <unistd.h>
#include <chrono>
#include <thread>
#include <QElapsedTimer>

#define HARNESS_TEXT(x) #x
#define HARNESS_STRING(x) HARNESS_TEXT(x)

namespace {

int failures = 0;
void Check(bool ok, const QString& what) {
  std::printf("%s: %s\n", ok ? "ok" : "FAIL", qUtf8Printable(what));
  if (!ok) ++failures;
}

const char* const kGrouping = "Cone LOD: Normal Cone Face Grouping";
const char* const kCulling = "Cone LOD: Cluster Culling Cost";
const char* const kGroupQem = "Cone LOD: Group-Preserving Quadric Edge Collapse";
const char* const kIntegrity = "Cone LOD: Group Integrity";
const char* const kFeature = "Cone LOD: Feature-Preserving Edge Simplification";
const char* const kBudget = "Cone LOD: Face Budget from Screen Pixels";
const char* const kPca = "Cone LOD: PCA Recursive Face Partition";
const char* const kProgressive = "Cone LOD: Progressive Cluster Mesh";
const char* const kExport = "Cone LOD: Export LOD File";
const char* const kExtract = "Cone LOD: Extract View-Dependent LOD";
const char* const kAll[] = {kGrouping, kCulling, kGroupQem,    kIntegrity, kFeature,
                            kBudget,   kPca,     kProgressive, kExport,    kExtract};

// What a filter could change: faces, positions, the data mask, per-face quality and colour, attributes.
struct Snapshot {
  std::vector<float> coords;
  std::vector<long> faces;
  int mask = 0;
  std::vector<float> quality;
  std::vector<unsigned> colour;
  size_t faceAttributes = 0, vertexAttributes = 0;
  bool operator==(const Snapshot& o) const {
    if (coords.size() != o.coords.size()) return false;
    for (size_t i = 0; i < coords.size(); ++i)  // NaN == NaN here: bitwise
      if (std::memcmp(&coords[i], &o.coords[i], sizeof(float)) != 0) return false;
    return faces == o.faces && mask == o.mask && quality == o.quality && colour == o.colour &&
           faceAttributes == o.faceAttributes && vertexAttributes == o.vertexAttributes;
  }
};

Snapshot Take(MeshModel& mm) {
  Snapshot s;
  for (const auto& v : mm.cm.vert)
    for (int k = 0; k < 3; ++k) s.coords.push_back(v.cP()[k]);
  for (const auto& f : mm.cm.face)
    for (int k = 0; k < 3; ++k) s.faces.push_back(f.IsD() ? -2 : long(f.cV(k) - &mm.cm.vert[0]));
  s.mask = mm.dataMask();
  if (mm.hasDataMask(MeshModel::MM_FACEQUALITY))
    for (const auto& f : mm.cm.face) s.quality.push_back(f.cQ());
  if (mm.hasDataMask(MeshModel::MM_FACECOLOR))
    for (const auto& f : mm.cm.face) {
      const auto& c = f.cC();
      s.colour.push_back(unsigned(c[0]) << 24 | unsigned(c[1]) << 16 | unsigned(c[2]) << 8 | c[3]);
    }
  s.faceAttributes = mm.cm.face_attr.size();
  s.vertexAttributes = mm.cm.vert_attr.size();
  return s;
}

MeshModel* Load(MeshDocument& md, const QString& path) {
  MeshModel* mm = md.addNewMesh(path, QFileInfo(path).fileName());
  int mask = 0;
  if (vcg::tri::io::ImporterPLY<CMeshO>::Open(mm->cm, qUtf8Printable(path), mask) != 0) {
    std::printf("cannot load %s\n", qUtf8Printable(path));
    std::exit(2);
  }
  vcg::tri::UpdateBounding<CMeshO>::Box(mm->cm);
  vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFaceNormalized(mm->cm);
  return mm;
}

int Layers(MeshDocument& md) { return harness::LayerCount(md); }

bool CancelAtOnce(const int, const char*) { return false; }

// The number after `key` in the last log line that has it ("two_state_cost 0.6523 ..."), as written.
QString Figure(GLLogStream& log, const QString& key) {
  const QRegularExpression re("(?:^|\\s)" + QRegularExpression::escape(key) + "\\s+([-0-9.eE+]+)");
  const auto& lines = log.logStringList();
  for (int i = lines.size() - 1; i >= 0; --i) {
    const QRegularExpressionMatch m = re.match(lines[i].second);
    if (m.hasMatch()) return m.captured(1);
  }
  return "missing";
}

// Whether a log line from the `from`-th on contains `text`.
bool LogHas(GLLogStream& log, const QString& text, int from = 0) {
  const auto& lines = log.logStringList();
  for (int i = from; i < lines.size(); ++i)
    if (lines[i].second.contains(text)) return true;
  return false;
}

// What a filter produced on the current layer: faces, vertices, distinct per-face quality values
// (the groups) and a hash of the per-face quality in face order, plus figures from the log.
QString Digest(MeshDocument& md, GLLogStream& log, const QStringList& keys) {
  MeshModel& m = *md.mm();
  QString d = QString("layers=%1 faces=%2 vertices=%3").arg(Layers(md)).arg(m.cm.fn).arg(m.cm.vn);
  if (m.hasDataMask(MeshModel::MM_FACEQUALITY)) {
    std::map<float, int> groups;
    unsigned long long hash = 1469598103934665603ull;
    for (const auto& f : m.cm.face) {
      if (f.IsD()) continue;
      const float q = f.cQ();
      ++groups[q];
      unsigned bits;
      std::memcpy(&bits, &q, 4);
      hash = (hash ^ bits) * 1099511628211ull;
    }
    d += QString(" groups=%1 quality_hash=%2").arg(groups.size()).arg(hash, 16, 16, QChar('0'));
  }
  for (const QString& k : keys) d += " " + k + "=" + Figure(log, k);
  return d;
}

struct Run {
  harness::Plugin& plugin;
  QString bunny, nanMesh;
  QTemporaryDir dir;
  std::map<QString, QString> digest;

  QAction* action(const char* name) { return plugin.action(name); }
  RichParameterList params(const char* name, MeshDocument& md) { return plugin.params(action(name), md); }
  QString apply(const char* name, MeshDocument& md, const RichParameterList& par, vcg::CallBackPos* cb = nullptr) {
    return plugin.apply(action(name), md, par, cb);
  }
  QString apply(const char* name, MeshDocument& md) { return apply(name, md, params(name, md)); }

  // A failing run: a message naming `expect`, none of `mustNotName`, the mesh and document unchanged.
  QString refused(const char* name, MeshDocument& md, const RichParameterList& par, const QString& expect,
                  const QString& why, vcg::CallBackPos* cb = nullptr, const QString& mustNotName = QString()) {
    MeshModel* mm = md.mm();
    if (mm) mm->updateDataMask(plugin.filter()->getRequirements(action(name)));  // MeshLab does this first
    const Snapshot before = mm ? Take(*mm) : Snapshot();
    const int layers = Layers(md);
    const QString message = apply(name, md, par, cb);
    Check(!message.isEmpty(), QString("%1 refuses %2").arg(name, why));
    std::printf("   message: %s\n", qUtf8Printable(message));
    Check(message.contains(expect), QString("  the message says '%1'").arg(expect));
    if (!mustNotName.isEmpty()) Check(!message.contains(mustNotName), "  and does not name " + mustNotName);
    Check(Layers(md) == layers && md.mm() == mm, "  no layer is added");
    if (mm) Check(Take(*mm) == before, "  the mesh is unchanged");
    Check(LogHas(plugin.log(), "ConeLOD error: " + message), "  the log has the message");
    return message;
  }
};

void ListFilters(Run& r) {
  const QStringList names = r.plugin.names();
  Check(names.size() == int(sizeof(kAll) / sizeof(kAll[0])), QString("%1 filters listed").arg(names.size()));
  for (const char* n : kAll) {
    Check(names.contains(n), QString("listed: %1").arg(n));
#if CONELOD_MESHLAB_API >= 2022
    if (QAction* a = r.action(n)) {
      MeshDocument md;
      QStringList ps;
      for (const RichParameter& p : r.plugin.params(a, md)) ps << harness::Plugin::pythonName(p);
      std::printf("   pymeshlab: ms.%s(%s)\n", qUtf8Printable(r.plugin.pythonName(a)), qUtf8Printable(ps.join(", ")));
    }
#endif
  }
}

// Every filter applied on the bunny with the dialog's defaults (file names filled in).
void ApplyEveryFilter(Run& r) {
  GLLogStream& log = r.plugin.log();
  {
    MeshDocument md;
    MeshModel* mm = Load(md, r.bunny);
    const QString m = r.apply(kGrouping, md);
    Check(m.isEmpty(), QString("grouping succeeds %1").arg(m));
    Check(mm->hasDataMask(MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR), "  quality and colour enabled");
    auto l1 = vcg::tri::Allocator<CMeshO>::FindPerFaceAttribute<int>(mm->cm, "conelod_group_L1");
    Check(vcg::tri::Allocator<CMeshO>::IsValidHandle(mm->cm, l1), "  attribute conelod_group_L1 exists");
    bool same = true;
    for (const auto& f : mm->cm.face) same = same && int(f.cQ()) == l1[f];
    Check(same, "  quality = level-1 group id (Display level 1)");
    r.digest[kGrouping] = Digest(md, log, {"level 1: groups"});

    const Snapshot grouped = Take(*mm);
    Check(r.apply(kCulling, md).isEmpty(), "culling cost succeeds");
    Check(Take(*mm) == grouped, "  culling cost does not change the mesh");
    const double two = Figure(log, "two_state_cost").toDouble(), three = Figure(log, "three_state_cost").toDouble();
    Check(three < two && two < 1.0, QString("  three-state %1 < two-state %2 < 1").arg(three).arg(two));
    r.digest[kCulling] = Digest(md, log, {"two_state_cost", "three_state_cost", "rejected_fraction"});

    // The group-preserving collapse at its defaults (half the faces) on a copy of the grouped layer,
    // then Group Integrity against the copy: every group intact.
    MeshModel* before = md.addNewMesh("", "before", false);
    before->updateDataMask(mm);
    vcg::tri::Append<CMeshO, CMeshO>::MeshCopy(before->cm, mm->cm, false, true);
    md.setCurrentMesh(mm->id());
    RichParameterList par = r.params(kGroupQem, md);
    harness::SetEnum(par, "GroupSource", 0);  // the groups of the grouping (per-face quality)
    Check(r.apply(kGroupQem, md, par).isEmpty(), "group-preserving collapse of the grouping's groups succeeds");
    Check(mm->cm.fn <= 69451 / 2 + 1 && mm->cm.fn > 30000, QString("  %1 faces (target: half)").arg(mm->cm.fn));
    Check(Figure(log, "integrity_percent") == "100.00", "  every group intact");
    r.digest[kGroupQem] = Digest(md, log, {"faces_out", "groups_after"});
    par = r.params(kIntegrity, md);
#if CONELOD_MESHLAB_API >= 2022
    Check(par.getMeshId("ReferenceMesh") == unsigned(before->id()),
          "  Group Integrity's default reference: the other layer");
#else
    Check(par.getMesh("ReferenceMesh") == before, "  Group Integrity's default reference: the other layer");
#endif
    Check(r.apply(kIntegrity, md, par).isEmpty(), "group integrity against the copy succeeds");
    Check(Figure(log, "integrity_percent") == "100.00" && Figure(log, "groups_split") == "0",
          "  100 % intact, none split");
    r.digest[kIntegrity] = Digest(md, log, {"groups_before", "groups_after", "integrity_percent"});
  }
  {  // Group Integrity of a layer against itself: no trivial 100 %, an explanation instead.
    MeshDocument md;
    MeshModel* mm = Load(md, r.bunny);
    Check(r.apply(kGrouping, md).isEmpty(), "grouping succeeds");
    const int lines = log.logStringList().size();
    Check(r.apply(kIntegrity, md).isEmpty(), "group integrity with one layer succeeds");
    bool percent = false;
    for (int i = lines; i < log.logStringList().size(); ++i)
      percent = percent || log.logStringList()[i].second.contains("integrity_percent");
    Check(!percent, "  no integrity percentage for a layer compared with itself");
    Check(LogHas(log, "nothing to compare") && LogHas(log, "Duplicate Current Layer"),
          "  the log says there is nothing to compare and how to keep a copy");
    (void)mm;
  }
  {
    MeshDocument md;
    Load(md, r.bunny);
    Check(r.apply(kFeature, md).isEmpty(), "feature-preserving simplification succeeds at its defaults");
    Check(md.mm()->cm.fn == 34726 || md.mm()->cm.fn == 34725, QString("  %1 faces (half)").arg(md.mm()->cm.fn));
    Check(LogHas(log, "Polygonal Modality"), "  the log says where the feature lines show");
    r.digest[kFeature] = Digest(md, log, {"faces_out", "feature_edges"});
  }
  {
    MeshDocument md;
    MeshModel* mm = Load(md, r.bunny);
    const Snapshot before = Take(*mm);
    Check(r.apply(kBudget, md).isEmpty(), "face budget succeeds");
    Check(Take(*mm) == before, "  with Simplifier None the mesh is unchanged");
    RichParameterList par = r.params(kBudget, md);
    par.setValue("Width", IntValue(64));
    par.setValue("Height", IntValue(48));
    harness::SetEnum(par, "Simplifier", 1);
    Check(r.apply(kBudget, md, par).isEmpty(), "face budget at 64 x 48 with the feature simplifier");
    Check(QString::number(mm->cm.fn) == Figure(log, "faces_out"), "  the mesh has the logged faces");
    r.digest[kBudget] = Digest(md, log, {"covered_pixels", "target_faces", "faces_out"});
  }
  {
    MeshDocument md;
    Load(md, r.bunny);
    Check(r.apply(kPca, md).isEmpty(), "PCA partition succeeds");
    Check(Figure(log, "pca_clusters") == "64" && Figure(log, "all_connected") == "1", "  64 connected clusters");
    r.digest[kPca] = Digest(md, log, {"pca_clusters"});
  }
  {
    MeshDocument md;
    MeshModel* mm = Load(md, r.bunny);
    const Snapshot before = Take(*mm);
    Check(r.apply(kProgressive, md).isEmpty(), "progressive cluster mesh succeeds");
    Check(Layers(md) == 2 && md.mm() != mm, "  a new layer, made current");
    Check(Take(*mm) == before, "  the input layer is unchanged");
    Check(QString::number(md.mm()->cm.fn) == Figure(log, "progressive_faces"), "  the layer has the logged faces");
    r.digest[kProgressive] = Digest(md, log, {"progressive_faces", "progressive_vertices"});
  }
  {  // An unreferenced vertex at 1e20 stretched the sampled distance's grid: meshlabserver was killed
     // (SIGSEGV). It is left out of the grid and its box: the filter runs.
    MeshDocument md;
    MeshModel* mm = Load(md, r.bunny);
    vcg::tri::Allocator<CMeshO>::AddVertices(mm->cm, 1)->P() = CMeshO::CoordType(1e20f, 0, 0);
    Check(r.apply(kProgressive, md).isEmpty(), "progressive cluster mesh with an unreferenced vertex at 1e20");
    Check(Figure(log, "progressive_faces").toInt() > 0, "  it makes a coarse mesh");
  }
  {
    MeshDocument md;
    MeshModel* mm = Load(md, r.bunny);
    const Snapshot before = Take(*mm);
    const QString clod = r.dir.filePath("bunny.clod");
    RichParameterList par = r.params(kExport, md);
    harness::SetPath(par, "FileName", clod);
    Check(r.apply(kExport, md, par).isEmpty(), "export succeeds");
    Check(QFileInfo(clod).size() > 0 && QString::number(QFileInfo(clod).size()) == Figure(log, "lod_file_bytes"),
          "  writes the file of the logged size");
    Check(Take(*mm) == before, "  export leaves the mesh unchanged");
    r.digest[kExport] = Digest(md, log, {"lod_levels", "lod_nodes"});
    par = r.params(kExtract, md);
    harness::SetPath(par, "FileName", clod);
    par.setValue("FaceBudget", IntValue(0));
    Check(r.apply(kExtract, md, par).isEmpty(), "extract succeeds");
    Check(Layers(md) == 2 && md.mm() != mm && md.mm()->cm.fn == mm->cm.fn,
          "  adds a layer with every face of the input (no budget)");
    Check(Take(*mm) == before, "  extract leaves the mesh unchanged");
    par.setValue("FaceBudget", IntValue(8000));
    Check(r.apply(kExtract, md, par).isEmpty(), "extract with a budget of 8000 faces");
    Check(md.mm()->cm.fn <= 8000 && md.mm()->cm.fn > 0, QString("  %1 faces").arg(md.mm()->cm.fn));
    r.digest[kExtract] = Digest(md, log, {"lod_faces", "lod_max_level_difference"});
  }
}

// Issue 24, items 2 and 18: what the LOD export, the grouping and the collapse do with vertices a
// mesh repeats or does not use.
MeshModel* AddMesh(MeshDocument& md, const QString& name, const std::vector<vcg::Point3f>& positions,
                   const std::vector<std::array<int, 3>>& faces) {
  MeshModel* mm = md.addNewMesh("", name);
  auto v = vcg::tri::Allocator<CMeshO>::AddVertices(mm->cm, positions.size());
  for (size_t i = 0; i < positions.size(); ++i, ++v)
    v->P() = CMeshO::CoordType(positions[i][0], positions[i][1], positions[i][2]);
  auto f = vcg::tri::Allocator<CMeshO>::AddFaces(mm->cm, faces.size());
  for (size_t i = 0; i < faces.size(); ++i, ++f)
    for (int k = 0; k < 3; ++k) f->V(k) = &mm->cm.vert[size_t(faces[i][size_t(k)])];
  vcg::tri::UpdateBounding<CMeshO>::Box(mm->cm);
  vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFaceNormalized(mm->cm);
  return mm;
}

void RepeatedAndUnusedVertices(Run& r) {
  GLLogStream& log = r.plugin.log();
  {  // An 8-face mesh with 58 unreferenced vertices: the file written is one the reader takes.
    std::vector<vcg::Point3f> pos = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int i = 0; i < 58; ++i) pos.push_back({float(i), 7, 7});
    MeshDocument md;
    MeshModel* mm = AddMesh(md, "octahedron", pos,
                            {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}});
    const Snapshot before = Take(*mm);
    const QString clod = r.dir.filePath("unreferenced.clod");
    RichParameterList par = r.params(kExport, md);
    harness::SetPath(par, "FileName", clod);
    Check(r.apply(kExport, md, par).isEmpty(), "export of a mesh with 58 unreferenced vertices succeeds");
    Check(Take(*mm) == before, "  and leaves the mesh unchanged");
    par = r.params(kExtract, md);
    harness::SetPath(par, "FileName", clod);
    par.setValue("FaceBudget", IntValue(0));
    const QString m = r.apply(kExtract, md, par);
    Check(m.isEmpty(), "  its file is read back " + m);
    Check(Layers(md) == 2 && md.mm()->cm.fn == 8 && md.mm()->cm.vn == 6, "  a layer with the 8 faces and 6 vertices");
  }
  {  // The bunny with the vertices its upper half shares with the lower half repeated (a seam by
     // index only): the grouping gives the bunny's groups, the collapse the bunny's result.
    MeshDocument md;
    MeshModel* whole = Load(md, r.bunny);
    vcg::tri::Allocator<CMeshO>::CompactEveryVector(whole->cm);
    std::vector<vcg::Point3f> pos;
    for (const auto& v : whole->cm.vert) pos.push_back(vcg::Point3f(v.cP()[0], v.cP()[1], v.cP()[2]));
    const float mid = whole->cm.bbox.Center()[1];
    std::vector<std::array<int, 3>> faces;
    std::vector<char> upper, lowerUses(pos.size(), 0);
    for (const auto& f : whole->cm.face) {
      std::array<int, 3> t;
      for (int k = 0; k < 3; ++k) t[size_t(k)] = int(f.cV(k) - &whole->cm.vert[0]);
      faces.push_back(t);
      upper.push_back((f.cP(0)[1] + f.cP(1)[1] + f.cP(2)[1]) / 3 > mid);
      if (!upper.back())
        for (int v : t) lowerUses[size_t(v)] = 1;
    }
    std::map<int, int> copy;
    for (size_t i = 0; i < faces.size(); ++i)
      if (upper[i])
        for (int& v : faces[i])
          if (lowerUses[size_t(v)]) {
            auto ins = copy.emplace(v, int(pos.size()));
            if (ins.second) pos.push_back(pos[size_t(v)]);
            v = ins.first->second;
          }
    MeshModel* split = AddMesh(md, "split bunny", pos, faces);
    Check(copy.size() > 100, QString("the split bunny repeats %1 vertices").arg(copy.size()));
    std::vector<std::vector<float>> quality;
    for (MeshModel* mm : {whole, split}) {
      md.setCurrentMesh(mm->id());
      Check(r.apply(kGrouping, md).isEmpty(),
            QString("grouping succeeds on the %1 bunny").arg(mm == whole ? "whole" : "split"));
      std::vector<float> q;
      for (const auto& f : mm->cm.face) q.push_back(f.cQ());
      quality.push_back(q);
    }
    Check(quality[0] == quality[1], "  the seam does not change the groups");
    Check(split->cm.vn == int(pos.size()), "  the grouping leaves the layer's vertices as they are");
    std::vector<QString> results;
    for (MeshModel* mm : {whole, split}) {
      md.setCurrentMesh(mm->id());
      RichParameterList par = r.params(kGroupQem, md);
      harness::SetEnum(par, "GroupSource", 1);
      Check(r.apply(kGroupQem, md, par).isEmpty(),
            QString("group-preserving collapse succeeds on the %1 bunny").arg(mm == whole ? "whole" : "split"));
      results.push_back(QString("faces %1 vertices %2 integrity %3")
                            .arg(mm->cm.fn)
                            .arg(mm->cm.vn)
                            .arg(Figure(log, "integrity_percent")));
    }
    Check(results[0] == results[1], "  the seam does not change the collapse: " + results[0] + " / " + results[1]);
  }
}

void Failures(Run& r) {
  {  // A bad parameter, in the dialog's words.
    MeshDocument md;
    Load(md, r.bunny);
    RichParameterList par = r.params(kGrouping, md);
    par.setValue("ConeThresholdDeg", FloatValue(0.0f));
    r.refused(kGrouping, md, par, "'Cone threshold (deg)' must be > 0", "a cone threshold of 0", nullptr,
              "ConeThresholdDeg");
    par = r.params(kGroupQem, md);
    par.setValue("TargetPerc", FloatValue(1.5f));
    r.refused(kGroupQem, md, par, "'Target fraction (0..1)' must be between 0 and 1", "a target fraction of 1.5",
              nullptr, "TargetPerc");
    par = r.params(kGroupQem, md);
    par.setValue("TargetPerc", FloatValue(0.0f));
    r.refused(kGroupQem, md, par, "give a target", "no target at all", nullptr, "TargetFaceNum");
    par = r.params(kCulling, md);
    par.setValue("Views", IntValue(0));
    r.refused(kCulling, md, par, "'View directions' must be between 1 and", "0 views");
    par = r.params(kFeature, md);
    par.setValue("TargetPerc", FloatValue(0.0f));
    r.refused(kFeature, md, par, "give a stop criterion", "no stop criterion", nullptr, "MaxErrorDistance");
    par = r.params(kBudget, md);
    par.setValue("Width", IntValue(0));
    r.refused(kBudget, md, par, "'Screen width (pixels)' must be >= 1", "a width of 0");
    par = r.params(kProgressive, md);
    par.setValue("MaxNormalTurnDeg", FloatValue(180.0f));
    r.refused(kProgressive, md, par, "'Max normal turn (deg)' must be in (0, 180)", "a normal turn of 180");
  }
  {  // A normal cone level that cannot reach the target: the faces reached and the level that would.
    MeshDocument md;
    Load(md, r.bunny);
    RichParameterList par = r.params(kGroupQem, md);
    harness::SetEnum(par, "GroupSource", 1);
    par.setValue("GroupLevel", IntValue(1));
    par.setValue("TargetPerc", FloatValue(0.02f));
    const QString m = r.refused(kGroupQem, md, par, "cannot be reached with the", "a target level 1 cannot reach");
    Check(m.contains("stopped at") && m.contains("would reach it"),
          "  names the faces reached and the level that would reach the target");
    par.setValue("GroupLevel", IntValue(0));
    Check(r.apply(kGroupQem, md, par).isEmpty(), "the automatic level (0) reaches the same target");
    Check(Figure(r.plugin.log(), "integrity_percent") == "100.00", "  every group intact");
    Check(md.mm()->cm.fn <= 1389, QString("  %1 faces (target 1389)").arg(md.mm()->cm.fn));
  }
  {  // Group ids from per-face quality, on a mesh without it.
    MeshDocument md;
    Load(md, r.bunny);
    RichParameterList par = r.params(kGroupQem, md);
    harness::SetEnum(par, "GroupSource", 0);
    r.refused(kGroupQem, md, par, "no per-face quality", "a mesh without group ids", nullptr, "GroupSource");
  }
  {  // Cancellation through MeshLab's callback.
    MeshDocument md;
    Load(md, r.bunny);
    for (const char* name : {kGrouping, kFeature, kPca})
      r.refused(name, md, r.params(name, md), "cancel", "a cancelled run", CancelAtOnce);
  }
  {  // NaN coordinates: every filter that reads the mesh refuses them.
    MeshDocument md;
    Load(md, r.nanMesh);
    for (const char* name : {kGrouping, kCulling, kFeature, kBudget, kPca, kProgressive}) {
      RichParameterList par = r.params(name, md);
      r.refused(name, md, par, "NaN", "NaN coordinates");
    }
    RichParameterList par = r.params(kGroupQem, md);
    harness::SetEnum(par, "GroupSource", 1);
    r.refused(kGroupQem, md, par, "NaN", "NaN coordinates");
    par = r.params(kExport, md);
    const QString clod = r.dir.filePath("nan.clod");
    harness::SetPath(par, "FileName", clod);
    r.refused(kExport, md, par, "NaN", "NaN coordinates");
    Check(!QFileInfo::exists(clod), "  no file is left");
  }
  {  // Coordinates around 1e19 (their squares overflow floats; the sampled distance crashed on
     // them): every filter that reads the mesh refuses them and leaves it unchanged, except the
     // progressive cluster mesh, which works on the mesh scaled by a power of two.
    MeshDocument md;
    MeshModel* mm = Load(md, r.bunny);
    for (auto& v : mm->cm.vert) v.P() *= 1e20f;
    {
      const int layers = Layers(md);
      Check(r.apply(kProgressive, md).isEmpty() && Layers(md) == layers + 1,
            "Progressive Cluster Mesh takes coordinates around 1e19 (a new layer)");
      md.setCurrentMesh(mm->id());
    }
    for (const char* name : {kGrouping, kCulling, kFeature, kBudget, kPca}) {
      RichParameterList par = r.params(name, md);
      r.refused(name, md, par, "beyond +-1e18", "coordinates around 1e19");
    }
    RichParameterList par = r.params(kGroupQem, md);
    harness::SetEnum(par, "GroupSource", 1);
    r.refused(kGroupQem, md, par, "beyond +-1e18", "coordinates around 1e19");
    par = r.params(kExport, md);
    const QString clod = r.dir.filePath("huge.clod");
    harness::SetPath(par, "FileName", clod);
    r.refused(kExport, md, par, "beyond +-1e18", "coordinates around 1e19");
    Check(!QFileInfo::exists(clod), "  no file is left");
  }
  {  // File parameters: no hidden default file; missing and broken files named.
    MeshDocument md;
    MeshModel* mm = Load(md, r.bunny);
    // MeshLab 2020.09's dialog passes on only a file chosen with "...": the message says so there.
    const QString how = CONELOD_MESHLAB_API >= 2022 ? "type the path" : "'...' button";
    for (const char* name : {kExport, kExtract}) {
      const QString m = r.refused(name, md, r.params(name, md), "'LOD file' is empty", "an empty file name");
      Check(m.contains(how), "  and says how to give one (" + how + ")");
    }
    Check(!QFileInfo::exists("out.clod"), "no out.clod is written or read in the current folder");

    const QString clod = r.dir.filePath("ok.clod"), cancelled = r.dir.filePath("cancelled.clod");
    RichParameterList par = r.params(kExport, md);
    harness::SetPath(par, "FileName", cancelled);
    r.refused(kExport, md, par, "cancel", "a cancelled export", CancelAtOnce);
    Check(!QFileInfo::exists(cancelled), "  a cancelled export leaves no file");
    harness::SetPath(par, "FileName", clod);
    Check(r.apply(kExport, md, par).isEmpty(), "export succeeds");
    QFile whole(clod);
    whole.open(QIODevice::ReadOnly);
    const QByteArray bytes = whole.readAll();
    whole.close();
    // Nothing the user named is lost: a cancelled export over an existing file leaves it as it
    // was (it was deleted), a FIFO or a missing folder is refused before the work.
    r.refused(kExport, md, par, "cancel", "a cancelled export over an existing file", CancelAtOnce);
    whole.open(QIODevice::ReadOnly);
    Check(whole.readAll() == bytes, "  the existing file is unchanged");
    whole.close();
    const QString fifo = r.dir.filePath("fifo.clod");
    Check(mkfifo(qUtf8Printable(fifo), 0644) == 0, "a FIFO is made");
    harness::SetPath(par, "FileName", fifo);
    r.refused(kExport, md, par, "only a regular file is written", "a FIFO as the LOD file");
    Check(QFileInfo(fifo).exists(), "  the FIFO is still there");
    harness::SetPath(par, "FileName", r.dir.filePath("no/such/folder/x.clod"));
    r.refused(kExport, md, par, "No such file or directory", "a file in a missing folder");
    harness::SetPath(par, "FileName", clod);
    const QString truncated = r.dir.filePath("truncated.clod");
    QFile cut(truncated);
    cut.open(QIODevice::WriteOnly);
    cut.write(bytes.left(bytes.size() / 2));
    cut.close();
    {  // A FIFO as the LOD file to read: open() blocked MeshLab for ever; refused before opening it.
       // (Should it block, a writer comes after 3 s: the test then fails instead of hanging.)
      const QString inFifo = r.dir.filePath("in_fifo.clod");
      Check(mkfifo(qUtf8Printable(inFifo), 0644) == 0, "a FIFO to read is made");
      std::thread writer([&] {
        std::this_thread::sleep_for(std::chrono::seconds(3));
        const int fd = ::open(qUtf8Printable(inFifo), O_WRONLY | O_NONBLOCK);
        if (fd >= 0) ::close(fd);
      });
      par = r.params(kExtract, md);
      harness::SetPath(par, "FileName", inFifo);
      QElapsedTimer timer;
      timer.start();
      r.refused(kExtract, md, par, "is a FIFO", "a FIFO as the LOD file to read");
      Check(timer.elapsed() < 2000, "  at once");
      const int reader = ::open(qUtf8Printable(inFifo), O_RDONLY | O_NONBLOCK);  // frees a waiting writer
      writer.join();
      if (reader >= 0) ::close(reader);
    }
    for (const QString& bad : {r.dir.filePath("missing.clod"), truncated}) {
      par = r.params(kExtract, md);
      harness::SetPath(par, "FileName", bad);
      r.refused(kExtract, md, par, bad, "a missing or truncated file (named)");
    }
    (void)mm;
  }
  {  // An empty mesh: refused, no file.
    MeshDocument md;
    md.addNewMesh("", "empty");
    const QString clod = r.dir.filePath("empty.clod");
    RichParameterList par = r.params(kExport, md);
    harness::SetPath(par, "FileName", clod);
    r.refused(kExport, md, par, "has no faces", "an empty mesh");
    Check(!QFileInfo::exists(clod), "  no file is left");
  }
}

// What the dialogs say and offer (issue 24, items 11-16).
void Dialogs(Run& r) {
  GLLogStream& log = r.plugin.log();
  {  // Export LOD File offers what the DAG build uses (conelod lod build's options), and each of
     // its parameters changes the file: Max levels, the three weights, Min top-level groups and
     // Lock group boundaries gave byte-identical files.
    MeshDocument md;
    Load(md, r.bunny);
    QStringList names;
    for (const RichParameter& p : r.params(kExport, md)) names << p.name();
    for (const char* gone :
         {"ConeWeight", "ShapeWeight", "SizeWeight", "MaxLevels", "MinTopGroups", "LockGroupBoundaries"})
      Check(!names.contains(gone),
            QString("Export LOD File has no parameter %1 (the DAG build has no use for it)").arg(gone));
    const QString info = r.plugin.filter()->filterInfo(r.action(kExport));
    Check(!info.contains("eight at a time") && info.contains("12 by default"),
          "  its help says 12 clusters are gathered into a group, as the build does");
    auto exportBytes = [&](RichParameterList par, const QString& file) {
      harness::SetPath(par, "FileName", r.dir.filePath(file));
      const QString m = r.apply(kExport, md, par);
      QFile f(r.dir.filePath(file));
      const QByteArray bytes = m.isEmpty() && f.open(QIODevice::ReadOnly) ? f.readAll() : QByteArray();
      if (!m.isEmpty()) std::printf("   export failed: %s\n", qUtf8Printable(m));
      return bytes;
    };
    const RichParameterList defaults = r.params(kExport, md);
    const QByteArray base = exportBytes(defaults, "base.clod");
    RichParameterList boundary = defaults;  // Boundary Preserving Weight acts with Preserve Boundary
    boundary.setValue("PreserveBoundary", BoolValue(true));
    const QByteArray boundaryBase = exportBytes(boundary, "boundary.clod");
    Check(!base.isEmpty() && !boundaryBase.isEmpty(), "  export at the defaults (and with Preserve Boundary) succeeds");
    struct Change {
      const char* name;
      double value;
      bool boundary;
    };
    const Change changes[] = {
        {"ConeThresholdDeg", 30, false}, {"ThresholdGrowth", 1.2, false}, {"ClusterFaces", 64, false},
        {"GroupClusters", 6, false},     {"LevelRatio", 0.6, false},      {"QualityThr", 0.6, false},
        {"OptimalPlacement", 0, false},  {"PreserveBoundary", 1, false},  {"BoundaryWeight", 8, true},
        {"PreserveNormal", 0, false},    {"Precision", 1e-4, false}};
    Check(names.size() == int(sizeof(changes) / sizeof(changes[0])) + 1,
          QString("  %1 parameters: the file name and the %2 below")
              .arg(names.size())
              .arg(sizeof(changes) / sizeof(changes[0])));
    for (const Change& ch : changes) {
      RichParameterList par = ch.boundary ? boundary : defaults;
      Check(par.hasParameter(ch.name), QString("  it has %1").arg(ch.name));
      if (!par.hasParameter(ch.name)) continue;
      const QString type = par.getParameterByName(ch.name).stringType();
      if (type == "RichBool")
        par.setValue(ch.name, BoolValue(ch.value != 0));
      else if (type == "RichInt")
        par.setValue(ch.name, IntValue(int(ch.value)));
      else
        par.setValue(ch.name, FloatValue(float(ch.value)));
      const QByteArray bytes = exportBytes(par, QString(ch.name) + ".clod");
      Check(!bytes.isEmpty() && bytes != (ch.boundary ? boundaryBase : base),
            QString("  %1 = %2 changes the file").arg(ch.name).arg(ch.value));
    }
    RichParameterList par = defaults;
    par.setValue("LevelRatio", FloatValue(1.0f));
    harness::SetPath(par, "FileName", r.dir.filePath("ratio1.clod"));
    r.refused(kExport, md, par, "'Faces kept per level (0..1)' must be in (0, 1)", "a level ratio of 1");
  }
  {  // Extract View-Dependent LOD describes the cut it makes: watertight, levels side by side.
    const QString info = r.plugin.filter()->filterInfo(r.action(kExtract));
    Check(!info.contains("one level apart") && info.contains("watertight") && info.contains("lod_max_level_difference"),
          "Extract View-Dependent LOD's help promises a watertight cut, not neighbours one level apart");
    MeshDocument md;
    Load(md, r.bunny);
    RichParameterList par = r.params(kExport, md);
    const QString clod = r.dir.filePath("levels.clod");
    harness::SetPath(par, "FileName", clod);
    r.apply(kExport, md, par);
    par = r.params(kExtract, md);
    harness::SetPath(par, "FileName", clod);
    par.setValue("FaceBudget", IntValue(8000));
    Check(r.apply(kExtract, md, par).isEmpty(), "  a cut of 8000 faces");
    std::printf("   lod_max_level_difference %s\n", qUtf8Printable(Figure(log, "lod_max_level_difference")));
    const QStringList choices = harness::EnumChoices(r.params(kExtract, md), "ViewMode");
    Check(choices.size() == 3, "  its View has 3 choices");
    for (const QString& choice : choices)
      Check(!choice.contains("ViewDirection") && !choice.contains("Eye"), "  a View choice names no key: " + choice);
  }
  {  // Group-Preserving Quadric Edge Collapse at its defaults on a freshly loaded mesh: the
     // automatic normal cone groups (conelod simplify --groups cone:auto), shown in colour.
    MeshDocument md;
    MeshModel* mm = Load(md, r.bunny);
    const int from = log.logStringList().size();
    const QString m = r.apply(kGroupQem, md);
    Check(m.isEmpty(), "Group-Preserving QEM at its defaults on a freshly loaded mesh succeeds " + m);
    Check(LogHas(log, "normal cone groups, level", from) && LogHas(log, "(automatic)", from),
          "  with the automatic normal cone groups");
    Check(LogHas(log, "integrity_percent 100.00", from), "  every group intact");
    std::map<unsigned, std::set<float>> qualitiesOfColour;
    std::map<float, std::set<unsigned>> coloursOfQuality;
    const bool coloured = m.isEmpty() && mm->hasDataMask(MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR);
    for (const auto& f : mm->cm.face) {
      if (!coloured) break;
      const auto& c = f.cC();
      const unsigned colour = unsigned(c[0]) << 16 | unsigned(c[1]) << 8 | c[2];
      qualitiesOfColour[colour].insert(f.cQ());
      coloursOfQuality[f.cQ()].insert(colour);
    }
    bool onePerGroup = coloursOfQuality.size() > 1;
    for (const auto& kv : coloursOfQuality) onePerGroup = onePerGroup && kv.second.size() == 1;
    Check(onePerGroup && qualitiesOfColour.size() > 8, QString("  one colour per group (%1 groups, %2 colours)")
                                                           .arg(coloursOfQuality.size())
                                                           .arg(qualitiesOfColour.size()));
    // The ids already on the mesh remain a choice: the groups of Normal Cone Face Grouping.
    MeshDocument md2;
    Load(md2, r.bunny);
    RichParameterList par = r.params(kGroupQem, md2);
    harness::SetEnum(par, "GroupSource", 0);
    r.refused(kGroupQem, md2, par, "no per-face quality", "per-face quality groups on a mesh without them");
    Check(r.apply(kGrouping, md2).isEmpty() && r.apply(kGroupQem, md2, par).isEmpty() &&
              LogHas(log, "per-face quality groups"),
          "  per-face quality groups after Normal Cone Face Grouping");
  }
  {  // Messages name parameters by the dialog's labels.
    MeshDocument md;
    Load(md, r.bunny);
    RichParameterList par = r.params(kGrouping, md);
    par.setValue("DisplayLevel", IntValue(99999));
    int from = log.logStringList().size();
    Check(r.apply(kGrouping, md, par).isEmpty(), "grouping with Display level 99999");
    Check(LogHas(log, "'Display level' 99999 is above", from) && !LogHas(log, "DisplayLevel 99999", from),
          "  the log says 'Display level', not DisplayLevel");
    par = r.params(kGroupQem, md);
    harness::SetEnum(par, "GroupSource", 1);
    par.setValue("GroupLevel", IntValue(99));
    from = log.logStringList().size();
    Check(r.apply(kGroupQem, md, par).isEmpty(), "collapse with Normal cone level 99");
    Check(LogHas(log, "'Normal cone level (0 = automatic)' 99 is above", from) && !LogHas(log, "GroupLevel 99", from),
          "  the log says 'Normal cone level (0 = automatic)', not GroupLevel");
  }
  {  // The file box: what this MeshLab's dialog takes (2020.09 ignores a path typed into the box).
    MeshDocument md;
    Load(md, r.bunny);
    for (const char* name : {kExport, kExtract}) {
      const QString info = r.plugin.filter()->filterInfo(r.action(name));
      const QString tip = r.params(name, md).getParameterByName("FileName").toolTip();
      for (const QString& text : {info, tip}) {
        if (CONELOD_MESHLAB_API >= 2022)
          Check(text.contains("type a path into the box"),
                QString("%1 says a path can be typed into the box").arg(name));
        else
          Check(!text.contains("type a path") && text.contains("ignores a path typed or edited in the box itself") &&
                    text.contains("'...'"),
                QString("%1 says MeshLab 2020.09 takes a file chosen with '...' only").arg(name));
      }
    }
  }
}

#if CONELOD_MESHLAB_API >= 2022
// The attributes MeshLab writes for a parameter's value (not its type, label or tooltip).
QString ValueXml(const RichParameter& p) {
  QDomDocument doc;
  QDomElement e = doc.createElement("Param");
  p.value().fillToXMLElement(e);
  QStringList kv;
  const QDomNamedNodeMap a = e.attributes();
  for (int i = 0; i < a.count(); ++i) kv << a.item(i).nodeName() + "=" + a.item(i).nodeValue();
  kv.sort();
  return kv.join(" ");
}

void Scripts(Run& r, const QString& dirPath) {
  const QStringList files = QDir(dirPath).entryList(QStringList() << "*.mlx", QDir::Files, QDir::Name);
  Check(files.size() == int(sizeof(kAll) / sizeof(kAll[0])),
        QString("%1 scripts in %2").arg(files.size()).arg(dirPath));
  for (const QString& file : files) {
    const QString path = QDir(dirPath).filePath(file);
    FilterScript script;
    Check(script.open(path) && script.size() == 1, "FilterScript::open reads " + file);
    if (script.size() != 1) continue;
    const QString name = script.front().filterName();
    QAction* a = r.plugin.action(name);
    Check(a != nullptr, "  its filter exists: " + name);
    if (!a) continue;
    // The script holds every parameter of the filter, at its default (an empty document, as the
    // shipped scripts were written).
    MeshDocument empty;
    const RichParameterList defaults = r.plugin.params(a, empty);
    const RichParameterList& given = script.front().second;
    bool same = given.size() == defaults.size();
    for (const RichParameter& p : defaults) {
      if (!given.hasParameter(p.name())) {
        std::printf("   missing %s\n", qUtf8Printable(p.name()));
        same = false;
      } else if (ValueXml(given.getParameterByName(p.name())) != ValueXml(p)) {
        std::printf("   %s: script %s, plugin %s\n", qUtf8Printable(p.name()),
                    qUtf8Printable(ValueXml(given.getParameterByName(p.name()))), qUtf8Printable(ValueXml(p)));
        same = false;
      }
    }
    Check(same, "  the script's parameters are the plugin's, at its defaults");

    MeshDocument md;
    MeshModel* mm = Load(md, r.bunny);
    const QString clod = r.dir.filePath("script.clod");
    if (name == kGroupQem || name == kIntegrity) {  // they read group ids: group the bunny first
      Check(r.apply(kGrouping, md).isEmpty(), "  grouping first");
      if (name == kIntegrity) {  // as a user would: simplify a copy; the script's reference is layer 0
        MeshModel* copy = md.addNewMesh("", "copy", true);
        copy->updateDataMask(mm);
        vcg::tri::Append<CMeshO, CMeshO>::MeshCopy(copy->cm, mm->cm, false, true);
        Check(r.plugin.runScript(QDir(dirPath).filePath("group_preserving_quadric_edge_collapse.mlx"), md, nullptr)
                  .isEmpty(),
              "  the copy simplified first");
      }
    }
    if (name == kExport || name == kExtract) {
      const Snapshot before = Take(*mm);
      const int layers = Layers(md);
      const QString m = r.plugin.runScript(path, md, nullptr);
      Check(m.contains("'LOD file' is empty") && Layers(md) == layers && Take(*mm) == before,
            "  at its defaults (no file name) it is refused, nothing changed: " + m);
      if (name == kExtract) {  // needs a file to read
        RichParameterList par = r.params(kExport, md);
        harness::SetPath(par, "FileName", clod);
        r.apply(kExport, md, par);
      }
      const QString ok = r.plugin.runScript(path, md, nullptr, {{"FileName", clod}});
      Check(ok.isEmpty(), "  with a file name it runs " + ok);
    } else {
      const QString m = r.plugin.runScript(path, md, nullptr);
      Check(m.isEmpty(), "  it runs at its defaults " + m);
    }
  }
}
#endif

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // our lines and MeshLab's stderr stay in order in a log
  QApplication app(argc, argv);
  if (argc < 4) {
    std::printf("usage: plugin_harness PLUGIN.so BUNNY.ply NAN.ply [--scripts DIR] [--digest OUT] [--compare REF]\n");
    return 2;
  }
  QString scripts, digestOut, compare;
  for (int i = 4; i + 1 < argc; i += 2) {
    const QString opt = argv[i];
    (opt == "--scripts" ? scripts : opt == "--digest" ? digestOut : compare) = QString::fromLocal8Bit(argv[i + 1]);
  }
  std::printf("MeshLab plugin API %d (built against MeshLab %s)\n", CONELOD_MESHLAB_API,
              HARNESS_STRING(MESHLAB_VERSION));
  harness::Plugin plugin;
  QString why;
  const bool loaded = plugin.load(argv[1], why);
  Check(loaded, "MeshLab's PluginManager loads the plugin " + why);
  if (!loaded) return 1;
  Run r{plugin, argv[2], argv[3], {}, {}};
  ListFilters(r);
  ApplyEveryFilter(r);
  RepeatedAndUnusedVertices(r);
  Failures(r);
  Dialogs(r);
#if CONELOD_MESHLAB_API >= 2022
  if (!scripts.isEmpty()) Scripts(r, scripts);
#else
  if (!scripts.isEmpty())
    Check(false, "--scripts: MeshLab 2020.09's scripts run through meshlabserver (tests/integration/cases.py)");
#endif

  QString text;
  for (const auto& kv : r.digest) text += kv.first + ": " + kv.second + "\n";
  std::printf("digest:\n%s", qUtf8Printable(text));
  if (!digestOut.isEmpty()) {
    QFile f(digestOut);
    Check(f.open(QIODevice::WriteOnly) && f.write(text.toUtf8()) == text.toUtf8().size(),
          "digest written to " + digestOut);
  }
  if (!compare.isEmpty()) {
    QFile f(compare);
    const QString ref = f.open(QIODevice::ReadOnly) ? QString::fromUtf8(f.readAll()) : QString();
    const QStringList mine = text.split('\n'), theirs = ref.split('\n');
    for (const QString& line : theirs)
      if (!line.isEmpty()) Check(mine.contains(line), "same as " + QFileInfo(compare).fileName() + ": " + line);
    Check(!ref.isEmpty() && mine.size() == theirs.size(), "as many results as " + compare);
  }
  std::printf("%d failure(s)\n", failures);
  return failures == 0 ? 0 : 1;
}
