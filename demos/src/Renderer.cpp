#include "Renderer.h"

#include "ShapeMesh.h"

#include <GL/gl.h>
#include <GL/osmesa.h>
#include <png.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csetjmp>
#include <csignal>
#include <cstdio>
#include <cstdlib>

namespace cape::demo {

namespace fs = std::filesystem;

// --- Camera -----------------------------------------------------------------------------------------------

Camera Camera::lookAt(const Vec3& eye, const Vec3& target, int width, int height, float fovYDegrees,
                      float zNear, float zFar) {
  Camera c;
  c.width = width;
  c.height = height;
  const Vec3 f = (target - eye).normalized();
  const Vec3 s = f.cross(Vec3::UnitY()).normalized();
  const Vec3 u = s.cross(f);
  c.view.setIdentity();
  c.view.block<1, 3>(0, 0) = s.transpose();
  c.view.block<1, 3>(1, 0) = u.transpose();
  c.view.block<1, 3>(2, 0) = -f.transpose();
  c.view(0, 3) = -s.dot(eye);
  c.view(1, 3) = -u.dot(eye);
  c.view(2, 3) = f.dot(eye);
  const float t = 1.0f / std::tan(0.5f * fovYDegrees * 3.14159265f / 180.0f);
  const float aspect = static_cast<float>(width) / static_cast<float>(height);
  c.projection.setZero();
  c.projection(0, 0) = t / aspect;
  c.projection(1, 1) = t;
  c.projection(2, 2) = (zFar + zNear) / (zNear - zFar);
  c.projection(2, 3) = 2.0f * zFar * zNear / (zNear - zFar);
  c.projection(3, 2) = -1.0f;
  return c;
}

bool Camera::project(const Vec3& world, Eigen::Vector2f& pixel) const {
  const Vec4 clip = projection * view * Vec4(world.x(), world.y(), world.z(), 1.0f);
  if (clip.w() <= 1e-6f) return false;
  const float x = clip.x() / clip.w(), y = clip.y() / clip.w();
  pixel = Eigen::Vector2f(static_cast<float>(this->x) + 0.5f * (x + 1.0f) * static_cast<float>(width),
                          static_cast<float>(this->y) + 0.5f * (1.0f - y) * static_cast<float>(height));
  return true;
}

Vec3 Camera::eye() const {
  const Eigen::Matrix3f r = view.block<3, 3>(0, 0);
  return -(r.transpose() * view.block<3, 1>(0, 3));
}

// --- PNG --------------------------------------------------------------------------------------------------

namespace {

/// libpng's part, with only plain C locals around its setjmp.
bool writePngFile(std::FILE* file, const std::uint8_t* rgba, int width, int height, int compression) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_init_io(png, file);
  png_set_compression_level(png, compression);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8,
               PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_set_filler(png, 0, PNG_FILLER_AFTER);  // the rows are RGBA: drop the fourth byte
  for (int y = 0; y < height; ++y)
    png_write_row(png, rgba + static_cast<std::size_t>(y) * static_cast<std::size_t>(width) * 4);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace

bool writePng(const fs::path& file, const Image& image, std::string& error, int compression) {
  std::FILE* f = std::fopen(file.c_str(), "wb");
  if (!f) {
    error = "cannot write " + file.string();
    return false;
  }
  const bool ok =
      writePngFile(f, image.rgba.data(), image.width, image.height, std::clamp(compression, 0, 9));
  if (std::fclose(f) != 0 || !ok) {
    error = "cannot write PNG " + file.string();
    return false;
  }
  return true;
}

// --- Renderer ---------------------------------------------------------------------------------------------

namespace {

void setMaterial(GLenum face, const Colour& c) {
  const GLfloat diffuse[4] = {c.x(), c.y(), c.z(), 1.0f};
  const GLfloat specular[4] = {0.08f, 0.08f, 0.08f, 1.0f};
  glMaterialfv(face, GL_AMBIENT_AND_DIFFUSE, diffuse);
  glMaterialfv(face, GL_SPECULAR, specular);
  glMaterialf(face, GL_SHININESS, 24.0f);
}

void drawInterleaved(const std::vector<float>& vertices, const std::uint32_t* indices, std::size_t count) {
  glEnableClientState(GL_VERTEX_ARRAY);
  glEnableClientState(GL_NORMAL_ARRAY);
  glVertexPointer(3, GL_FLOAT, 6 * sizeof(float), vertices.data());
  glNormalPointer(GL_FLOAT, 6 * sizeof(float), vertices.data() + 3);
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(count), GL_UNSIGNED_INT, indices);
  glDisableClientState(GL_NORMAL_ARRAY);
  glDisableClientState(GL_VERTEX_ARRAY);
}

}  // namespace

Renderer::Renderer(int width, int height, int supersample)
    : width_(width), height_(height), supersample_(std::clamp(supersample, 1, 4)) {
  if (width < 16 || height < 16 || width > 4096 || height > 4096) {
    error_ = "image size " + std::to_string(width) + "x" + std::to_string(height) + " outside 16..4096";
    return;
  }
  const GLint attributes[] = {OSMESA_FORMAT,
                              OSMESA_RGBA,
                              OSMESA_DEPTH_BITS,
                              24,
                              OSMESA_STENCIL_BITS,
                              0,
                              OSMESA_ACCUM_BITS,
                              0,
                              OSMESA_PROFILE,
                              OSMESA_COMPAT_PROFILE,
                              0};
  OSMesaContext context = OSMesaCreateContextAttribs(attributes, nullptr);
  if (!context) context = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
  if (!context) {
    error_ = "cannot create an OSMesa OpenGL context";
    return;
  }
  context_ = context;
  buffer_.resize(static_cast<std::size_t>(width_ * supersample_) *
                 static_cast<std::size_t>(height_ * supersample_) * 4);
  if (!OSMesaMakeCurrent(context, buffer_.data(), GL_UNSIGNED_BYTE, width_ * supersample_,
                         height_ * supersample_)) {
    error_ = "cannot make the OSMesa context current";
    return;
  }
  image_.width = width_;
  image_.height = height_;
  image_.rgba.resize(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_) * 4);
}

Renderer::~Renderer() {
  if (!context_) return;
  if (OSMesaGetCurrentContext() == static_cast<OSMesaContext>(context_))
    OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);
  OSMesaDestroyContext(static_cast<OSMesaContext>(context_));
}

void Renderer::begin(const Camera& camera, const Colour& background, bool lighting) {
  if (!ok()) return;
  OSMesaMakeCurrent(static_cast<OSMesaContext>(context_), buffer_.data(), GL_UNSIGNED_BYTE,
                    width_ * supersample_, height_ * supersample_);
  lighting_ = lighting;
  // The camera's panel (the whole image unless it says otherwise); GL counts rows from the bottom.
  const int s = supersample_;
  const int panelX = camera.x * s, panelY = (height_ - camera.y - camera.height) * s;
  glViewport(panelX, panelY, camera.width * s, camera.height * s);
  glScissor(panelX, panelY, camera.width * s, camera.height * s);
  glEnable(GL_SCISSOR_TEST);
  glClearColor(background.x(), background.y(), background.z(), 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDisable(GL_CULL_FACE);
  glShadeModel(GL_SMOOTH);
  glMatrixMode(GL_PROJECTION);
  glLoadMatrixf(camera.projection.data());
  glMatrixMode(GL_MODELVIEW);
  glLoadMatrixf(camera.view.data());

  // A key light low from behind the camera's left, grazing across the cape's back so that its folds (which
  // run down it) show as light and shade, and a weaker fill from the other side; directions in the world
  // (set with the view loaded). Both sides of the cape are lit (two-sided lighting).
  const GLfloat key[4] = {-0.80f, 0.50f, 0.35f, 0.0f}, fill[4] = {0.6f, 0.35f, -0.5f, 0.0f};
  const GLfloat keyColour[4] = {0.80f, 0.78f, 0.74f, 1.0f}, fillColour[4] = {0.24f, 0.26f, 0.30f, 1.0f};
  const GLfloat ambient[4] = {0.24f, 0.24f, 0.26f, 1.0f}, black[4] = {0, 0, 0, 1};
  glLightfv(GL_LIGHT0, GL_POSITION, key);
  glLightfv(GL_LIGHT0, GL_DIFFUSE, keyColour);
  glLightfv(GL_LIGHT0, GL_SPECULAR, keyColour);
  glLightfv(GL_LIGHT0, GL_AMBIENT, black);
  glLightfv(GL_LIGHT1, GL_POSITION, fill);
  glLightfv(GL_LIGHT1, GL_DIFFUSE, fillColour);
  glLightfv(GL_LIGHT1, GL_SPECULAR, black);
  glLightfv(GL_LIGHT1, GL_AMBIENT, black);
  glLightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);
  glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_TRUE);
  glEnable(GL_LIGHT0);
  glEnable(GL_LIGHT1);
  glDisable(GL_LIGHTING);
  // Fog into the background hides the ground's edge and the grid's aliasing near the horizon.
  const GLfloat fog[4] = {background.x(), background.y(), background.z(), 1.0f};
  glFogi(GL_FOG_MODE, GL_LINEAR);
  glFogfv(GL_FOG_COLOR, fog);
  glFogf(GL_FOG_START, 12.0f);
  glFogf(GL_FOG_END, 38.0f);
  if (lighting) {
    glEnable(GL_FOG);
  } else {
    glDisable(GL_FOG);
  }
}

void Renderer::drawGround(const Vec3& centre, float halfSize) {
  if (!ok()) return;
  glDisable(GL_LIGHTING);
  const float x0 = std::floor(centre.x() - halfSize), x1 = std::ceil(centre.x() + halfSize);
  const float z0 = std::floor(centre.z() - halfSize), z1 = std::ceil(centre.z() + halfSize);
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1.0f, 1.0f);
  glColor3f(0.78f, 0.78f, 0.76f);
  // In 2 m tiles: the fixed-function fog is computed per vertex, so one big quad would be fogged all over.
  glBegin(GL_QUADS);
  for (float x = x0; x < x1; x += 2.0f) {
    for (float z = z0; z < z1; z += 2.0f) {
      glVertex3f(x, 0, z);
      glVertex3f(x, 0, z + 2.0f);
      glVertex3f(x + 2.0f, 0, z + 2.0f);
      glVertex3f(x + 2.0f, 0, z);
    }
  }
  glEnd();
  glDisable(GL_POLYGON_OFFSET_FILL);
  glLineWidth(static_cast<float>(supersample_));
  glBegin(GL_LINES);
  for (float x = x0; x <= x1; x += 1.0f) {
    const bool major = std::fmod(std::abs(x), 5.0f) < 0.5f;
    glColor3f(major ? 0.45f : 0.62f, major ? 0.45f : 0.62f, major ? 0.47f : 0.62f);
    for (float z = z0; z < z1; z += 2.0f) {
      glVertex3f(x, 0, z);
      glVertex3f(x, 0, z + 2.0f);
    }
  }
  for (float z = z0; z <= z1; z += 1.0f) {
    const bool major = std::fmod(std::abs(z), 5.0f) < 0.5f;
    glColor3f(major ? 0.45f : 0.62f, major ? 0.45f : 0.62f, major ? 0.47f : 0.62f);
    for (float x = x0; x < x1; x += 2.0f) {
      glVertex3f(x, 0, z);
      glVertex3f(x + 2.0f, 0, z);
    }
  }
  glEnd();
  glLineWidth(1.0f);
}

const Renderer::GpuMesh& Renderer::shapeMesh(const Collider& c) {
  char key[160];
  std::snprintf(key, sizeof(key), "%d %.5g %.5g %d %.5g %.5g %.5g", static_cast<int>(c.shape), c.radius,
                c.halfHeight, c.axis, c.halfExtents.x(), c.halfExtents.y(), c.halfExtents.z());
  auto it = shapes_.find(key);
  if (it != shapes_.end()) return it->second;
  const ShapeMesh shape = colliderMesh(c, 32);
  GpuMesh mesh;
  mesh.indices = shape.indices;
  mesh.interleaved.reserve(shape.positions.size() * 2);
  for (std::size_t i = 0; i < shape.vertexCount(); ++i) {
    mesh.interleaved.insert(mesh.interleaved.end(), shape.positions.begin() + static_cast<long>(3 * i),
                            shape.positions.begin() + static_cast<long>(3 * i + 3));
    mesh.interleaved.insert(mesh.interleaved.end(), shape.normals.begin() + static_cast<long>(3 * i),
                            shape.normals.begin() + static_cast<long>(3 * i + 3));
  }
  return shapes_.emplace(key, std::move(mesh)).first->second;
}

void Renderer::drawColliders(const std::vector<Collider>& colliders, const Colour& colour) {
  if (!ok()) return;
  if (lighting_) {
    glEnable(GL_LIGHTING);
    setMaterial(GL_FRONT_AND_BACK, colour);
  } else {
    glDisable(GL_LIGHTING);
    glColor3f(colour.x(), colour.y(), colour.z());
  }
  for (const Collider& c : colliders) {
    if (c.shape == ColliderShape::Plane) continue;
    const GpuMesh& mesh = shapeMesh(c);
    Eigen::Affine3f pose = Eigen::Translation3f(c.current.position) * c.current.rotation.normalized();
    glPushMatrix();
    glMultMatrixf(pose.matrix().data());
    drawInterleaved(mesh.interleaved, mesh.indices.data(), mesh.indices.size());
    glPopMatrix();
  }
  glDisable(GL_LIGHTING);
}

void Renderer::drawCape(const Cape& cape, const Colour& outside, const Colour& lining) {
  if (!ok() || cape.fabric().particleCount() == 0) return;
  if (capeFabric_ != &cape.fabric() ||
      capeMesh_.positions.rows() != static_cast<Eigen::Index>(cape.fabric().particleCount())) {
    capeMesh_.allocate(cape.fabric(), false);
    capeFabric_ = &cape.fabric();
  }
  capeMesh_.update(cape.fabric(), cape.state().positions);
  drawCape(capeMesh_, outside, lining);
}

void Renderer::drawCape(const CapeMesh& mesh, const Colour& outside, const Colour& lining) {
  if (!ok() || mesh.positions.rows() == 0) return;
  const auto n = static_cast<std::size_t>(mesh.positions.rows());
  capeVertices_.resize(6 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    for (int c = 0; c < 3; ++c) {
      capeVertices_[6 * i + static_cast<std::size_t>(c)] = mesh.positions(r, c);
      capeVertices_[6 * i + 3 + static_cast<std::size_t>(c)] = mesh.normals(r, c);
    }
  }
  if (lighting_) {
    glEnable(GL_LIGHTING);
    setMaterial(GL_FRONT, outside);
    setMaterial(GL_BACK, lining);
  } else {
    glDisable(GL_LIGHTING);
    glColor3f(outside.x(), outside.y(), outside.z());
  }
  const std::size_t front = mesh.twoSided() ? mesh.indices.size() / 2 : mesh.indices.size();
  drawInterleaved(capeVertices_, mesh.indices.data(), front);
  glDisable(GL_LIGHTING);
}

const Image& Renderer::finish() {
  if (!ok()) return image_;
  glFinish();
  // Average supersample x supersample blocks; the GL buffer's rows run from the bottom.
  const int s = supersample_, bw = width_ * s, bh = height_ * s;
  const int weight = s * s;
  for (int y = 0; y < height_; ++y) {
    std::uint8_t* out =
        image_.rgba.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) * 4;
    const int by = bh - (y + 1) * s;  // first buffer row of this image row's block
    for (int x = 0; x < width_; ++x) {
      int sum[4] = {0, 0, 0, 0};
      for (int dy = 0; dy < s; ++dy) {
        const std::uint8_t* in =
            buffer_.data() + (static_cast<std::size_t>(by + dy) * static_cast<std::size_t>(bw) +
                              static_cast<std::size_t>(x * s)) *
                                 4;
        for (int dx = 0; dx < s; ++dx, in += 4) {
          sum[0] += in[0];
          sum[1] += in[1];
          sum[2] += in[2];
          sum[3] += in[3];
        }
      }
      for (int c = 0; c < 4; ++c) out[4 * x + c] = static_cast<std::uint8_t>((sum[c] + weight / 2) / weight);
    }
  }
  return image_;
}

// --- RunRenderer ------------------------------------------------------------------------------------------

std::string shellQuote(const std::string& text) {
  std::string q = "'";
  for (char ch : text) {
    if (ch == '\'') {
      q += "'\\''";
    } else {
      q += ch;
    }
  }
  return q + "'";
}

RunRenderer::RunRenderer(const fs::path& dir, int characters, int width, int height, Layout layout)
    : dir_(dir),
      characters_(std::max(characters, 1)),
      pending_(static_cast<std::size_t>(characters_)),
      layout_(layout),
      views_(layout == Layout::SideBySide ? static_cast<std::size_t>(characters_) : 1) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec || !fs::is_directory(dir_)) {
    error_ = "cannot create render folder " + dir_.string() + (ec ? ": " + ec.message() : "");
    return;
  }
  renderer_ = std::make_unique<Renderer>(width, height, 2);
  if (!renderer_->ok()) error_ = renderer_->error();
}

void RunRenderer::record(int character, const Cape& cape, const std::vector<Collider>& colliders) {
  if (!ok() || character < 0 || character >= characters_) return;
  Pending& p = pending_[static_cast<std::size_t>(character)];
  p.cape = &cape;
  p.mesh = nullptr;
  p.colliders.assign(colliders.begin(), colliders.end());
  if (character == characters_ - 1) renderFrame();
}

void RunRenderer::record(int character, const CapeMesh& mesh, const std::vector<Collider>& colliders) {
  if (!ok() || character < 0 || character >= characters_) return;
  Pending& p = pending_[static_cast<std::size_t>(character)];
  p.cape = nullptr;
  p.mesh = &mesh;
  p.colliders.assign(colliders.begin(), colliders.end());
  if (character == characters_ - 1) renderFrame();
}

Vec3 characterCentre(const Points& capePositions, const std::vector<Collider>& colliders) {
  Vec3 c = Vec3::Zero();
  int count = 0;
  for (const Collider& col : colliders) {
    if (col.shape == ColliderShape::Plane) continue;
    c += col.current.position;
    ++count;
  }
  if (count > 0) return c / static_cast<float>(count);
  return capePositions.rows() > 0 ? Vec3(capePositions.colwise().mean().transpose()) : Vec3::Zero();
}

void FollowCamera::follow(const std::vector<Vec3>& centres, int x, int width, int height) {
  Vec3 centre = Vec3::Zero();
  for (const Vec3& c : centres) centre += c;
  centre /= static_cast<float>(std::max<std::size_t>(centres.size(), 1));
  float spread = 0.0f;
  for (const Vec3& c : centres) spread = std::max(spread, (c - centre).norm());

  // Turn with the heading of the motion (kept while standing), smoothed over about 0.35 s.
  const float dt = 1.0f / 60.0f, kTwoPi = 6.28318530718f;
  if (started_) {
    const Vec3 v = (centre - centre_) / dt;
    if (std::hypot(v.x(), v.z()) > 0.5f) {
      const float target = std::atan2(-v.x(), -v.z());
      const float delta = std::remainder(target - heading_, kTwoPi);
      heading_ = std::remainder(heading_ + delta * (1.0f - std::exp(-dt / 0.35f)), kTwoPi);
    }
  }
  started_ = true;
  centre_ = centre;
  const Vec3 forward(-std::sin(heading_), 0.0f, -std::cos(heading_));
  const Vec3 left(-std::cos(heading_), 0.0f, std::sin(heading_));
  target_ = Vec3(centre.x(), 1.0f, centre.z());
  // Farther back for a wide group or a narrow panel.
  const Framing& f = framing_;
  const float aspect = static_cast<float>(width) / static_cast<float>(height);
  const float back = (f.back + f.backPerSpread * spread) * std::max(1.0f, 1.6f / aspect);
  eye_ = target_ - back * forward + (f.side + f.sidePerSpread * spread) * left + Vec3(0, f.rise, 0);
  camera_ = Camera::lookAt(eye_, target_, width, height, f.fovYDegrees);
  camera_.x = x;
}

Camera FollowCamera::cameraFor(int width, int height) const {
  return Camera::lookAt(eye_, target_, width, height, framing_.fovYDegrees);
}

void RunRenderer::follow(FollowCamera& view, const std::vector<const Pending*>& characters, int x,
                         int width) {
  std::vector<Vec3> centres;
  for (const Pending* p : characters) {
    if (!p->cape && !p->mesh) continue;
    centres.push_back(
        characterCentre(p->cape ? p->cape->state().positions : p->mesh->positions, p->colliders));
  }
  view.follow(centres, x, width, renderer_->height());
}

void RunRenderer::renderFrame() {
  const auto start = std::chrono::steady_clock::now();
  std::vector<const Pending*> all;
  for (const Pending& p : pending_) all.push_back(&p);
  if (layout_ == Layout::Together) {
    follow(views_[0], all, 0, renderer_->width());
    renderer_->begin(views_[0].camera());
    renderer_->drawGround(views_[0].centre(), 40.0f);
    for (const Pending* p : all) {
      renderer_->drawColliders(p->colliders);
      if (p->cape) renderer_->drawCape(*p->cape);
      if (p->mesh) renderer_->drawCape(*p->mesh);
    }
  } else {
    // Panels of equal width, a 2 pixel gap between them (left as the clear colour of no panel: black).
    const int panels = static_cast<int>(views_.size()), gap = 2;
    const int width = (renderer_->width() - gap * (panels - 1)) / panels;
    for (int k = 0; k < panels; ++k) {
      FollowCamera& view = views_[static_cast<std::size_t>(k)];
      const Pending* p = all[static_cast<std::size_t>(k)];
      follow(view, {p}, k * (width + gap), width);
      renderer_->begin(view.camera());
      renderer_->drawGround(view.centre(), 40.0f);
      renderer_->drawColliders(p->colliders);
      if (p->cape) renderer_->drawCape(*p->cape);
      if (p->mesh) renderer_->drawCape(*p->mesh);
    }
  }
  const Image& image = renderer_->finish();
  renderMs_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ++frame_;
  char name[32];
  std::snprintf(name, sizeof(name), "%05d.png", frame_);
  std::string error;
  if (!writePng(dir_ / name, image, error, 3)) error_ = error;
}

bool RunRenderer::finish(std::string& error) {
  if (!ok()) {
    error = error_;
    return false;
  }
  if (frame_ == 0) {
    error = "no frames rendered into " + dir_.string();
    return false;
  }
  if (std::system("command -v ffmpeg >/dev/null 2>&1") != 0) {
    std::printf("cape_walk: ffmpeg is not on PATH: no run.mp4 or run.gif; the frames are in %s\n",
                dir_.c_str());
    return true;
  }
  const std::string frames = shellQuote((dir_ / "%05d.png").string());
  const std::string mp4 = "ffmpeg -y -loglevel error -framerate 60 -i " + frames +
                          " -c:v libx264 -pix_fmt yuv420p -crf 20 -preset medium -movflags +faststart " +
                          shellQuote((dir_ / "run.mp4").string());
  if (std::system(mp4.c_str()) != 0) {
    error = "ffmpeg could not write " + (dir_ / "run.mp4").string();
    return false;
  }
  const std::string gif =
      "ffmpeg -y -loglevel error -framerate 60 -i " + frames +
      " -vf \"fps=20,scale=320:-2:flags=lanczos,split[a][b];[a]palettegen=max_colors=64:stats_mode=diff[p];"
      "[b][p]paletteuse=dither=bayer:bayer_scale=5:diff_mode=rectangle\" " +
      shellQuote((dir_ / "run.gif").string());
  if (std::system(gif.c_str()) != 0) {
    error = "ffmpeg could not write " + (dir_ / "run.gif").string();
    return false;
  }
  return true;
}

// --- RunMovie ---------------------------------------------------------------------------------------------

namespace {

/// The area of the camera's image the capes' front triangles cover, px^2: their union on a grid of
/// kCoverageCell-pixel cells (a cell counts when its centre is inside a triangle), so a cape folded or
/// twisted over itself counts once, as the picture shows it. `mask` is scratch.
constexpr int kCoverageCell = 4;
double coveredArea(const std::vector<const CapeMesh*>& meshes, const Camera& camera,
                   std::vector<std::uint8_t>& mask) {
  const int columns = (camera.width + kCoverageCell - 1) / kCoverageCell;
  const int rows = (camera.height + kCoverageCell - 1) / kCoverageCell;
  mask.assign(static_cast<std::size_t>(columns) * static_cast<std::size_t>(rows), 0);
  std::size_t covered = 0;
  for (const CapeMesh* mesh : meshes) {
    if (mesh == nullptr) continue;
    const std::size_t front = mesh->twoSided() ? mesh->indices.size() / 2 : mesh->indices.size();
    for (std::size_t t = 0; t + 2 < front; t += 3) {
      Eigen::Vector2f p[3];
      bool seen = true;
      for (int i = 0; i < 3 && seen; ++i)
        seen = camera.project(mesh->positions.row(mesh->indices[t + static_cast<std::size_t>(i)]).transpose(),
                              p[i]);
      if (!seen) continue;
      // In cell units, relative to the panel; the cells whose centres the triangle's box holds.
      for (Eigen::Vector2f& q : p)
        q = (q - Eigen::Vector2f(static_cast<float>(camera.x), static_cast<float>(camera.y))) / kCoverageCell;
      const float area2 = (p[1] - p[0]).x() * (p[2] - p[0]).y() - (p[1] - p[0]).y() * (p[2] - p[0]).x();
      if (!(std::fabs(area2) > 0.0f)) continue;
      const float lo[2] = {std::min({p[0].x(), p[1].x(), p[2].x()}),
                           std::min({p[0].y(), p[1].y(), p[2].y()})};
      const float hi[2] = {std::max({p[0].x(), p[1].x(), p[2].x()}),
                           std::max({p[0].y(), p[1].y(), p[2].y()})};
      const int x0 = std::max(0, static_cast<int>(std::ceil(lo[0] - 0.5f)));
      const int x1 = std::min(columns - 1, static_cast<int>(std::floor(hi[0] - 0.5f)));
      const int y0 = std::max(0, static_cast<int>(std::ceil(lo[1] - 0.5f)));
      const int y1 = std::min(rows - 1, static_cast<int>(std::floor(hi[1] - 0.5f)));
      const float sign = area2 > 0.0f ? 1.0f : -1.0f;
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const Eigen::Vector2f c(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f);
          bool inside = true;
          for (int e = 0; e < 3 && inside; ++e) {
            const Eigen::Vector2f& a = p[e];
            const Eigen::Vector2f& b = p[(e + 1) % 3];
            inside = sign * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x()) >= 0.0f;
          }
          std::uint8_t& cell = mask[static_cast<std::size_t>(y) * static_cast<std::size_t>(columns) +
                                    static_cast<std::size_t>(x)];
          if (inside && cell == 0) {
            cell = 1;
            ++covered;
          }
        }
    }
  }
  return static_cast<double>(covered) * kCoverageCell * kCoverageCell;
}

}  // namespace

RunMovie::RunMovie(const fs::path& picture, const fs::path& video, int characters, const Settings& settings)
    : picture_(picture),
      video_(video),
      settings_(settings),
      characters_(std::max(characters, 1)),
      camera_(FollowCamera::threeQuarter()),
      meshes_(static_cast<std::size_t>(characters_), nullptr),
      colliders_(static_cast<std::size_t>(characters_)) {
  const int fps = std::clamp(settings.framesPerSecond, 1, 60);
  step_ = 60 / fps;
  windowFrames_ = std::min<std::int64_t>(settings.runFrames, std::llround(settings.seconds * 60.0));
  // The picture from the second second on, when the video is that long (the cape has left its flat start).
  pictureFrom_ = windowFrames_ >= 120 ? 60 : std::max<std::int64_t>(1, windowFrames_ / 2);
  best_.camera = camera_;
  renderer_ =
      std::make_unique<Renderer>(settings.videoWidth, settings.videoHeight, settings.videoSupersample);
  if (!renderer_->ok()) {
    error_ = renderer_->error();
    return;
  }
  if (settings.videoWidth % 2 != 0 || settings.videoHeight % 2 != 0) {
    error_ = "the video's sides must be even";
    return;
  }
  if (std::system("command -v ffmpeg >/dev/null 2>&1") != 0) return;  // no video: writesVideo() says so
  std::signal(SIGPIPE, SIG_IGN);
  const std::string command = "ffmpeg -y -loglevel error -f rawvideo -pix_fmt rgba -s " +
                              std::to_string(settings.videoWidth) + "x" +
                              std::to_string(settings.videoHeight) + " -framerate " + std::to_string(fps) +
                              " -i - -c:v libx264 -preset superfast -crf 27 -pix_fmt yuv420p -threads 1 "
                              "-movflags +faststart " +
                              shellQuote(video.string());
  pipe_ = popen(command.c_str(), "w");
  if (!pipe_) error_ = "cannot start ffmpeg for " + video.string();
}

RunMovie::~RunMovie() {
  if (pipe_) pclose(pipe_);
}

void RunMovie::draw(Renderer& renderer, const Camera& camera, const std::vector<const CapeMesh*>& meshes,
                    const std::vector<std::vector<Collider>>& colliders, const Vec3& centre) {
  renderer.begin(camera);
  renderer.drawGround(centre, 40.0f);
  for (std::size_t k = 0; k < meshes.size(); ++k) {
    renderer.drawColliders(colliders[k]);
    if (meshes[k]) renderer.drawCape(*meshes[k]);
  }
}

void RunMovie::record(std::int64_t frame, int character, const CapeMesh& mesh,
                      const std::vector<Collider>& colliders) {
  if (!ok() || !wants(frame) || character < 0 || character >= characters_) return;
  const auto k = static_cast<std::size_t>(character);
  meshes_[k] = &mesh;
  colliders_[k] = colliders;
  if (character != characters_ - 1) return;

  // Every frame moves the camera on (it smooths over frames); every step_-th is drawn, and the last.
  std::vector<Vec3> centres;
  for (std::size_t c = 0; c < meshes_.size(); ++c)
    if (meshes_[c]) centres.push_back(characterCentre(meshes_[c]->positions, colliders_[c]));
  camera_.follow(centres, 0, renderer_->width(), renderer_->height());
  if (frame % step_ != 0 && frame != windowFrames_) return;

  const auto start = std::chrono::steady_clock::now();
  {
    // Before pictureFrom_ the latest frame is kept (the picture of a run that ends early); from then on the
    // one that shows the most cape.
    const double score = frame >= pictureFrom_ ? coveredArea(meshes_, camera_.camera(), coverage_) : 0.0;
    if (frame < pictureFrom_ || best_.frame < pictureFrom_ || score > best_.score) {
      best_.frame = frame;
      best_.score = score;
      best_.camera = camera_;
      best_.colliders = colliders_;
      best_.meshes.clear();
      for (const CapeMesh* m : meshes_) best_.meshes.push_back(m ? *m : CapeMesh());
    }
  }
  if (pipe_) {
    draw(*renderer_, camera_.camera(), meshes_, colliders_, camera_.centre());
    const Image& image = renderer_->finish();
    if (std::fwrite(image.rgba.data(), 1, image.rgba.size(), pipe_) != image.rgba.size()) {
      error_ = "ffmpeg stopped taking the frames of " + video_.string();
      pclose(pipe_);
      pipe_ = nullptr;
    }
    ++videoFrames_;
  }
  renderMs_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

bool RunMovie::finish(std::string& error) {
  if (pipe_) {
    const int status = pclose(pipe_);
    pipe_ = nullptr;
    if (status != 0 && ok()) error_ = "ffmpeg could not write " + video_.string();
  }
  if (ok() && best_.frame == 0) error_ = "no frame recorded for " + picture_.string();
  if (!ok()) {
    error = error_;
    return false;
  }
  Renderer still(settings_.pictureWidth, settings_.pictureHeight, settings_.pictureSupersample);
  if (!still.ok()) {
    error = still.error();
    return false;
  }
  std::vector<const CapeMesh*> meshes;
  for (const CapeMesh& m : best_.meshes) meshes.push_back(m.positions.rows() > 0 ? &m : nullptr);
  draw(still, best_.camera.cameraFor(still.width(), still.height()), meshes, best_.colliders,
       best_.camera.centre());
  return writePng(picture_, still.finish(), error, 6);
}

}  // namespace cape::demo
