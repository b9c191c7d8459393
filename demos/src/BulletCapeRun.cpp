// Our cape on the scene's Bullet world: one CapeAction per character, stepped together by a CapeGroup (on
// --threads workers) inside stepSimulation. The cape time of a frame is the wall time of the group's
// updateAction calls in it (every cape's prepare and advance, on however many workers), timed from outside;
// the rest of stepSimulation is Bullet's own.
#include "BulletScene.h"
#include "ImageFile.h"

#include "cape/bullet/CapeAction.h"
#include "cape/bullet/CapeGroup.h"
#include "cape/bullet/Convert.h"

#include <algorithm>
#include <chrono>
#include <cstdio>

namespace cape::demo {

namespace {

/// The group as the world sees it: each internal step's updateAction passed on and timed, wall clock.
class TimedGroup final : public btActionInterface {
 public:
  explicit TimedGroup(bullet::CapeGroup& group) : group_(group) {}
  void updateAction(btCollisionWorld* world, btScalar dt) override {
    const auto start = std::chrono::steady_clock::now();
    group_.updateAction(world, dt);
    microseconds_ +=
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
  }
  void debugDraw(btIDebugDraw* drawer) override { group_.debugDraw(drawer); }
  /// The wall time of the updateAction calls since the last call of this function, µs.
  double takeMicroseconds() {
    const double t = microseconds_;
    microseconds_ = 0.0;
    return t;
  }

 private:
  bullet::CapeGroup& group_;
  double microseconds_ = 0.0;
};

class BulletCapeRun final : public SceneRun {
 public:
  BulletCapeRun(std::unique_ptr<BulletScene> scene, int threads)
      : scene_(std::move(scene)),
        group_(std::make_unique<bullet::CapeGroup>(threads)),
        timed_(std::make_unique<TimedGroup>(*group_)) {}
  ~BulletCapeRun() override {
    scene_->world().removeAction(timed_.get());
    timed_.reset();
    group_.reset();
    capes_.clear();
  }

  bool build(const CapeSettings& settings, SceneKind kind, std::string& error) {
    for (int k = 0; k < scene_->characterCount(); ++k) {
      // The scene's settings turned into the world (the wind's direction; gravity comes from the world).
      CapeSettings inWorld = settingsForScene(kind, settings);
      inWorld.wind.direction = scene_->sceneToWorld() * inWorld.wind.direction;
      inWorld.gravity = scene_->sceneToWorld() * inWorld.gravity;
      auto cape = std::make_unique<bullet::CapeAction>(scene_->rig().fabric, inWorld,
                                                       bullet::toBt(scene_->capePlacement(k)));
      if (!cape->ok()) {
        error = cape->cape().status().message();
        return false;
      }
      // Placed relative to the scene's origin, in a frame at the grid point nearest that placement (zero
      // near the origin): moved there exactly, the frame kept at that grid point from the scene's origin. A
      // crowd's capes more than 8 m out (half CapeActionSettings::frameSpacing) keep frames of their own,
      // which relocating to the origin itself would have dropped, shifting the cape 16 m from its pins.
      cape->relocate(scene_->origin() + cape->frameOrigin());
      scene_->startCape(k, *cape);
      for (const PinSpec& p : scene_->pins(k)) cape->attach(p.particle, p.body, p.localPivot);
      group_->add(cape.get());
      capes_.push_back(std::move(cape));
    }
    scene_->world().addAction(timed_.get());
    return true;
  }

  /// Levels of detail by distance (RunOptions::lodDistances) from the viewpoint (scene frame, relative to
  /// the scene's origin; by default 4 m behind the last row, 1.6 m up).
  Status setDetail(const std::vector<double>& distances, const std::optional<Eigen::Vector3d>& viewpoint,
                   bool coarse) {
    if (distances.empty()) return Status::success();
    Eigen::Vector3d v = viewpoint.value_or(Eigen::Vector3d::Zero());
    if (!viewpoint) {
      // Behind the rows (the characters walk towards -Z), at the middle of them, at eye height.
      const Eigen::Matrix3d toScene = scene_->sceneToWorld().cast<double>().transpose();
      double minX = 1e300, maxX = -1e300, maxZ = -1e300;
      for (int k = 0; k < scene_->characterCount(); ++k) {
        const Eigen::Vector3d p = toScene * scene_->capePlacement(k).position.cast<double>();
        minX = std::min(minX, p.x()), maxX = std::max(maxX, p.x()), maxZ = std::max(maxZ, p.z());
      }
      v = Eigen::Vector3d(0.5 * (minX + maxX), 1.6, maxZ + 4.0);
    }
    viewpoint_ = scene_->sceneToWorld().cast<double>() * v + scene_->origin();
    const bullet::DetailLevel ladder[] = {{2, 0}, {4, 0, coarse}, {4, 2, coarse}};
    std::vector<bullet::DetailBand> bands;
    for (std::size_t k = 0; k < distances.size() && k < 3; ++k)
      bands.push_back({btScalar(distances[k]), ladder[k]});
    return group_->setDetailPolicy(
        btVector3(btScalar(viewpoint_.x()), btScalar(viewpoint_.y()), btScalar(viewpoint_.z())),
        std::move(bands));
  }
  std::vector<std::size_t> detailCounts() const override { return group_->detailCounts(); }
  void setParallelPrepare(bool parallel) { group_->setParallelPrepare(parallel); }
  Status setSpinMicroseconds(double microseconds) { return group_->setSpinMicroseconds(microseconds); }
  Eigen::Vector3d detailViewpoint() const override { return viewpoint_; }

  /// The same motion constraints on every character's cape (one fabric: one weight map fits them all).
  Status setMotionConstraints(const MotionConstraints& constraints) {
    for (auto& c : capes_) {
      Status s = c->cape().setMotionConstraints(constraints);
      if (!s.ok()) return s;
    }
    return Status::success();
  }

  int characterCount() const override { return scene_->characterCount(); }
  void advanceFrame() override {
    ++frame_;
    frameUs_ = scene_->stepFrame(frame_ / 60.0);
    capeUs_ = std::min(timed_->takeMicroseconds(), frameUs_);
    for (auto& c : capes_) c->takeAccumulatedMicroseconds();  // each cape's own work: not needed here
    guardTotals_.resize(capes_.size(), 0);
    guardLastFrame_.resize(capes_.size(), 0);
    for (std::size_t k = 0; k < capes_.size(); ++k) {
      const std::uint64_t total = capes_[k]->cape().guard().total;
      guardLastFrame_[k] =
          static_cast<std::uint32_t>(std::min<std::uint64_t>(total - guardTotals_[k], 0xffffffffu));
      guardTotals_[k] = total;
    }
  }
  const Cape& cape(int k) const override { return capes_[static_cast<std::size_t>(k)]->cape(); }
  std::vector<Collider> bodyColliders(int k) const override {
    return scene_->bodyColliders(k, capes_[static_cast<std::size_t>(k)]->frameOrigin());
  }
  Vec3 torsoCentre(int k) const override {
    return scene_->torsoCentre(k, capes_[static_cast<std::size_t>(k)]->frameOrigin());
  }
  std::uint32_t guardRestoredLastFrame(int k) const override {
    return guardLastFrame_.empty() ? 0 : guardLastFrame_[static_cast<std::size_t>(k)];
  }
  Eigen::Vector3d frameOffset(int k) const override {
    return capes_[static_cast<std::size_t>(k)]->frameOrigin() - scene_->origin();
  }
  double lastFrameTimeUs() const override { return frameUs_; }
  double lastCapeTimeUs() const override { return capeUs_; }
  double lastMotionTimeUs() const override { return scene_->lastMotionTimeUs(); }
  int worldObjectCount() const override { return scene_->world().getNumCollisionObjects(); }
  std::string describe() const override { return scene_->describe(); }
  Vec3 up() const override { return scene_->up(); }
  CapeSize capeSize() const override { return scene_->capeSize(); }
  const CapeSettings& settings() const override { return scene_->settings(); }

 private:
  std::unique_ptr<BulletScene> scene_;
  std::unique_ptr<bullet::CapeGroup> group_;
  std::unique_ptr<TimedGroup> timed_;  ///< the group in the world, timed
  std::vector<std::unique_ptr<bullet::CapeAction>> capes_;
  std::vector<std::uint64_t> guardTotals_;     ///< each cape's Cape::guard().total after the last frame
  std::vector<std::uint32_t> guardLastFrame_;  ///< what the guard restored in the last frame
  int frame_ = 0;
  double frameUs_ = 0.0, capeUs_ = 0.0;
  Eigen::Vector3d viewpoint_ = Eigen::Vector3d::Zero();
};

}  // namespace

std::unique_ptr<SceneRun> makeSceneRun(const RunOptions& options, std::string& error) {
  std::vector<std::string> warnings;
  std::unique_ptr<BulletScene> scene = BulletScene::create(options, error, WorldKind::SoftRigid, &warnings);
  for (const std::string& w : warnings) std::fprintf(stderr, "cape_walk: warning: %s\n", w.c_str());
  if (!scene) return nullptr;
  for (const std::string& n : scene->notes()) std::printf("cape_walk: %s\n", n.c_str());
  auto run = std::make_unique<BulletCapeRun>(std::move(scene), options.threads);
  run->setParallelPrepare(options.parallelPrepare);
  if (options.spinMicroseconds >= 0.0) {
    if (Status s = run->setSpinMicroseconds(options.spinMicroseconds); !s.ok()) {
      error = "--spin: " + s.message();
      return nullptr;
    }
  }
  if (!run->build(run->settings(), options.scene, error)) return nullptr;
  if (Status s = run->setDetail(options.lodDistances, options.viewpoint, options.lodCoarse); !s.ok()) {
    error = "--lod: " + s.message();
    return nullptr;
  }
  if (!options.maxDistanceMap.empty()) {
    GrayImage image;
    if (!readGrayPng(options.maxDistanceMap, image, error)) return nullptr;
    const WeightMapResult map = weightMapFromImage(run->cape(0).fabric(), image, options.maxDistanceRange[0],
                                                   options.maxDistanceRange[1]);
    if (!map) {
      error = "--max-distance-map: " + map.status.message();
      return nullptr;
    }
    MotionConstraints constraints;
    constraints.maxDistance = map.values;
    if (Status s = run->setMotionConstraints(constraints); !s.ok()) {
      error = "--max-distance-map: " + s.message();
      return nullptr;
    }
  }
  return run;
}

}  // namespace cape::demo
