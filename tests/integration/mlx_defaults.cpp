// Writes, for every filter of a MeshLab plugin, a one-filter .mlx script holding every parameter
// at its default, using MeshLab's own script writer (FilterScript). The integration tests compare
// these with scripts/mlx/, so the shipped scripts can never fall out of sync with the plugin
// (meshlabserver aborts on a script that misses a parameter).
//   mlx_defaults PLUGIN.so OUT_DIR
#include <QApplication>
#include <QDir>
#include <QPluginLoader>
#include <cstdio>

#include <common/filterscript.h>
#include <common/interfaces.h>
#include <common/meshmodel.h>

// "Cone LOD: Normal Cone Face Grouping" -> "normal_cone_face_grouping"
static QString Slug(QString name) {
  const int colon = name.indexOf(':');
  if (colon >= 0) name = name.mid(colon + 1);
  name = name.trimmed().toLower();
  name.replace(QRegExp("[^a-z0-9]+"), "_");
  return name;
}

int main(int argc, char** argv) {
  QApplication app(argc, argv);
  if (argc != 3) {
    std::fprintf(stderr, "usage: mlx_defaults PLUGIN.so OUT_DIR\n");
    return 1;
  }
  QPluginLoader loader(argv[1]);
  QObject* obj = loader.instance();
  auto* plugin = qobject_cast<MeshFilterInterface*>(obj);
  if (!plugin) {
    std::fprintf(stderr, "cannot load %s: %s\n", argv[1], qPrintable(loader.errorString()));
    return 1;
  }
  QDir().mkpath(argv[2]);
  MeshDocument md;
  md.addNewMesh("", "empty");  // the current mesh of every filter's defaults
  for (QAction* a : plugin->actions()) {
    RichParameterList par;
    plugin->initParameterSet(a, md, par);  // the document form: filters with mesh parameters need it
    FilterScript script;
    FilterNameParameterValuesPair pair;
    pair.first = plugin->filterName(a);
    pair.second = par;
    script.append(pair);
    const QString path = QDir(argv[2]).filePath(Slug(plugin->filterName(a)) + ".mlx");
    if (!script.save(path)) {
      std::fprintf(stderr, "cannot write %s\n", qPrintable(path));
      return 1;
    }
    std::printf("%s\n", qPrintable(path));
  }
  return 0;
}
