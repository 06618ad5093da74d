// Drives the built plugin in-process, as MeshLab does (QPluginLoader, initParameterSet,
// applyFilter on a MeshDocument), to check what meshlabserver cannot show: a filter that fails
// (bad parameters, bad input, cancellation) leaves the mesh exactly as it was.
//   plugin_harness PLUGIN.so GOOD.ply NAN.ply       exit 0 when every check passes
#include <QApplication>
#include <QFile>
#include <QFileInfo>
#include <QPluginLoader>
#include <QTemporaryDir>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <vector>

#include <common/GLLogStream.h>
#include <common/interfaces.h>
#include <common/meshmodel.h>
#include <wrap/io_trimesh/import_ply.h>

namespace {

int failures = 0;
#define CHECK(cond, what)                                            \
  do {                                                               \
    if (!(cond)) { std::printf("FAIL: %s\n", what); ++failures; }    \
    else std::printf("ok: %s\n", what);                              \
  } while (0)

// What a filter could change: positions, per-face quality/colour (when enabled), attributes.
struct Snapshot {
  std::vector<float> coords;
  int mask = 0;
  std::vector<float> quality;
  std::vector<unsigned> colour;
  size_t faceAttributes = 0;
  bool operator==(const Snapshot& o) const {
    if (coords.size() != o.coords.size()) return false;
    for (size_t i = 0; i < coords.size(); ++i)  // NaN == NaN here: bitwise
      if (std::memcmp(&coords[i], &o.coords[i], sizeof(float)) != 0) return false;
    return mask == o.mask && quality == o.quality && colour == o.colour && faceAttributes == o.faceAttributes;
  }
};

Snapshot Take(MeshModel& mm) {
  Snapshot s;
  for (const auto& v : mm.cm.vert)
    for (int k = 0; k < 3; ++k) s.coords.push_back(v.cP()[k]);
  s.mask = mm.dataMask();
  if (mm.hasDataMask(MeshModel::MM_FACEQUALITY))
    for (const auto& f : mm.cm.face) s.quality.push_back(f.cQ());
  if (mm.hasDataMask(MeshModel::MM_FACECOLOR))
    for (const auto& f : mm.cm.face) {
      const auto& c = f.cC();
      s.colour.push_back(unsigned(c[0]) << 24 | unsigned(c[1]) << 16 | unsigned(c[2]) << 8 | c[3]);
    }
  s.faceAttributes = mm.cm.face_attr.size();
  return s;
}

MeshModel* Load(MeshDocument& md, const char* path) {
  MeshModel* mm = md.addNewMesh(path, "m");
  int mask = 0;
  if (vcg::tri::io::ImporterPLY<CMeshO>::Open(mm->cm, path, mask) != 0) {
    std::printf("cannot load %s\n", path);
    std::exit(2);
  }
  mm->cm.face.EnableFFAdjacency();  // nothing of ours needs it: only to vary the mask
  mm->cm.face.DisableFFAdjacency();
  return mm;
}

bool cancelAtOnce(const int, const char*) { return false; }

}  // namespace

int main(int argc, char** argv) {
  QApplication app(argc, argv);
  if (argc != 4) { std::printf("usage: plugin_harness PLUGIN.so GOOD.ply NAN.ply\n"); return 2; }
  QPluginLoader loader(argv[1]);
  auto* plugin = qobject_cast<MeshFilterInterface*>(loader.instance());
  if (!plugin) { std::printf("cannot load the plugin: %s\n", qPrintable(loader.errorString())); return 2; }
  GLLogStream log;
  plugin->setLog(&log);
  QAction* grouping = plugin->AC("Cone LOD: Normal Cone Face Grouping");
  QAction* culling = plugin->AC("Cone LOD: Cluster Culling Cost");
  CHECK(grouping && culling, "both filters found by name");
  if (!grouping || !culling) return 1;

  auto params = [&](QAction* a, MeshModel& mm) {
    RichParameterList par;
    plugin->initParameterSet(a, mm, par);
    return par;
  };

  {  // Bad parameter: refused, mesh unchanged.
    MeshDocument md;
    MeshModel* mm = Load(md, argv[2]);
    const Snapshot before = Take(*mm);
    RichParameterList par = params(grouping, *mm);
    par.setValue("ConeThresholdDeg", FloatValue(0.0f));
    CHECK(!plugin->applyFilter(grouping, md, par, nullptr), "ConeThresholdDeg = 0 is refused");
    CHECK(plugin->errorMsg().contains("'Cone threshold (deg)'") && !plugin->errorMsg().contains("ConeThresholdDeg"),
          "the message names the dialog's label, 'Cone threshold (deg)'");
    CHECK(Take(*mm) == before, "the mesh is unchanged after a refused parameter");
  }
  {  // Cancellation through MeshLab's callback: refused, mesh unchanged.
    MeshDocument md;
    MeshModel* mm = Load(md, argv[2]);
    const Snapshot before = Take(*mm);
    CHECK(!plugin->applyFilter(grouping, md, params(grouping, *mm), cancelAtOnce), "a cancelled run fails");
    CHECK(plugin->errorMsg().contains("cancel"), "the message says it was cancelled");
    CHECK(Take(*mm) == before, "the mesh is unchanged after cancellation");
  }
  {  // NaN coordinates: both filters refuse, mesh unchanged.
    MeshDocument md;
    MeshModel* mm = Load(md, argv[3]);
    const Snapshot before = Take(*mm);
    CHECK(!plugin->applyFilter(grouping, md, params(grouping, *mm), nullptr), "grouping refuses NaN input");
    CHECK(plugin->errorMsg().contains("NaN"), "the message names NaN");
    CHECK(!plugin->applyFilter(culling, md, params(culling, *mm), nullptr), "culling cost refuses NaN input");
    CHECK(Take(*mm) == before, "the mesh is unchanged after NaN input");
  }
  {  // Success: quality, colour and one attribute per level are written.
    MeshDocument md;
    MeshModel* mm = Load(md, argv[2]);
    CHECK(plugin->applyFilter(grouping, md, params(grouping, *mm), nullptr), "grouping succeeds");
    CHECK(mm->hasDataMask(MeshModel::MM_FACEQUALITY | MeshModel::MM_FACECOLOR), "quality and colour enabled");
    auto l1 = vcg::tri::Allocator<CMeshO>::FindPerFaceAttribute<int>(mm->cm, "conelod_group_L1");
    CHECK(vcg::tri::Allocator<CMeshO>::IsValidHandle(mm->cm, l1), "attribute conelod_group_L1 exists");
    bool same = true;
    for (const auto& f : mm->cm.face) same = same && int(f.cQ()) == l1[f];
    CHECK(same, "quality = level-1 group id (DisplayLevel 1)");
    const Snapshot after = Take(*mm);
    CHECK(!plugin->applyFilter(culling, md, [&] { auto p = params(culling, *mm); p.setValue("Views", IntValue(0)); return p; }(), nullptr),
          "culling cost refuses Views = 0");
    CHECK(Take(*mm) == after, "a failed culling run leaves the grouped mesh as it was");
    CHECK(plugin->applyFilter(culling, md, params(culling, *mm), nullptr), "culling cost succeeds");
    CHECK(Take(*mm) == after, "culling cost does not change the mesh");
  }
  {  // The LOD filters: export writes a file and changes nothing; extract adds one layer; failures
     // (cancelled, missing or corrupt file, empty mesh) leave the mesh as it was, add no layer and
     // leave no file.
    QAction* exportLod = plugin->AC("Cone LOD: Export LOD File");
    QAction* extractLod = plugin->AC("Cone LOD: Extract View-Dependent LOD");
    CHECK(exportLod && extractLod, "both LOD filters found by name");
    QTemporaryDir dir;
    if (exportLod && extractLod && dir.isValid()) {
      MeshDocument md;
      MeshModel* mm = Load(md, argv[2]);
      const Snapshot before = Take(*mm);
      auto exportParams = [&](MeshModel& m, const QString& path) {
        RichParameterList p = params(exportLod, m);
        p.setValue("FileName", FileValue(path));
        return p;
      };
      auto extractParams = [&](const QString& path) {
        RichParameterList p;
        plugin->initParameterSet(extractLod, md, p);
        p.setValue("FileName", FileValue(path));
        p.setValue("FaceBudget", IntValue(0));
        return p;
      };
      const QString clod = dir.filePath("m.clod"), cancelled = dir.filePath("cancelled.clod");
      CHECK(!plugin->applyFilter(exportLod, md, exportParams(*mm, cancelled), cancelAtOnce), "a cancelled export fails");
      CHECK(!QFileInfo::exists(cancelled), "a cancelled export leaves no file");
      CHECK(plugin->applyFilter(exportLod, md, exportParams(*mm, clod), nullptr), "export succeeds");
      CHECK(QFileInfo(clod).size() > 0, "export writes the file");
      CHECK(Take(*mm) == before, "export leaves the mesh unchanged");

      QFile whole(clod);
      whole.open(QIODevice::ReadOnly);
      const QByteArray bytes = whole.readAll();
      const QString truncated = dir.filePath("truncated.clod");
      QFile cut(truncated);
      cut.open(QIODevice::WriteOnly);
      cut.write(bytes.left(bytes.size() / 2));
      cut.close();
      for (const QString& bad : {dir.filePath("missing.clod"), truncated}) {
        const int layers = md.meshList.size();
        CHECK(!plugin->applyFilter(extractLod, md, extractParams(bad), nullptr), "extract refuses a missing or truncated file");
        CHECK(plugin->errorMsg().contains(bad), "the message names the file");
        CHECK(md.meshList.size() == layers && md.mm() == mm, "no layer is added after a failed extract");
        CHECK(Take(*mm) == before, "the mesh is unchanged after a failed extract");
      }
      const int layers = md.meshList.size();
      CHECK(plugin->applyFilter(extractLod, md, extractParams(clod), nullptr), "extract succeeds");
      CHECK(md.meshList.size() == layers + 1 && md.mm() != mm, "extract adds a layer and makes it current");
      CHECK(md.mm()->cm.fn == mm->cm.fn, "without a budget the extract gives back every face of the input");
      CHECK(Take(*mm) == before, "extract leaves the mesh unchanged");

      MeshDocument emptyDoc;
      MeshModel* empty = emptyDoc.addNewMesh("", "empty");
      const QString emptyClod = dir.filePath("empty.clod");
      CHECK(!plugin->applyFilter(exportLod, emptyDoc, exportParams(*empty, emptyClod), nullptr), "export refuses an empty mesh");
      CHECK(!QFileInfo::exists(emptyClod), "a failed export leaves no file");
    }
  }
  std::printf("%d failure(s)\n", failures);
  return failures == 0 ? 0 : 1;
}
