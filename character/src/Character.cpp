// One walking character: skeleton, gait, mapping and bodies kept in step.
#include "cape/character/Character.h"

namespace cape::character {

CharacterResult Character::create(const UrdfModelPtr& model, btDynamicsWorld& world, const Gait& gait,
                                  const CharacterSettings& settings, const JointMapping* mapping) {
  CharacterResult result;
  if (!model) {
    result.status = Status::error(ErrorCode::InvalidArgument, "Character::create: no model");
    return result;
  }
  std::unique_ptr<Character> c(
      new Character(model, gait, settings, mapping ? *mapping : JointMapping::automatic(model)));
  result.status = c->skeleton_.setScale(settings.scale);
  if (!result.status.ok()) return result;
  c->gait_.apply(0.0, c->mapping_, c->skeleton_, settings.offset);
  c->bodies_ = std::make_unique<CharacterBodies>(world, c->skeleton_, settings.bodies);
  result.character = std::move(c);
  return result;
}

Character::Character(const UrdfModelPtr& model, const Gait& gait, const CharacterSettings& settings,
                     JointMapping mapping)
    : skeleton_(model), gait_(gait), settings_(settings), mapping_(std::move(mapping)) {}

void Character::advanceTo(double t) {
  gait_.apply(t, mapping_, skeleton_, settings_.offset);
  if (t > time_) {
    (void)bodies_->update(t - time_);
  } else {
    bodies_->teleport();
  }
  time_ = t;
}

std::vector<std::string> Character::warnings() const {
  std::vector<std::string> out = skeleton_.model().warnings();
  out.insert(out.end(), mapping_.warnings().begin(), mapping_.warnings().end());
  return out;
}

}  // namespace cape::character
