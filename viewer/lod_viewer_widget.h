// conelod-viewer: the widget that draws a .clod file and refines it while the user is idle.
//
// Kamiya, Suzuki, Kawachi, "LODs for efficient displaying triangle meshes", §7: the
// coarsest level is drawn at once; while the user rotates or zooms only that level is drawn, and
// when the view has been still for a moment the cut is refined in idle-time slices, in the order
// of the paper's priority f(g), until the face budget or the finest level is reached. Every frame
// tests each node of the cut once against the eye (three-state normal-cone test, perspective-
// correct: normal_cone.h's ClassifyPerspective) and skips the back-facing ones.
//
// GPU data: one vertex buffer (positions, normals, colours) and one index buffer per node of the cut,
// uploaded when the node enters the cut and freed when it leaves (the refiner then evicts the
// node's geometry from the reader too). OpenGL 2.1 / GLSL 1.10 (GLES 2 compatible), so that Mesa's
// llvmpipe under Xvfb runs it.
#pragma once

#include <QElapsedTimer>
#include <QMatrix4x4>
#include <QOpenGLBuffer>
#include <QOpenGLFunctions>
#include <QOpenGLShaderProgram>
#include <QOpenGLTexture>
#include <QOpenGLWidget>
#include <QQuaternion>
#include <QTimer>
#include <QVector3D>
#include <memory>
#include <string>
#include <unordered_map>

#include "conelod/lod/lod_read.h"

struct ViewerOptions {
  size_t faceBudget = 500000;  // faces of the refined cut (the roots may exceed it)
  bool cullBackFacing = true;  // per-frame cone test; the refiner also refines back-facing nodes last
  bool flatShading = false;    // flat face normals (unshared vertices) instead of per-vertex normals
  bool colourLevels = false;   // one colour per node level (GroupColor(level), as conelod lod extract)
                               // instead of the file's vertex colours (version 5 files; else grey);
                               // a file's stored normals shade it smoothly unless flatShading
  int stillMs = 150;           // the view counts as still after this long without input
  bool refineWhenIdle = true;  // false: only refineToDone() refines (headless measurements)
  bool hud = true;             // the text overlay
  double sliceMs = 8;          // refinement work per idle-time tick (at least the last frame's time)
  // What the refinement expands first: the screen-space error (refined while a group's error
  // projects to more than pixelError pixels, within the budget), or the paper's f(g).
  conelod::LodPriority priority = conelod::LodPriority::ScreenError;
  double pixelError = 1.0;  // 0: no pixel threshold (refine to the budget)
};

// What the last frame drew.
struct FrameStats {
  size_t cutNodes = 0, cutFaces = 0;
  size_t facesDrawn = 0, groupsDrawn = 0, groupsCulled = 0;
  size_t groupsFront = 0;          // drawn groups whose every face faces the eye (three-state test)
  int minLevel = 0, maxLevel = 0;  // over the drawn nodes
  double maxPixelError = 0;        // the largest projected error of a drawn node, pixels (ProjectedError)
  bool budgetReached = false;      // the refinement stopped at the face budget
  double renderMs = 0;             // drawing time of the frame, glFinish included (HUD excluded)
};

class LodViewerWidget : public QOpenGLWidget, protected QOpenGLFunctions {
  Q_OBJECT

 public:
  LodViewerWidget(conelod::LodReader& reader, const std::string& title, const ViewerOptions& options,
                  QWidget* parent = nullptr);
  ~LodViewerWidget() override;

  // Camera: the model rotates about its box centre; the eye looks at the centre.
  void frameModel();                                    // front view (+Z), the bounding sphere fills the view
  void setEye(const QVector3D& eyeInModelCoordinates);  // look at the centre from there
  conelod::LodView currentView() const;

  // Headless use (screenshots, tests): refine synchronously until Done(); false on a read error.
  bool refineToDone(double* seconds = nullptr);
  // Renders `frames` frames into the widget's framebuffer, waiting for each (glFinish), turning
  // the model a little between frames (the per-node cone tests included); returns the mean
  // milliseconds per frame and shows the resulting frames per second in the HUD from then on.
  double benchmarkFrames(int frames);
  const FrameStats& lastFrame() const { return stats_; }
  // The first frame: the roots drawn into the widget's framebuffer and waited for (glFinish),
  // milliseconds since the clock given below; -1 before it.
  double firstFrameMsecs() const { return firstFrameMsecs_; }
  // The first image: that frame composed onto the window and swapped (QOpenGLWidget::frameSwapped),
  // since the same clock; -1 before it.
  double firstImageMsecs() const { return firstImageMsecs_; }
  // The process's CPU time (all its threads, from its start) at the first image; -1 before it.
  double firstImageCpuMsecs() const { return firstImageCpuMsecs_; }
  void setStartClock(const QElapsedTimer& clock) { startClock_ = clock; }
  size_t gpuBytes() const { return gpuBytes_; }
  const std::string& error() const { return error_; }  // a read error during refinement

 protected:
  void initializeGL() override;
  void resizeGL(int w, int h) override;
  void paintGL() override;
  void mousePressEvent(QMouseEvent* e) override;
  void mouseMoveEvent(QMouseEvent* e) override;
  void mouseReleaseEvent(QMouseEvent* e) override;
  void wheelEvent(QWheelEvent* e) override;
  void keyPressEvent(QKeyEvent* e) override;

 private:
  struct NodeBuffers {
    QOpenGLBuffer vertices{QOpenGLBuffer::VertexBuffer};
    QOpenGLBuffer indices{QOpenGLBuffer::IndexBuffer};
    int indexCount = 0;  // 0: flat shading, drawn with glDrawArrays
    int vertexCount = 0;
    size_t bytes = 0;
  };

  void interactionStarted();  // back to the coarsest cut, refinement paused
  void viewStill();           // restart the refinement for the current view
  void refineSlice();         // one idle-time tick of Step()
  void syncBuffers();         // upload the cut's new nodes, free those that left it
  bool upload(uint32_t node, NodeBuffers& b);
  void renderScene();
  void drawHud();
  void loadTexture();  // the file's texture image into texture_ (context current)
  QMatrix4x4 viewMatrix() const;
  QMatrix4x4 projectionMatrix() const;
  QVector3D eyeInModel() const;

  conelod::LodReader& reader_;
  std::unique_ptr<conelod::LodRefiner> refiner_;
  std::string title_;
  ViewerOptions options_;
  std::string error_;

  QOpenGLShaderProgram program_;
  std::unique_ptr<QOpenGLTexture> texture_;  // the file's texture image (its TEXR chunk), when it has one
  std::unordered_map<uint32_t, NodeBuffers> buffers_;
  size_t gpuBytes_ = 0;
  bool cutChanged_ = true;  // the refiner's cut changed since the last syncBuffers()

  QVector3D centre_;
  float radius_ = 1;
  float distance_ = 3;
  QQuaternion rotation_;
  QPoint lastMouse_;
  bool dragging_ = false;

  QTimer stillTimer_, idleTimer_;
  bool refining_ = false;

  FrameStats stats_;
  QElapsedTimer startClock_;
  double firstFrameMsecs_ = -1;
  double firstImageMsecs_ = -1;
  double firstImageCpuMsecs_ = -1;
  double fps_ = 0;       // 1000 / the last frame's drawing time, or the benchmark's mean
  int benchmarked_ = 0;  // frames of benchmarkFrames behind fps_ (0: fps_ is the last frame's)
};
