// The shipped humanoid in a Bullet world wearing an N x N cape pinned by its top corners to the shoulders,
// fitted and placed as the demos fit it (demos/src/BulletScene.cpp: the pin line 4 cm above the shoulders'
// centre and 3 cm behind the back, the width and length from the shoulders), the action added to the world.
#pragma once

#include "cape/bullet/CapeAction.h"
#include "cape/bullet/Convert.h"
#include "cape/character/Anchors.h"
#include "cape/character/Character.h"
#include "cape/scenes/Scene.h"

#include "CharacterTestWorld.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>
#include <vector>

namespace capetest {

struct CapedHumanoid {
  /// ok is false (and a test failure recorded) if any part could not be made.
  CapedHumanoid(int n, bool selfCollision, cape::SceneKind gait) {
    using namespace cape::character;
    CharacterResult made = Character::create(UrdfModel::humanoid().model, w.world, Gait::forScene(gait));
    EXPECT_TRUE(made.ok()) << made.status.message();
    if (!made.ok()) return;
    character = std::move(made.character);
    Character& c = *character;
    const ShoulderAnchors a = findShoulderAnchors(c);
    EXPECT_TRUE(a.status.ok()) << a.status.message();
    if (!a.status.ok()) return;
    cape::CapeSize size;
    const double span = std::fabs(a.right.x() - a.left.x());
    size.width = static_cast<float>(std::round(std::clamp(span + 0.16, 0.2, 3.0) * 1000.0) / 1000.0);
    const double pinHeight = 0.5 * (a.left.y() + a.right.y()) + 0.04;
    size.height = static_cast<float>(std::round(std::clamp(pinHeight - 0.45, 0.2, 1.0) * 1000.0) / 1000.0);
    const cape::CapeRig rig = cape::makeCapeRig(n, cape::PinLayout::Corners, true, size);
    EXPECT_TRUE(rig.fabric != nullptr);
    if (!rig.fabric) return;
    const cape::Vec3 centre = (a.left.cast<float>() + a.right.cast<float>()) / 2.0f;
    const cape::Vec3 shift =
        centre + cape::Vec3(0.0f, 0.04f, static_cast<float>(a.back + 0.03)) - cape::Vec3(0.0f, 1.56f, 0.15f);
    cape::Pose placement = cape::capeStartPlacement(cape::SceneKind::Walk, size);  // hanging straight down
    placement.position += shift;
    cape::CapeSettings settings;
    settings.selfCollision = selfCollision;
    action = std::make_unique<cape::bullet::CapeAction>(
        rig.fabric, cape::settingsForScene(cape::SceneKind::Hang, settings), cape::bullet::toBt(placement));
    EXPECT_TRUE(action->ok()) << action->cape().status().message();
    if (!action->ok()) return;
    std::vector<std::pair<float, btRigidBody*>> anchors;
    for (int link : {a.leftLink, a.rightLink}) {
      btRigidBody* body = c.bodies().bodyForLink(link);
      EXPECT_NE(body, nullptr);
      if (!body) return;
      anchors.emplace_back(static_cast<float>(c.skeleton().linkPose(link).translation().x()), body);
    }
    for (std::size_t p = 0; p < rig.pinnedParticles.size(); ++p) {
      const cape::Vec3 point = rig.pinLocalPoints[p] + shift;
      const auto nearest =
          std::min_element(anchors.begin(), anchors.end(), [&](const auto& l, const auto& r) {
            return std::fabs(l.first - point.x()) < std::fabs(r.first - point.x());
          });
      btRigidBody* body = nearest->second;
      action->attach(rig.pinnedParticles[p], body,
                     body->getWorldTransform().inverse() * cape::bullet::toBt(point));
    }
    w.world.addAction(action.get());
    ok = true;
  }
  ~CapedHumanoid() {
    if (action) w.world.removeAction(action.get());
  }
  CapedHumanoid(const CapedHumanoid&) = delete;
  CapedHumanoid& operator=(const CapedHumanoid&) = delete;

  World w;
  std::unique_ptr<cape::character::Character> character;
  std::unique_ptr<cape::bullet::CapeAction> action;
  bool ok = false;
};

}  // namespace capetest
