// The character library against the installed package: the shipped humanoid walks in a plain Bullet world,
// the cape's anchors are found from its joint mapping, and a URDF whose link is an OBJ mesh (through assimp,
// a private dependency of the installed static library) loads as a convex hull. Exit status 0 on success.
#include <cape/character/Anchors.h>
#include <cape/character/Character.h>

#include <btBulletDynamicsCommon.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

int main() {
  using namespace cape::character;
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &configuration);
  const UrdfLoadResult humanoid = UrdfModel::humanoid();
  CharacterResult made = Character::create(humanoid.model, world, Gait::forScene(cape::SceneKind::Walk));
  if (!made.ok()) return std::fprintf(stderr, "%s\n", made.status.message().c_str()), 1;
  for (int frame = 1; frame <= 60; ++frame) {
    made.character->advanceTo(frame / 60.0);
    world.stepSimulation(1.0f / 60, 8, 1.0f / 240);
  }
  const ShoulderAnchors anchors = findShoulderAnchors(*made.character);
  std::printf("anchors: %s, back %.2f m\n", anchors.description.c_str(), anchors.back);

  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "cape_character_consumer";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "tetra.obj")
      << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  std::ofstream(dir / "robot.urdf")
      << "<robot name='m'><link name='l'><collision><geometry>"
         "<mesh filename='tetra.obj' scale='0.1 0.1 0.1'/></geometry></collision>"
         "</link></robot>";
  const UrdfLoadResult mesh = UrdfModel::fromFile((dir / "robot.urdf").string());
  std::filesystem::remove_all(dir);
  if (!mesh.ok()) return std::fprintf(stderr, "%s\n", mesh.status.message().c_str()), 1;
  const ShapeDesc& hull = mesh.model->links()[0].shapes.at(0);
  std::printf("mesh link: %s of %zu vertices\n", toString(hull.type), hull.hull.size());
  return anchors.status.ok() && hull.type == ShapeType::ConvexHull && hull.hull.size() == 4 ? 0 : 1;
}
