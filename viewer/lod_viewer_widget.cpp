// conelod-viewer: the widget (see lod_viewer_widget.h).
#include "lod_viewer_widget.h"

#include <QImage>
#include <QKeyEvent>
#include <QMouseEvent>
#include <QPainter>
#include <QWheelEvent>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <unordered_set>
#include <vector>

#include "conelod/grouping/group_colors.h"
#include "conelod/grouping/normal_cone.h"
#include "conelod/process_memory.h"

using namespace conelod;

namespace {

const float kFovDeg = 35.0f;
const int kStride = 11;  // floats a vertex: position, normal, colour, texture coordinates

// GLSL 1.10 / GLSL ES 1.00: a headlight, Lambert plus a little specular; both sides lit, so that
// a mesh with flipped faces still shows when culling is off.
const char* const kVertexShader = R"(
attribute vec3 aPosition;
attribute vec3 aNormal;
attribute vec3 aColour;
attribute vec2 aTexCoord;
uniform mat4 uModelView;
uniform mat4 uProjection;
uniform mat3 uNormalMatrix;
varying vec3 vNormal;
varying vec3 vPosition;
varying vec3 vColour;
varying vec2 vTexCoord;
void main() {
  vec4 p = uModelView * vec4(aPosition, 1.0);
  vPosition = p.xyz;
  vNormal = uNormalMatrix * aNormal;
  vColour = aColour;
  vTexCoord = aTexCoord;
  gl_Position = uProjection * p;
}
)";

const char* const kFragmentShader = R"(
#ifdef GL_ES
precision mediump float;
#endif
uniform vec3 uColour;
uniform float uVertexColour;  // 1: the file's vertex colours (times uColour), 0: uColour alone
uniform float uUseTexture;    // 1: times the file's texture image at vTexCoord
uniform sampler2D uTexture;
varying vec3 vNormal;
varying vec3 vPosition;
varying vec3 vColour;
varying vec2 vTexCoord;
void main() {
  vec3 n = normalize(vNormal);
  vec3 l = normalize(-vPosition);
  if (dot(n, l) < 0.0) n = -n;
  float diffuse = max(dot(n, l), 0.0);
  float specular = pow(diffuse, 64.0) * 0.12;
  vec3 albedo = uColour * mix(vec3(1.0), vColour, uVertexColour) *
                mix(vec3(1.0), texture2D(uTexture, vTexCoord).rgb, uUseTexture);
  gl_FragColor = vec4(albedo * (0.18 + 0.82 * diffuse) + vec3(specular), 1.0);
}
)";

QVector3D ToQt(const vcg::Point3f& p) { return QVector3D(p[0], p[1], p[2]); }

QString Thousands(size_t n) {
  QString s = QString::number(qulonglong(n));
  for (int i = s.size() - 3; i > 0; i -= 3) s.insert(i, ',');
  return s;
}

QString MiB(double bytes) { return QString::number(bytes / (1024.0 * 1024.0), 'f', 1) + " MiB"; }

}  // namespace

LodViewerWidget::LodViewerWidget(LodReader& reader, const std::string& title, const ViewerOptions& options,
                                 QWidget* parent)
    : QOpenGLWidget(parent), reader_(reader), refiner_(new LodRefiner(reader)), title_(title), options_(options) {
  const vcg::Box3f& box = reader_.info().box;
  if (!box.IsNull() && box.Diag() > 0) {
    centre_ = ToQt(box.Center());
    radius_ = 0.5f * box.Diag();
  }
  frameModel();
  const Status s = refiner_->Start(currentView());  // the cut = the roots
  if (!s.ok()) error_ = s.message;
  stillTimer_.setSingleShot(true);
  connect(&stillTimer_, &QTimer::timeout, this, &LodViewerWidget::viewStill);
  idleTimer_.setInterval(0);
  connect(&idleTimer_, &QTimer::timeout, this, &LodViewerWidget::refineSlice);
  // The first image is on the window: its time, the process's CPU time so far; the HUD and the
  // file's texture image, left out of the frames before it, come now (under llvmpipe the HUD's
  // fonts and Qt's paint engine cost about a sixth of the process's CPU time to the first image,
  // a 2048 x 2048 texture more than that time again: docs/lod_viewer.md).
  connect(this, &QOpenGLWidget::frameSwapped, this, [this] {
    if (firstImageMsecs_ >= 0 || firstFrameMsecs_ < 0) return;
    firstImageMsecs_ = startClock_.nsecsElapsed() * 1e-6;
    timespec cpu;
    if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &cpu) == 0) firstImageCpuMsecs_ = cpu.tv_sec * 1e3 + cpu.tv_nsec * 1e-6;
    makeCurrent();
    loadTexture();
    doneCurrent();
    update();
  });
  setFocusPolicy(Qt::StrongFocus);
  setWindowTitle(QString("ConeLOD viewer - %1").arg(QString::fromStdString(title_)));
  startClock_.start();
}

LodViewerWidget::~LodViewerWidget() {
  makeCurrent();
  buffers_.clear();  // QOpenGLBuffer destroys its buffer with the context current
  texture_.reset();
  program_.removeAllShaders();
  doneCurrent();
}

void LodViewerWidget::frameModel() {
  rotation_ = QQuaternion();
  distance_ = radius_ / std::sin(0.5f * kFovDeg * float(M_PI) / 180.0f) * 1.05f;
}

void LodViewerWidget::setEye(const QVector3D& eye) {
  const QVector3D d = eye - centre_;
  if (d.length() < 1e-6f * radius_) return frameModel();
  distance_ = d.length();
  const QVector3D dir = d / distance_;
  const QVector3D up = std::abs(dir.y()) > 0.99f ? QVector3D(0, 0, -1) : QVector3D(0, 1, 0);
  QMatrix4x4 look;
  look.lookAt(eye, centre_, up);  // = R * T(-eye); R maps dir to +Z
  rotation_ = QQuaternion::fromRotationMatrix(look.normalMatrix());
}

QVector3D LodViewerWidget::eyeInModel() const {
  return centre_ + rotation_.conjugated().rotatedVector(QVector3D(0, 0, distance_));
}

QMatrix4x4 LodViewerWidget::viewMatrix() const {
  QMatrix4x4 v;
  v.translate(0, 0, -distance_);
  v.rotate(rotation_);
  v.translate(-centre_);
  return v;
}

QMatrix4x4 LodViewerWidget::projectionMatrix() const {
  QMatrix4x4 p;
  const float nearPlane = std::max(distance_ - 1.5f * radius_, 0.01f * radius_);
  p.perspective(kFovDeg, float(std::max(width(), 1)) / float(std::max(height(), 1)), nearPlane,
                distance_ + 1.5f * radius_);
  return p;
}

LodView LodViewerWidget::currentView() const {
  LodView v;
  const QVector3D e = eyeInModel();
  v.eye = vcg::Point3d(e.x(), e.y(), e.z());
  v.faceBudget = options_.faceBudget;
  v.cullBackFacing = options_.cullBackFacing;
  v.priority = options_.priority;
  // Pixels per model unit at distance 1: the viewport's height over the view's height there.
  v.projectionScale = double(std::max(height(), 1)) / (2 * std::tan(0.5 * double(kFovDeg) * M_PI / 180.0));
  v.maxPixelError = options_.pixelError;
  return v;
}

// --- Refinement -----------------------------------------------------------------------------

void LodViewerWidget::interactionStarted() {
  stillTimer_.start(options_.stillMs);
  if (!refining_ && refiner_->cut().refinements == 0) return;  // already the coarsest cut
  idleTimer_.stop();
  refining_ = false;
  const Status s = refiner_->Start(currentView());
  cutChanged_ = true;
  if (!s.ok()) error_ = s.message;
}

void LodViewerWidget::viewStill() {
  if (dragging_) return;  // still pressed: wait for the release
  const Status s = refiner_->Start(currentView());
  cutChanged_ = true;
  if (!s.ok()) {
    error_ = s.message;
    return;
  }
  refining_ = true;
  idleTimer_.start();
}

void LodViewerWidget::refineSlice() {
  // At least as long as the last frame took: when frames are slow, refinement still gets half of
  // the time instead of crawling between repaints.
  const double sliceMs = std::max(options_.sliceMs, stats_.renderMs);
  QElapsedTimer t;
  t.start();
  while (!refiner_->Done() && t.nsecsElapsed() < qint64(sliceMs * 1e6)) {
    const Status s = refiner_->Step(16);
    cutChanged_ = true;
    if (!s.ok()) {
      error_ = s.message;
      break;
    }
  }
  if (refiner_->Done() || !error_.empty()) {
    idleTimer_.stop();
    refining_ = false;
  }
  update();
}

bool LodViewerWidget::refineToDone(double* seconds) {
  QElapsedTimer t;
  t.start();
  Status s = refiner_->Start(currentView());
  while (s.ok() && !refiner_->Done()) s = refiner_->Step(64);
  cutChanged_ = true;
  if (!s.ok()) error_ = s.message;
  if (seconds) *seconds = t.nsecsElapsed() * 1e-9;
  return s.ok();
}

// --- GPU buffers ----------------------------------------------------------------------------

bool LodViewerWidget::upload(uint32_t id, NodeBuffers& b) {
  if (!reader_.geometry(id)) {
    const Status s = reader_.LoadGeometry(id);
    if (!s.ok()) {
      error_ = s.message;
      return false;
    }
  }
  const LodGeometry& g = *reader_.geometry(id);
  static const LodAttributes kNone;
  const LodAttributes& ga = reader_.attributes(id) ? *reader_.attributes(id) : kNone;
  // Position, normal, colour (the file's, else white), texture coordinates (the file's, else 0).
  std::vector<float> interleaved;
  const bool colours = !ga.colors.empty(), uvs = !ga.texCoords.empty();
  auto put = [&](const vcg::Point3f& p, const vcg::Point3f& n, uint32_t v) {
    float c[3] = {1, 1, 1}, t[2] = {0, 0};
    if (colours)
      for (int k = 0; k < 3; ++k) c[k] = ga.colors[v][size_t(k)] / 255.0f;
    if (uvs) conelod::DecodeLodTexCoord(ga.texCoords[v], ga.uvMin, ga.uvMax, t);
    interleaved.insert(interleaved.end(), {p[0], p[1], p[2], n[0], n[1], n[2], c[0], c[1], c[2], t[0], t[1]});
  };
  auto faceNormal = [&g](const std::array<uint32_t, 3>& f) {  // length = twice the area
    return (g.positions[f[1]] - g.positions[f[0]]) ^ (g.positions[f[2]] - g.positions[f[0]]);
  };
  if (options_.flatShading) {
    interleaved.reserve(g.faces.size() * 3 * kStride);
    for (const auto& f : g.faces) {
      const vcg::Point3f n = faceNormal(f).Normalize();
      for (uint32_t v : f) put(g.positions[v], n, v);
    }
    b.vertexCount = int(g.faces.size() * 3);
    b.indexCount = 0;
  } else {
    // The file's normals (version 5), else area-weighted vertex normals within the node. Nodes
    // share no vertex buffer, so computed normals of a vertex on a group border may differ a
    // little on both sides: a faint seam at most (stored ones are the same on both sides).
    std::vector<vcg::Point3f> normals(g.positions.size(), vcg::Point3f(0, 0, 0));
    if (!ga.normals.empty()) {
      for (size_t v = 0; v < g.positions.size(); ++v) normals[v] = conelod::DecodeLodNormal(ga.normals[v]);
    } else {
      for (const auto& f : g.faces) {
        const vcg::Point3f n = faceNormal(f);
        for (uint32_t v : f) normals[v] += n;
      }
    }
    interleaved.reserve(g.positions.size() * kStride);
    for (size_t v = 0; v < g.positions.size(); ++v) put(g.positions[v], normals[v].Normalize(), uint32_t(v));
    b.vertexCount = int(g.positions.size());
    b.indexCount = int(g.faces.size() * 3);
  }
  b.vertices.create();
  b.vertices.bind();
  b.vertices.allocate(interleaved.data(), int(interleaved.size() * sizeof(float)));
  b.bytes = interleaved.size() * sizeof(float);
  if (b.indexCount) {
    std::vector<uint32_t> indices;
    indices.reserve(size_t(b.indexCount));
    for (const auto& f : g.faces) indices.insert(indices.end(), f.begin(), f.end());
    b.indices.create();
    b.indices.bind();
    b.indices.allocate(indices.data(), int(indices.size() * sizeof(uint32_t)));
    b.bytes += indices.size() * sizeof(uint32_t);
  }
  // The GPU holds the node now; the reader reads it again if the node ever comes back.
  reader_.EvictGeometry(id);
  return true;
}

void LodViewerWidget::syncBuffers() {
  if (!cutChanged_) return;
  cutChanged_ = false;
  const LodCut& cut = refiner_->cut();
  const std::unordered_set<uint32_t> inCut(cut.nodes.begin(), cut.nodes.end());
  for (auto it = buffers_.begin(); it != buffers_.end();) {
    if (inCut.count(it->first)) {
      ++it;
      continue;
    }
    gpuBytes_ -= it->second.bytes;
    it = buffers_.erase(it);  // ~QOpenGLBuffer frees the GL buffers (context is current)
  }
  for (uint32_t id : cut.nodes) {
    if (buffers_.count(id)) continue;
    NodeBuffers& b = buffers_[id];
    if (!upload(id, b)) {
      buffers_.erase(id);
      break;
    }
    gpuBytes_ += b.bytes;
  }
}

// --- Drawing --------------------------------------------------------------------------------

void LodViewerWidget::initializeGL() {
  initializeOpenGLFunctions();
  if (!program_.addShaderFromSourceCode(QOpenGLShader::Vertex, kVertexShader) ||
      !program_.addShaderFromSourceCode(QOpenGLShader::Fragment, kFragmentShader) || !program_.link())
    error_ = "shader: " + program_.log().toStdString();
}

// The texture image stored in the file, decoded by Qt (v up, as the PLY's coordinates: the
// image's rows bottom first), with the context current. One that does not decode is said on
// stderr and not drawn. Called once the first image is on the window (the constructor), as the
// web viewer reads it beside its first image: until then the model is drawn without it.
void LodViewerWidget::loadTexture() {
  if (!reader_.info().texCoords || !reader_.info().textureBytes) return;
  conelod::LodTexture tex;
  const Status s = reader_.LoadTexture(tex);
  QImage image;
  if (s.ok() && image.loadFromData(tex.bytes.data(), int(tex.bytes.size()))) {
    texture_.reset(new QOpenGLTexture(image.mirrored()));
    texture_->setMinificationFilter(QOpenGLTexture::LinearMipMapLinear);
    texture_->setMagnificationFilter(QOpenGLTexture::Linear);
    texture_->setWrapMode(QOpenGLTexture::Repeat);
  } else {
    std::fprintf(stderr, "conelod-viewer: the texture image %s is not drawn: %s\n", reader_.info().textureName.c_str(),
                 s.ok() ? "Qt cannot decode it" : s.message.c_str());
  }
}

void LodViewerWidget::resizeGL(int, int) {}

void LodViewerWidget::renderScene() {
  QElapsedTimer t;
  t.start();
  const qreal dpr = devicePixelRatioF();
  glViewport(0, 0, int(width() * dpr), int(height() * dpr));
  glClearColor(0.13f, 0.14f, 0.17f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  if (options_.cullBackFacing)
    glEnable(GL_CULL_FACE);  // what the group test leaves, the GPU culls
  else
    glDisable(GL_CULL_FACE);

  FrameStats s;
  const LodCut& cut = refiner_->cut();
  s.cutNodes = cut.nodes.size();
  s.minLevel = INT32_MAX;
  s.maxLevel = -1;
  if (!program_.isLinked()) return;
  program_.bind();
  const QMatrix4x4 view = viewMatrix();
  program_.setUniformValue("uModelView", view);
  program_.setUniformValue("uProjection", projectionMatrix());
  program_.setUniformValue("uNormalMatrix", view.normalMatrix());
  const int position = program_.attributeLocation("aPosition"), normal = program_.attributeLocation("aNormal"),
            colour = program_.attributeLocation("aColour"), texCoord = program_.attributeLocation("aTexCoord");
  program_.enableAttributeArray(position);
  program_.enableAttributeArray(normal);
  program_.enableAttributeArray(colour);
  if (texCoord >= 0) program_.enableAttributeArray(texCoord);
  // The file's texture image, times the vertex colours, unless the level colours are asked for.
  const bool textured = texture_ && !options_.colourLevels;
  program_.setUniformValue("uUseTexture", textured ? 1.0f : 0.0f);
  program_.setUniformValue("uTexture", 0);
  if (textured) texture_->bind(0);
  // The file's vertex colours unless the level colours are asked for (c).
  program_.setUniformValue("uVertexColour", options_.colourLevels ? 0.0f : 1.0f);
  const QVector3D e = eyeInModel();
  const vcg::Point3d eye(e.x(), e.y(), e.z());
  const LodView lodView = currentView();
  s.budgetReached = cut.budgetReached;
  const QVector3D plain = reader_.info().colors || textured ? QVector3D(1, 1, 1) : QVector3D(0.82f, 0.80f, 0.74f);
  const int colourUniform = program_.uniformLocation("uColour");  // looked up once, not per draw
  int colourLevel = -1;                                           // the level uColour holds now
  if (!options_.colourLevels) program_.setUniformValue(colourUniform, plain);

  for (uint32_t id : cut.nodes) {
    const LodNode& node = reader_.node(id);
    s.cutFaces += node.faceCount;
    if (options_.cullBackFacing) {
      const Facing facing = ClassifyPerspective(node.cone, vcg::Point3d::Construct(node.center), node.radius, eye);
      if (facing == Facing::Back) {
        ++s.groupsCulled;  // one cone test rejects the whole group
        continue;
      }
      if (facing == Facing::Front) ++s.groupsFront;
    }
    const auto it = buffers_.find(id);
    if (it == buffers_.end()) continue;
    NodeBuffers& b = it->second;
    if (options_.colourLevels && node.level != colourLevel) {
      const vcg::Color4b c = GroupColor(node.level);  // the colours of conelod lod extract's output
      program_.setUniformValue(colourUniform, QVector3D(c[0], c[1], c[2]) / 255.0f);
      colourLevel = node.level;
    }
    b.vertices.bind();
    glVertexAttribPointer(GLuint(position), 3, GL_FLOAT, GL_FALSE, kStride * sizeof(float), nullptr);
    glVertexAttribPointer(GLuint(normal), 3, GL_FLOAT, GL_FALSE, kStride * sizeof(float),
                          reinterpret_cast<const void*>(3 * sizeof(float)));
    glVertexAttribPointer(GLuint(colour), 3, GL_FLOAT, GL_FALSE, kStride * sizeof(float),
                          reinterpret_cast<const void*>(6 * sizeof(float)));
    if (texCoord >= 0)
      glVertexAttribPointer(GLuint(texCoord), 2, GL_FLOAT, GL_FALSE, kStride * sizeof(float),
                            reinterpret_cast<const void*>(9 * sizeof(float)));
    if (b.indexCount) {
      b.indices.bind();
      glDrawElements(GL_TRIANGLES, b.indexCount, GL_UNSIGNED_INT, nullptr);
    } else {
      glDrawArrays(GL_TRIANGLES, 0, b.vertexCount);
    }
    ++s.groupsDrawn;
    s.facesDrawn += node.faceCount;
    s.maxPixelError = std::max(s.maxPixelError, ProjectedError(node, lodView));
    s.minLevel = std::min(s.minLevel, node.level);
    s.maxLevel = std::max(s.maxLevel, node.level);
  }
  program_.disableAttributeArray(position);
  program_.disableAttributeArray(normal);
  program_.disableAttributeArray(colour);
  if (texCoord >= 0) program_.disableAttributeArray(texCoord);
  if (textured) texture_->release(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
  program_.release();
  glDisable(GL_CULL_FACE);
  glDisable(GL_DEPTH_TEST);
  if (s.maxLevel < 0) s.minLevel = s.maxLevel = 0;
  glFinish();  // so that the frame time is the drawing's, not only the time to issue it
  s.renderMs = t.nsecsElapsed() * 1e-6;
  stats_ = s;
}

void LodViewerWidget::drawHud() {
  const double readerBytes = double(reader_.residentBytes());
  const double rss = double(conelod::ProcessStatusBytes("VmRSS"));
  const LodFileInfo& info = reader_.info();
  QStringList lines;
  lines << QString("ConeLOD viewer  %1").arg(QString::fromStdString(title_));
  lines << QString("%1 fps  (%2 ms per frame%3)")
               .arg(fps_, 0, 'f', 1)
               .arg(1000 / std::max(fps_, 1e-3), 0, 'f', 1)
               .arg(benchmarked_ ? QString(", mean of %1").arg(benchmarked_) : QString());
  lines << QString("faces drawn %1  (cut %2, input %3)")
               .arg(Thousands(stats_.facesDrawn), Thousands(stats_.cutFaces), Thousands(info.inputFaces));
  lines << QString("groups drawn %1 (all front-facing %2)  culled %3")
               .arg(Thousands(stats_.groupsDrawn), Thousands(stats_.groupsFront), Thousands(stats_.groupsCulled));
  lines << QString("levels %1-%2 of 0-%3  %4")
               .arg(stats_.minLevel)
               .arg(stats_.maxLevel)
               .arg(info.levels - 1)
               .arg(refining_   ? QString("refining...")
                    : dragging_ ? QString("coarse while moving")
                                : QString("still, error <= %1 px%2")
                                      .arg(stats_.maxPixelError, 0, 'f', 2)
                                      .arg(stats_.budgetReached ? " (face budget reached)" : ""));
  lines << QString("memory: reader %1, GPU buffers %2, process %3")
               .arg(MiB(readerBytes), MiB(double(gpuBytes_)), MiB(rss));
  if (!error_.empty()) lines << QString("error: %1").arg(QString::fromStdString(error_));

  QPainter p(this);
  p.setRenderHint(QPainter::TextAntialiasing);
  QFont font("DejaVu Sans Mono");
  font.setStyleHint(QFont::Monospace);
  font.setPixelSize(std::max(11, std::min(15, height() / 40)));
  p.setFont(font);
  const QFontMetrics fm(font);
  int w = 0;
  for (const QString& l : lines) w = std::max(w, fm.horizontalAdvance(l));
  const int lh = fm.height(), pad = 6;
  p.fillRect(QRect(8, 8, w + 2 * pad, lh * lines.size() + 2 * pad), QColor(0, 0, 0, 150));
  p.setPen(QColor(235, 235, 235));
  for (int i = 0; i < lines.size(); ++i) p.drawText(8 + pad, 8 + pad + fm.ascent() + i * lh, lines[i]);
}

void LodViewerWidget::paintGL() {
  syncBuffers();
  renderScene();
  if (firstFrameMsecs_ < 0) {
    firstFrameMsecs_ = startClock_.nsecsElapsed() * 1e-6;
    if (options_.refineWhenIdle) stillTimer_.start(options_.stillMs);  // the coarsest level is on screen: refine
  }
  if (!benchmarked_) fps_ = 1000.0 / std::max(stats_.renderMs, 1e-3);
  if (options_.hud && firstImageMsecs_ >= 0) drawHud();  // not before the first image (above)
}

double LodViewerWidget::benchmarkFrames(int frames) {
  if (frames <= 0) return 0;
  makeCurrent();
  glBindFramebuffer(GL_FRAMEBUFFER, defaultFramebufferObject());
  syncBuffers();
  const QQuaternion start = rotation_;
  const FrameStats kept = stats_;
  QElapsedTimer t;
  t.start();
  for (int i = 0; i < frames; ++i) {
    rotation_ = QQuaternion::fromAxisAndAngle(0, 1, 0, 360.0f * float(i) / float(frames) * 0.05f) * start;
    renderScene();
    glFinish();
  }
  const double ms = t.nsecsElapsed() * 1e-6 / frames;
  rotation_ = start;
  stats_ = kept;
  doneCurrent();
  fps_ = 1000.0 / ms;
  benchmarked_ = frames;
  return ms;
}

// --- Input ----------------------------------------------------------------------------------

void LodViewerWidget::mousePressEvent(QMouseEvent* e) {
  dragging_ = true;
  lastMouse_ = e->pos();
  interactionStarted();
  update();
}

void LodViewerWidget::mouseMoveEvent(QMouseEvent* e) {
  if (!dragging_) return;
  const QPoint d = e->pos() - lastMouse_;
  lastMouse_ = e->pos();
  if (e->buttons() & Qt::LeftButton) {
    const float len = std::sqrt(float(d.x() * d.x() + d.y() * d.y()));
    if (len > 0) rotation_ = QQuaternion::fromAxisAndAngle(QVector3D(d.y(), d.x(), 0) / len, 0.4f * len) * rotation_;
  } else {  // right or middle button: zoom
    distance_ *= std::pow(1.005f, float(d.y()));
  }
  interactionStarted();
  update();
}

void LodViewerWidget::mouseReleaseEvent(QMouseEvent*) {
  dragging_ = false;
  stillTimer_.start(options_.stillMs);
  update();
}

void LodViewerWidget::wheelEvent(QWheelEvent* e) {
  distance_ *= std::pow(0.9985f, float(e->angleDelta().y()));
  distance_ = std::max(distance_, 0.02f * radius_);
  interactionStarted();
  update();
}

void LodViewerWidget::keyPressEvent(QKeyEvent* e) {
  switch (e->key()) {
    case Qt::Key_C:
      options_.colourLevels = !options_.colourLevels;
      break;
    case Qt::Key_H:
      options_.hud = !options_.hud;
      break;
    case Qt::Key_B:
      options_.cullBackFacing = !options_.cullBackFacing;
      viewStill();
      break;
    case Qt::Key_R:
      frameModel();
      interactionStarted();
      break;
    case Qt::Key_Space:
      viewStill();
      break;
    case Qt::Key_Q:
    case Qt::Key_Escape:
      close();
      return;
    default:
      QOpenGLWidget::keyPressEvent(e);
      return;
  }
  update();
}
