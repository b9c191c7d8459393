#include "SceneRun.h"

#include <chrono>

namespace cape::demo {

namespace {

using Clock = std::chrono::steady_clock;

class SimpleBodyRun final : public SceneRun {
 public:
  explicit SimpleBodyRun(const RunOptions& o) {
    const int k = o.scene == SceneKind::Crowd ? o.characters : 1;
    for (int c = 0; c < k; ++c) {
      // Crowd members walk side by side, 2 m apart along X.
      const Vec3 offset(2.0f * (static_cast<float>(c) - 0.5f * static_cast<float>(k - 1)), 0.0f, 0.0f);
      scenes_.push_back(std::make_unique<SimpleScene>(o.scene, o.size, o.attachment, o.settings, offset));
    }
  }
  const Status& status() const { return scenes_.front()->status(); }
  int characterCount() const override { return static_cast<int>(scenes_.size()); }
  void advanceFrame() override {
    const auto t0 = Clock::now();
    double cape = 0.0;
    for (auto& s : scenes_) {
      // SimpleScene::advanceFrame moves the body (negligible) and steps the cape.
      const auto c0 = Clock::now();
      s->advanceFrame();
      cape += std::chrono::duration<double, std::micro>(Clock::now() - c0).count();
    }
    frameUs_ = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    capeUs_ = cape;
  }
  const Cape& cape(int c) const override { return scenes_[static_cast<std::size_t>(c)]->cape(); }
  std::vector<Collider> bodyColliders(int c) const override {
    const ColliderSpan s = scenes_[static_cast<std::size_t>(c)]->body().bodyColliders();
    return std::vector<Collider>(s.begin(), s.end());
  }
  Vec3 torsoCentre(int c) const override { return scenes_[static_cast<std::size_t>(c)]->body().torsoCentre(); }
  double lastFrameTimeUs() const override { return frameUs_; }
  double lastCapeTimeUs() const override { return capeUs_; }
  std::string describe() const override { return "simple body of SCENARIOS.md (core only, no Bullet)"; }

 private:
  std::vector<std::unique_ptr<SimpleScene>> scenes_;
  double frameUs_ = 0.0, capeUs_ = 0.0;
};

}  // namespace

std::unique_ptr<SceneRun> makeSimpleBodyRun(const RunOptions& options, std::string& error) {
  auto run = std::make_unique<SimpleBodyRun>(options);
  if (!run->status().ok()) {
    error = run->status().message();
    return nullptr;
  }
  return run;
}

}  // namespace cape::demo
