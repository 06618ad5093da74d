// conelod-viewer: opens a .clod LOD file, draws its coarsest level at once and refines it while
// the user is idle (lod_viewer_widget.h). With --screenshot it renders in a real window (run it
// under xvfb-run without a display), writes the picture, prints the figures and exits. A file
// with vertex colours and normals (version 5) is drawn with them; --color-levels (or the c key)
// shows one colour per level instead.
//
//   conelod-viewer FILE.clod [--budget F] [--priority screen|error|fg] [--pixel-error PX] [--flat]
//                            [--color-levels] [--no-cull] [--no-hud]
//   conelod-viewer FILE.clod --screenshot OUT.png [--size WxH] [--eye X,Y,Z] [--budget F]
//                  [--refine] [--frames N] [--json]
// Exit codes: 0 ok, 1 usage, 2 bad file, 3 cannot write the picture, 4 no OpenGL.
#include <cmath>
#include <QApplication>
#include <QCommandLineParser>
#include <QElapsedTimer>
#include <QFileInfo>
#include <QJsonDocument>
#include <QJsonObject>
#include <QSurfaceFormat>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "lod_viewer_widget.h"
#include "conelod/mesh/safe_file.h"
#include "conelod/process_memory.h"

namespace {

int Fail(int code, const QString& message) {
  std::fprintf(stderr, "conelod-viewer: %s\n", qUtf8Printable(message));
  return code;
}

// A failure about the file at `path`: the message names it once ("PATH: why"; the reader's own
// messages already name it).
int FailFile(const QString& path, const std::string& why) {
  const QString message = QString::fromStdString(why);
  return Fail(2, message.contains(path) ? message : path + ": " + message);
}

QJsonObject ToJson(const FrameStats& s) {
  QJsonObject o;
  o["faces_drawn"] = double(s.facesDrawn);
  o["groups_drawn"] = double(s.groupsDrawn);
  o["groups_culled"] = double(s.groupsCulled);
  o["groups_front"] = double(s.groupsFront);
  o["cut_faces"] = double(s.cutFaces);
  o["cut_nodes"] = double(s.cutNodes);
  o["min_level"] = s.minLevel;
  o["max_level"] = s.maxLevel;
  o["max_pixel_error"] = s.maxPixelError;
  o["budget_reached"] = s.budgetReached;
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  QElapsedTimer clock;  // time to first frame counts from here
  clock.start();
  // Qt aborts without a display: say what to do instead.
  if (!std::getenv("DISPLAY") && !std::getenv("WAYLAND_DISPLAY") && !std::getenv("QT_QPA_PLATFORM"))
    return Fail(4, "no display: run it under an X server (headless: xvfb-run -a conelod-viewer ...)");
  QSurfaceFormat format;
  format.setDepthBufferSize(24);
  QSurfaceFormat::setDefaultFormat(format);
  QApplication app(argc, argv);
  QApplication::setApplicationName("conelod-viewer");

  QCommandLineParser parser;
  parser.setApplicationDescription(
      "Shows a ConeLOD .clod file: the coarsest level at once, refined while the view is still.\n"
      "Mouse: left drag rotates, right drag or wheel zooms. Keys: C colour per level, B back-face "
      "culling, H text overlay, R reset view, Space refine again, Q quit.");
  parser.addHelpOption();
  parser.addPositionalArgument("file", "the .clod file (conelod lod build)");
  const QCommandLineOption budget("budget", "face budget of the refined cut (default 500000)", "F", "500000");
  const QCommandLineOption flat("flat", "flat shading (face normals)");
  const QCommandLineOption colours(
      "color-levels", "one colour per level (as conelod lod extract's output) instead of the file's vertex colours");
  const QCommandLineOption noCull("no-cull", "no back-face culling (neither per group nor on the GPU)");
  const QCommandLineOption noHud("no-hud", "no text overlay");
  const QCommandLineOption screenshot("screenshot", "render, save the picture to OUT.png and exit", "OUT.png");
  const QCommandLineOption size("size", "window size (default 800x600)", "WxH", "800x600");
  const QCommandLineOption eye("eye", "eye position in model coordinates (default: framed from +Z)", "X,Y,Z");
  const QCommandLineOption refine("refine", "with --screenshot: refine to the budget before the picture");
  const QCommandLineOption frames("frames", "with --screenshot: frames timed for the fps figure (default 30)", "N",
                                  "30");
  const QCommandLineOption json("json", "with --screenshot: print the figures as one JSON line");
  const QCommandLineOption priority(
      "priority",
      "what is refined first: screen (the error projected in pixels, default), "
      "error (by the error in model units, what an expansion gains per face) or fg (the paper's f(g))",
      "P", "screen");
  const QCommandLineOption pixelError("pixel-error",
                                      "with --priority screen: refine while a group's error projects to more "
                                      "than this many pixels (default 1; 0: refine to the budget)",
                                      "PX", "1");
  parser.addOptions(
      {budget, flat, colours, noCull, noHud, screenshot, size, eye, refine, frames, json, priority, pixelError});
  if (!parser.parse(QApplication::arguments())) return Fail(1, parser.errorText());
  if (parser.isSet("help")) parser.showHelp(0);
  if (parser.positionalArguments().size() != 1) return Fail(1, "give one .clod file (--help for usage)");
  const QString path = parser.positionalArguments()[0];

  ViewerOptions options;
  bool ok = true;
  const double budgetFaces = parser.value(budget).toDouble(&ok);
  if (!ok || !std::isfinite(budgetFaces) || budgetFaces < 1 || budgetFaces > 1e15)  // "inf" parses as a double
    return Fail(1, "--budget needs a face count from 1 to 1e15");
  options.faceBudget = size_t(budgetFaces);
  options.flatShading = parser.isSet(flat);
  options.colourLevels = parser.isSet(colours);
  options.cullBackFacing = !parser.isSet(noCull);
  const QString pr = parser.value(priority);
  if (pr == "screen")
    options.priority = conelod::LodPriority::ScreenError;
  else if (pr == "error")
    options.priority = conelod::LodPriority::ObjectError;
  else if (pr == "fg")
    options.priority = conelod::LodPriority::ConeFg;
  else
    return Fail(1, "--priority needs screen, error or fg");
  options.pixelError = parser.value(pixelError).toDouble(&ok);
  if (!ok || !(options.pixelError >= 0) || !std::isfinite(options.pixelError))
    return Fail(1, "--pixel-error needs a number of pixels >= 0");
  options.hud = !parser.isSet(noHud);
  options.refineWhenIdle = !parser.isSet(screenshot);  // headless: the coarse frame, then --refine at once
  const QStringList wh = parser.value(size).split('x');
  const int width = wh.size() == 2 ? wh[0].toInt() : 0, height = wh.size() == 2 ? wh[1].toInt() : 0;
  if (width < 16 || height < 16 || width > 8192 || height > 8192) return Fail(1, "--size needs WxH, e.g. 800x600");
  QVector3D eyePosition;
  if (parser.isSet(eye)) {
    const QStringList xyz = parser.value(eye).split(',');
    bool okx = xyz.size() == 3, oky = okx, okz = okx;
    if (okx) eyePosition = QVector3D(xyz[0].toFloat(&okx), xyz[1].toFloat(&oky), xyz[2].toFloat(&okz));
    if (!okx || !oky || !okz || !std::isfinite(eyePosition.x()) || !std::isfinite(eyePosition.y()) ||
        !std::isfinite(eyePosition.z()))
      return Fail(1, "--eye needs X,Y,Z (three finite numbers)");
  }
  const int benchFrames = parser.value(frames).toInt(&ok);
  if (!ok || benchFrames < 0) return Fail(1, "--frames needs a count >= 0");

  // A FIFO (or a device) would block the open below for ever: refused before it is opened.
  const std::string notRegular = conelod::CheckInputPath(path.toStdString(), true);
  if (!notRegular.empty()) return Fail(2, QString::fromStdString(notRegular));
  std::unique_ptr<conelod::LodReader> reader;
  QElapsedTimer openTimer;
  openTimer.start();
  const conelod::Status opened = conelod::LodReader::Open(path.toStdString(), reader);
  if (!opened.ok()) return FailFile(path, opened.message);
  const double openMs = openTimer.nsecsElapsed() * 1e-6;

  LodViewerWidget widget(*reader, QFileInfo(path).fileName().toStdString(), options);
  widget.setStartClock(clock);
  widget.resize(width, height);
  if (parser.isSet(eye)) widget.setEye(eyePosition);
  widget.show();
  if (!parser.isSet(screenshot)) return app.exec();

  // Headless: wait for the window's first image (the first frame on the window; at most 2 s more
  // once the frame is drawn, should the platform never say it swapped), then measure.
  QElapsedTimer waited;
  waited.start();
  while (widget.firstImageMsecs() < 0 && waited.elapsed() < 20000 &&
         (widget.firstFrameMsecs() < 0 || waited.elapsed() < widget.firstFrameMsecs() + 2000))
    app.processEvents(QEventLoop::AllEvents, 20);
  if (!widget.isValid() || widget.firstFrameMsecs() < 0)
    return Fail(4, "no OpenGL context: run with an X server that has GLX (e.g. xvfb-run -a conelod-viewer ...)");
  if (!widget.error().empty()) return FailFile(path, widget.error());
  const FrameStats coarse = widget.lastFrame();
  double refineSeconds = 0;
  if (parser.isSet(refine) && !widget.refineToDone(&refineSeconds)) return FailFile(path, widget.error());
  const double frameMs = widget.benchmarkFrames(benchFrames);
  const QImage image = widget.grabFramebuffer();
  const FrameStats last = widget.lastFrame();
  if (!widget.error().empty()) return FailFile(path, widget.error());
  const QString out = parser.value(screenshot);
  if (image.isNull() || !image.save(out)) return Fail(3, "cannot write " + out);

  const conelod::LodFileInfo& info = reader->info();
  QJsonObject o;
  o["file"] = path;
  o["screenshot"] = out;
  o["width"] = image.width();
  o["height"] = image.height();
  o["budget"] = double(options.faceBudget);
  o["input_faces"] = double(info.inputFaces);
  o["levels"] = info.levels;
  o["nodes"] = double(info.nodeCount);
  o["open_ms"] = openMs;
  o["first_frame_ms"] = widget.firstFrameMsecs();
  o["first_image_ms"] = widget.firstImageMsecs();
  o["first_image_cpu_ms"] = widget.firstImageCpuMsecs();
  o["coarse"] = ToJson(coarse);
  if (parser.isSet(refine)) {
    QJsonObject r = ToJson(last);
    r["refine_ms"] = refineSeconds * 1e3;
    o["refined"] = r;
  }
  o["frames"] = benchFrames;
  o["frame_ms"] = frameMs;
  o["fps"] = frameMs > 0 ? 1000.0 / frameMs : 0.0;
  o["resident_bytes"] = double(reader->residentBytes());
  o["gpu_bytes"] = double(widget.gpuBytes());
  o["process_rss_bytes"] = double(conelod::ProcessStatusBytes("VmRSS"));
  if (parser.isSet(json)) {
    std::printf("%s\n", QJsonDocument(o).toJson(QJsonDocument::Compact).constData());
  } else {
    std::printf("%s: %dx%d, first frame after %.0f ms (open %.1f ms): %zu faces drawn, %zu groups drawn, %zu culled\n",
                qUtf8Printable(out), image.width(), image.height(), widget.firstFrameMsecs(), openMs, coarse.facesDrawn,
                coarse.groupsDrawn, coarse.groupsCulled);
    if (parser.isSet(refine))
      std::printf("refined in %.0f ms: %zu faces drawn, %zu groups drawn, %zu culled, levels %d-%d\n",
                  refineSeconds * 1e3, last.facesDrawn, last.groupsDrawn, last.groupsCulled, last.minLevel,
                  last.maxLevel);
    if (benchFrames > 0)
      std::printf("%.2f ms per frame (%.1f fps) over %d frames\n", frameMs, 1000.0 / frameMs, benchFrames);
  }
  return 0;
}
