// The walking humanoid drawn at 30, 60 and 144 Hz: stepSimulation(1 / rate, 8, 1 / 240) with the gait
// advanced to each render frame's time, the cape's pinned corners (CapeAction::renderPositions) against the
// shoulders as a renderer draws them, from their bodies' motion states (issue 17: within 1 mm).
#include "CapedHumanoid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

TEST(RenderRate, TheCapesCornersSitOnTheRenderedShouldersAtEveryRate) {
  for (const int rate : {30, 60, 144}) {
    capetest::CapedHumanoid h(20, false, cape::SceneKind::Walk);
    ASSERT_TRUE(h.ok);
    double drawn = 0.0, simulated = 0.0;
    for (int f = 1; f <= 2 * rate; ++f) {
      h.character->advanceTo(static_cast<double>(f) / rate);
      h.w.world.stepSimulation(btScalar(1.0 / rate), 8, btScalar(1.0 / 240.0));
      const cape::Points& x = h.action->renderPositions(h.w.world);
      ASSERT_TRUE(x.allFinite());
      for (const cape::bullet::Attachment& a : h.action->attachments()) {
        btTransform shown;
        a.body->getMotionState()->getWorldTransform(shown);
        const btVector3 shoulder = shown * a.localPivot;
        const btVector3 corner(x(a.particle, 0), x(a.particle, 1), x(a.particle, 2));
        drawn = std::max(drawn, static_cast<double>((corner - shoulder).length()));
        simulated =
            std::max(simulated, static_cast<double>((h.action->position(a.particle) - shoulder).length()));
      }
    }
    std::printf(
        "walking humanoid drawn at %d Hz: the cape's corners %.3f mm from the drawn shoulders "
        "(renderPositions), %.3f mm as simulated (positions)\n",
        rate, 1e3 * drawn, 1e3 * simulated);
    EXPECT_LT(drawn, 1e-3) << rate << " Hz";
  }
}
