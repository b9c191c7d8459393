// Headless pictures of a run through a real OpenGL implementation: Mesa's OSMesa (software, llvmpipe)
// renders into memory; libpng writes the frames; ffmpeg, when on PATH, turns them into an MP4 and a GIF.
// Legacy fixed-function GL is enough here: per-vertex lighting of the cape's area-weighted normals, lit on
// both sides (GL_LIGHT_MODEL_TWO_SIDE: the back faces use the flipped normal and their own material).
#pragma once

#include "cape/core/Cape.h"
#include "cape/core/CapeMesh.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace cape::demo {

using Vec4 = Eigen::Vector4f;
using Mat4 = Eigen::Matrix4f;

/// A pinhole camera: view and projection matrices as OpenGL uses them, and the image they map to.
struct Camera {
  Mat4 view = Mat4::Identity();
  Mat4 projection = Mat4::Identity();
  int width = 640, height = 360;  ///< The image (or the panel of it) the camera maps to, pixels.
  int x = 0, y = 0;               ///< The panel's top-left corner in the image, pixels.

  /// Looks from `eye` at `target` with +Y up; vertical field of view in degrees; near and far in m.
  static Camera lookAt(const Vec3& eye, const Vec3& target, int width, int height, float fovYDegrees = 40.0f,
                       float zNear = 0.1f, float zFar = 200.0f);
  /// Pixel coordinates of a world point (x to the right, y down from the top-left corner, pixel centres at
  /// +0.5); false if it lies behind the camera.
  bool project(const Vec3& world, Eigen::Vector2f& pixel) const;
  Vec3 eye() const;
};

/// RGB colour, components in [0, 1].
using Colour = Eigen::Vector3f;

/// An RGBA8 image, rows from the top.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;
  const std::uint8_t* pixel(int x, int y) const {
    return rgba.data() + (static_cast<std::size_t>(y) * width + x) * 4;
  }
};

/// Writes RGB from an RGBA image as an 8-bit PNG (zlib level 0..9). False with a reason on failure.
bool writePng(const std::filesystem::path& file, const Image& image, std::string& error, int compression = 6);

/// One OSMesa context and its frame buffer. Draw calls go between begin() and finish().
class Renderer {
 public:
  /// An image of width x height, rendered at `supersample` times the size in each direction and averaged
  /// down (OSMesa has no multisampling). Check ok().
  Renderer(int width, int height, int supersample = 2);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  int width() const { return width_; }
  int height() const { return height_; }

  /// Clears the camera's panel to `background`, loads the camera and sets the lights; `lighting` false draws
  /// flat colours. Several panels may be drawn (each after its own begin()) before finish().
  void begin(const Camera& camera, const Colour& background = Colour(0.80f, 0.86f, 0.93f),
             bool lighting = true);
  /// The ground y = 0: a light plane with 1 m grid lines (darker every 5 m) within `halfSize` m of `centre`.
  void drawGround(const Vec3& centre, float halfSize = 30.0f);
  /// Colliders as their true shapes (planes are skipped: drawGround draws the ground).
  void drawColliders(const std::vector<Collider>& colliders,
                     const Colour& colour = Colour(0.50f, 0.60f, 0.75f));
  /// The cape, smooth shaded with its per-vertex normals, `outside` on its front (counter-clockwise) faces
  /// and `lining` on its back.
  void drawCape(const Cape& cape, const Colour& outside = Colour(0.70f, 0.06f, 0.08f),
                const Colour& lining = Colour(0.85f, 0.66f, 0.22f));
  /// Any cloth given as a mesh (a btSoftBody's nodes and faces, say): its front triangles only when the mesh
  /// is two-sided, since the lighting already shades both sides.
  void drawCape(const CapeMesh& mesh, const Colour& outside = Colour(0.70f, 0.06f, 0.08f),
                const Colour& lining = Colour(0.85f, 0.66f, 0.22f));
  /// Finishes the frame and returns the image (valid until the next finish()).
  const Image& finish();
  /// The image of the last finish().
  const Image& image() const { return image_; }

 private:
  struct GpuMesh {
    std::vector<float> interleaved;  ///< x, y, z, nx, ny, nz per vertex
    std::vector<std::uint32_t> indices;
  };
  const GpuMesh& shapeMesh(const Collider& collider);

  int width_, height_, supersample_;
  std::string error_;
  void* context_ = nullptr;           ///< OSMesaContext
  std::vector<std::uint8_t> buffer_;  ///< The GL frame buffer, bottom row first, supersampled.
  Image image_;
  bool lighting_ = true;
  CapeMesh capeMesh_;
  const Fabric* capeFabric_ = nullptr;
  std::vector<float> capeVertices_;        ///< Interleaved position and normal, refreshed per draw.
  std::map<std::string, GpuMesh> shapes_;  ///< Collider meshes by shape and size.
};

/// Where a FollowCamera's eye sits relative to the point it looks at (1 m above the characters' centre) for
/// characters together at their centre; a group whose farthest character is `spread` m from the centre
/// moves it out by the per-spread terms.
struct CameraFraming {
  float back = 2.8f;           ///< behind the characters, m
  float backPerSpread = 1.2f;  ///< m per m of spread
  float side = 1.5f;           ///< to their left, m
  float sidePerSpread = 0.6f;  ///< m per m of spread
  float rise = 0.6f;           ///< above the point looked at, m
  float fovYDegrees = 40.0f;   ///< vertical field of view, degrees
};

/// A camera that follows characters as they move: it looks at a point 1 m above their centre from behind
/// them and to their left, turning with their heading (smoothed over about 0.35 s, kept while they stand).
class FollowCamera {
 public:
  using Framing = CameraFraming;
  /// Behind and to the left at 45 degrees, a little higher: the three-quarter view of a run's picture.
  static Framing threeQuarter() { return Framing{2.4f, 1.0f, 2.4f, 1.0f, 0.8f, 40.0f}; }

  explicit FollowCamera(const Framing& framing = Framing()) : framing_(framing) {}
  /// Moves on to this frame's character centres (m; one frame of 1/60 s after the last call) and aims at
  /// them in a panel `width` x `height` px whose left edge is `x` px from the image's.
  void follow(const std::vector<Vec3>& centres, int x, int width, int height);
  /// The camera of the last follow().
  const Camera& camera() const { return camera_; }
  /// The same eye and target in an image of another size.
  Camera cameraFor(int width, int height) const;
  /// The characters' centre at the last follow(), m.
  const Vec3& centre() const { return centre_; }

 private:
  Framing framing_;
  Camera camera_;
  Vec3 centre_ = Vec3::Zero(), eye_ = Vec3::Zero(), target_ = Vec3::Zero();
  float heading_ = 0.0f;  ///< rad about +Y; 0 faces -Z
  bool started_ = false;
};

/// Where a character is, for a following camera: the mean of its body colliders' centres (planes left out),
/// or of the cape's vertices when it has none.
Vec3 characterCentre(const Points& capePositions, const std::vector<Collider>& colliders);

/// Renders a run frame by frame into a folder: DIR/00001.png, ... and, with ffmpeg on PATH, DIR/run.mp4
/// (H.264, 60 fps) and DIR/run.gif (every third frame, 320 px wide, 64 colours). The camera follows the
/// characters from behind and to their left, looking at the torso, turning with their heading.
class RunRenderer {
 public:
  /// Creates the folder. Check ok(): false with a reason if the folder or the GL context cannot be made.
  /// Together: one camera on every character (a crowd). SideBySide: each character in its own panel, left to
  /// right, with its own camera (a comparison of two capes on twin characters).
  enum class Layout { Together, SideBySide };
  RunRenderer(const std::filesystem::path& dir, int characters, int width = 640, int height = 360,
              Layout layout = Layout::Together);
  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }

  /// Adds character k's cape and body colliders to the current frame; after the last character the frame is
  /// rendered and written. Characters come in order 0, 1, ...
  void record(int character, const Cape& cape, const std::vector<Collider>& colliders);
  /// The same for a cloth given as a mesh (kept by the caller until the frame is rendered).
  void record(int character, const CapeMesh& mesh, const std::vector<Collider>& colliders);
  /// Runs ffmpeg for the video and the GIF (or says why not). False with a reason if a frame or the video
  /// could not be written.
  bool finish(std::string& error);

  int frames() const { return frame_; }
  /// Mean wall time per frame of drawing and reading back (PNG writing excluded), ms.
  double meanRenderMs() const { return frame_ > 0 ? renderMs_ / frame_ : 0.0; }
  /// The camera of a panel (0 with Together) in the last frame, and the last frame itself.
  const Camera& camera(int panel = 0) const { return views_.at(static_cast<std::size_t>(panel)).camera(); }
  const Image& lastImage() const { return renderer_->image(); }

 private:
  void renderFrame();

  std::filesystem::path dir_;
  int characters_;
  std::string error_;
  std::unique_ptr<Renderer> renderer_;
  struct Pending {
    const Cape* cape = nullptr;
    const CapeMesh* mesh = nullptr;
    std::vector<Collider> colliders;
  };
  std::vector<Pending> pending_;
  void follow(FollowCamera& view, const std::vector<const Pending*>& characters, int x, int width);
  Layout layout_;
  std::vector<FollowCamera> views_;
  int frame_ = 0;
  double renderMs_ = 0.0;
};

/// The pictures a run leaves by default: a short H.264 video of its start, streamed to ffmpeg as the run
/// goes (raw frames through a pipe: no image files on the way), and one picture, the frame of the video in
/// which the cape covers the most of the image (its triangles' projected area), rendered again larger. Both
/// from FollowCamera::threeQuarter(). Opening the pipe ignores SIGPIPE for the process, so that an ffmpeg
/// that stops early is an error of finish(), not the end of the run.
class RunMovie {
 public:
  struct Settings {
    int videoWidth = 480, videoHeight = 270;      ///< px, each even (H.264's 4:2:0)
    int pictureWidth = 960, pictureHeight = 540;  ///< px
    int framesPerSecond = 20;                     ///< of the video: every (60 / fps)-th run frame
    double seconds = 10.0;                        ///< of the run the video shows, from its start, s
    std::int64_t runFrames = 0;                   ///< the run's length in 1/60 s frames
    int videoSupersample = 1;                     ///< per side (the video is drawn as the run goes)
    int pictureSupersample = 2;                   ///< per side (the picture is drawn once)
  };
  /// Starts ffmpeg (when it is on PATH) writing `video`; the picture goes to `picture` at finish(). Check
  /// ok(): false with a reason when the GL context or the pipe cannot be made.
  RunMovie(const std::filesystem::path& picture, const std::filesystem::path& video, int characters,
           const Settings& settings);
  ~RunMovie();
  RunMovie(const RunMovie&) = delete;
  RunMovie& operator=(const RunMovie&) = delete;
  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  /// Whether run frame `frame` (1, 2, ...) is within what the video shows (later frames are not needed).
  bool wants(std::int64_t frame) const { return frame <= windowFrames_; }
  /// Character k's cape (kept by the caller until the last character of the frame is recorded) and body
  /// colliders in run frame `frame`; characters in order 0, 1, ...
  void record(std::int64_t frame, int character, const CapeMesh& mesh,
              const std::vector<Collider>& colliders);
  /// Closes the video and writes the picture. False with a reason when either could not be written.
  bool finish(std::string& error);

  bool writesVideo() const { return pipe_ != nullptr || videoFrames_ > 0; }  ///< false without ffmpeg
  int videoFrames() const { return videoFrames_; }
  std::int64_t pictureFrame() const { return best_.frame; }  ///< the run frame in the picture
  /// Mean wall time per video frame of drawing, reading back and handing it to ffmpeg, ms.
  double meanRenderMs() const { return videoFrames_ > 0 ? renderMs_ / videoFrames_ : 0.0; }

 private:
  struct Still {
    std::int64_t frame = 0;
    double score = -1.0;  ///< the area of the video's image the capes cover, px^2
    std::vector<CapeMesh> meshes;
    std::vector<std::vector<Collider>> colliders;
    FollowCamera camera;
  };
  void draw(Renderer& renderer, const Camera& camera, const std::vector<const CapeMesh*>& meshes,
            const std::vector<std::vector<Collider>>& colliders, const Vec3& centre);

  std::filesystem::path picture_, video_;
  Settings settings_;
  int characters_;
  std::int64_t windowFrames_ = 0, step_ = 2, pictureFrom_ = 1;
  std::string error_;
  std::unique_ptr<Renderer> renderer_;
  std::FILE* pipe_ = nullptr;
  FollowCamera camera_;
  std::vector<const CapeMesh*> meshes_;
  std::vector<std::vector<Collider>> colliders_;
  Still best_;
  std::vector<std::uint8_t> coverage_;  ///< coveredArea's scratch
  int videoFrames_ = 0;
  double renderMs_ = 0.0;
};

/// Quotes a path for /bin/sh.
std::string shellQuote(const std::string& text);

}  // namespace cape::demo
