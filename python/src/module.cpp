// The capecloth Python module: World (a Bullet world that owns what is added to it), Body (a kinematic body
// of the user's), Character (a URDF character), Cape (an XPBD cape), CapeSettings and WindSettings. The API
// guide is docs/PYTHON.md.
#include "Arrays.h"
#include "PyWorld.h"

#include "cape/core/FabricPresets.h"
#include "cape/core/Simd.h"

#include <pybind11/stl.h>

#include <memory>

namespace py = pybind11;
using namespace py::literals;

namespace capepy {
namespace {

// None: empty (off); a number: the same for every one of n particles; else one value per particle (a 1-D
// array, a weight map). ValueError for anything else.
Eigen::VectorXf perParticle(const py::object& o, Eigen::Index n, const char* name) {
  Eigen::VectorXf v;
  if (o.is_none()) return v;
  if (py::isinstance<py::float_>(o) || py::isinstance<py::int_>(o)) {
    v = Eigen::VectorXf::Constant(n, o.cast<float>());
    return v;
  }
  const auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(o);
  if (!a || a.ndim() != 1)
    throw py::value_error(std::string(name) + " must be None, a number or a 1-D array of " +
                          std::to_string(n) + " values");
  v = Eigen::Map<const Eigen::VectorXf>(a.data(), a.shape(0));
  return v;
}

using WorldPtr = std::shared_ptr<World>;

/// Handles: a world and an index. Python may keep them as long as it likes; they keep their world alive.
struct BodyHandle {
  WorldPtr world;
  int index;
};
struct CharacterHandle {
  WorldPtr world;
  int index;
};
struct CapeHandle {
  WorldPtr world;
  int index;
};

cape::Vec3 toVec3f(const py::handle& object, const std::string& what) {
  return vec3FromObject(object, what).cast<float>();
}

Eigen::Isometry3d defaultFrame(const World& world) {
  Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
  frame.linear() = cape::character::Skeleton::sceneToWorld(world.up());
  return frame;
}

py::dict metricsDict(const cape::FrameMetrics& m) {
  return py::dict("max_strain"_a = m.maxStrain, "mean_strain"_a = m.meanStrain,
                  "max_penetration"_a = m.maxPenetration, "self_intersections"_a = m.selfIntersections,
                  "pin_error"_a = m.pinError, "mean_speed"_a = m.meanSpeed,
                  "guard_restored"_a = m.guardRestored, "blow_up"_a = m.blowUp);
}

py::dict summaryDict(const cape::RunSummary& s) {
  return py::dict(
      "frames"_a = s.frames, "max_strain"_a = s.maxStrain, "mean_strain"_a = s.meanStrain,
      "median_frame_max_strain"_a = s.medianFrameMaxStrain, "p95_frame_max_strain"_a = s.p95FrameMaxStrain,
      "max_penetration"_a = s.maxPenetration, "frames_penetration_over_1mm"_a = s.framesPenetrationOver1mm,
      "self_intersections_max"_a = s.selfIntersectionsMax,
      "frames_with_self_intersections"_a = s.framesWithSelfIntersections, "pin_error_max"_a = s.pinErrorMax,
      "guard_restored"_a = s.guardRestored, "frames_guard_restored"_a = s.framesGuardRestored,
      "blow_up"_a = s.blowUp, "rest_jitter"_a = s.restJitter);
}

py::dict collidersDict(const std::vector<ColliderInfo>& colliders, QuatOrder order) {
  const auto n = static_cast<py::ssize_t>(colliders.size());
  py::list owner, shape;
  py::array_t<double> radius(n), halfHeight(n), halfExtents({n, py::ssize_t(3)});
  py::array_t<int> axis(n);
  std::vector<Eigen::Isometry3d> poses;
  for (py::ssize_t i = 0; i < n; ++i) {
    const ColliderInfo& c = colliders[static_cast<std::size_t>(i)];
    owner.append(c.owner);
    std::string name = cape::toString(c.shape);
    for (char& ch : name) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    shape.append(name == "convexhull" ? "convex_hull" : name == "trianglemesh" ? "triangle_mesh" : name);
    radius.mutable_at(i) = c.radius;
    halfHeight.mutable_at(i) = c.halfHeight;
    axis.mutable_at(i) = c.axis;
    for (int k = 0; k < 3; ++k) halfExtents.mutable_at(i, k) = c.halfExtents[k];
    poses.push_back(c.pose);
  }
  return py::dict("owner"_a = owner, "shape"_a = shape, "radius"_a = radius, "half_height"_a = halfHeight,
                  "axis"_a = axis, "half_extents"_a = halfExtents, "poses"_a = posesToArray(poses, order));
}

BodyHandle addBody(const WorldPtr& w, BodyShape shape, const Eigen::Vector3d& size, int axis,
                   const py::object& pose, const std::string& name) {
  const Eigen::Isometry3d p =
      pose.is_none() ? Eigen::Isometry3d::Identity() : poseFromObject(pose, QuatOrder::Xyzw, "pose");
  return BodyHandle{w, w->addBody(shape, size, axis, p, name)};
}

int parseAxis(const std::string& axis) {
  if (axis == "x") return 0;
  if (axis == "y") return 1;
  if (axis == "z") return 2;
  throw std::invalid_argument("axis must be \"x\", \"y\" or \"z\", not \"" + axis + "\"");
}

CharacterHandle addCharacter(const WorldPtr& w, CharacterSpec spec, const py::object& offset) {
  if (!offset.is_none()) spec.offset = vec3FromObject(offset, "offset");
  return CharacterHandle{w, w->addCharacter(spec)};
}

CapeSpec capeSpec(int resolution, const std::string& pins, std::optional<double> width,
                  std::optional<double> height, const std::optional<cape::CapeSettings>& settings,
                  const std::string& fabric) {
  CapeSpec spec;
  spec.fabric = fabric;
  spec.resolution = resolution;
  spec.pins = pins;
  spec.width = width;
  spec.height = height;
  if (settings) spec.settings = *settings;
  return spec;
}

void bindSettings(py::module_& m) {
  py::enum_<cape::Integrator>(m, "Integrator", "How the cape's equations of motion are integrated.")
      .value("XPBD", cape::Integrator::Xpbd)
      .value("EXPLICIT_SPRING", cape::Integrator::ExplicitSpring);

  py::class_<cape::WindSettings> wind(
      m, "WindSettings", "Wind acting on a cape (cape::WindSettings): speeds in m/s, frequency in Hz.");
  py::enum_<cape::WindSettings::Model>(wind, "Model")
      .value("NONE", cape::WindSettings::Model::None)
      .value("SINE_WAVE", cape::WindSettings::Model::SineWave)
      .value("AERODYNAMIC", cape::WindSettings::Model::Aerodynamic);
  wind.def(py::init<>())
      .def_readwrite("model", &cape::WindSettings::model)
      .def_property(
          "direction", [](const cape::WindSettings& s) { return vec3ToArray(s.direction.cast<double>()); },
          [](cape::WindSettings& s, const py::object& v) { s.direction = toVec3f(v, "direction"); },
          "Unit direction of the mean wind, world.")
      .def_readwrite("speed", &cape::WindSettings::speed, "Mean wind speed, m/s.")
      .def_readwrite("gust_amplitude", &cape::WindSettings::gustAmplitude,
                     "Relative gust strength (0.5 = +-50 %).")
      .def_readwrite("gust_frequency", &cape::WindSettings::gustFrequency, "Hz.")
      .def_readwrite("turbulence_scale", &cape::WindSettings::turbulenceScale,
                     "m: spatial scale of the turbulence.")
      .def_readwrite("air_density", &cape::WindSettings::airDensity, "kg/m^3.")
      .def_readwrite("drag_coefficient", &cape::WindSettings::dragCoefficient)
      .def_readwrite("lift_coefficient", &cape::WindSettings::liftCoefficient)
      .def_readwrite("seed", &cape::WindSettings::seed);

  py::class_<cape::CapeSettings>(
      m, "CapeSettings", "Per-cape parameters (cape::CapeSettings), each with its unit; checked when set.")
      .def(py::init<>())
      .def_readwrite("integrator", &cape::CapeSettings::integrator)
      .def_readwrite("structural_stiffness", &cape::CapeSettings::structuralStiffness, "N/m per spring.")
      .def_readwrite("shear_stiffness", &cape::CapeSettings::shearStiffness, "N/m per spring.")
      .def_readwrite("bend_stiffness", &cape::CapeSettings::bendStiffness, "N/m per spring.")
      .def_readwrite("bending_rigidity", &cape::CapeSettings::bendingRigidity,
                     "N m: linear bending, flexural rigidity per unit width (0 = off).")
      .def_readwrite("use_tethers", &cape::CapeSettings::useTethers)
      .def_readwrite("damping", &cape::CapeSettings::damping, "1/s: dv/dt = -damping v.")
      .def_readwrite("collision_thickness", &cape::CapeSettings::collisionThickness, "m.")
      .def_readwrite("friction", &cape::CapeSettings::friction, "Coulomb coefficient against colliders.")
      .def_readwrite("substeps", &cape::CapeSettings::substeps, "Substeps per time_step, >= 1.")
      .def_readwrite("strain_limit", &cape::CapeSettings::strainLimit,
                     "Adaptive substepping threshold, 0 = off.")
      .def_readwrite("max_refinement", &cape::CapeSettings::maxRefinement)
      .def_readwrite("strain_ceiling", &cape::CapeSettings::strainCeiling,
                     "Strain limiting: the most a structural spring may stretch, 0..10 (0 = off).")
      .def_readwrite("strain_ceiling_passes", &cape::CapeSettings::strainCeilingPasses,
                     "Passes over the structural springs per iteration, 1..64.")
      .def_readwrite("guard_reach", &cape::CapeSettings::guardReach,
                     "Rest diameters beyond the farthest pin.")
      .def_readwrite("sleep_speed", &cape::CapeSettings::sleepSpeed, "m/s; 0 never sleeps.")
      .def_readwrite("sleep_delay", &cape::CapeSettings::sleepDelay, "s.")
      .def_readwrite("iterations", &cape::CapeSettings::iterations,
                     "Constraint iterations per substep, >= 1.")
      .def_property(
          "gravity", [](const cape::CapeSettings& s) { return vec3ToArray(s.gravity.cast<double>()); },
          [](cape::CapeSettings& s, const py::object& v) { s.gravity = toVec3f(v, "gravity"); },
          "m/s^2 (a cape in a World takes the world's gravity).")
      .def_readwrite("time_step", &cape::CapeSettings::timeStep, "s: the frame time substeps count per.")
      .def_readwrite("wind", &cape::CapeSettings::wind)
      .def_readwrite("self_collision", &cape::CapeSettings::selfCollision)
      .def_readwrite("self_collision_thickness", &cape::CapeSettings::selfCollisionThickness,
                     "m; 0 = automatic.")
      .def(
          "validate",
          [](const cape::CapeSettings& s) {
            const cape::Status st = s.validate();
            if (!st.ok()) throw std::invalid_argument(st.message());
          },
          "Raises ValueError with the library's message when a field is out of range.");
}

void bindHandles(py::module_& m) {
  py::class_<BodyHandle>(m, "Body",
                         "A kinematic body of the world (sphere, box or capsule), moved by its pose.")
      .def_property_readonly("index", [](const BodyHandle& b) { return b.index; })
      .def_property_readonly("name", [](const BodyHandle& b) { return b.world->bodyName(b.index); })
      .def(
          "set_pose",
          [](const BodyHandle& b, const py::object& pose, const py::object& position,
             const py::object& quaternion, bool teleport, const std::string& order) {
            const QuatOrder o = parseQuatOrder(order);
            if (pose.is_none() == position.is_none())
              throw std::invalid_argument("give either pose (7 numbers or 4x4) or position [and quaternion]");
            b.world->setBodyPose(b.index,
                                 pose.is_none() ? poseFromParts(position, quaternion, o, "body")
                                                : poseFromObject(pose, o, "pose"),
                                 teleport);
          },
          "pose"_a = py::none(), py::kw_only(), "position"_a = py::none(), "quaternion"_a = py::none(),
          "teleport"_a = false, "order"_a = "xyzw",
          "Moves the body for the next step (m, world). Bullet gives it the velocity of the move; "
          "teleport=True "
          "jumps at rest.")
      .def(
          "pose",
          [](const BodyHandle& b, const std::string& order) {
            return poseToArray(b.world->bodyPose(b.index), parseQuatOrder(order));
          },
          "order"_a = "xyzw", "(7,): x, y, z (m), then the quaternion in `order`.")
      .def_property_readonly("matrix",
                             [](const BodyHandle& b) { return matrixToArray(b.world->bodyPose(b.index)); })
      .def_property_readonly(
          "position",
          [](const BodyHandle& b) { return vec3ToArray(b.world->bodyPose(b.index).translation()); })
      .def("__repr__",
           [](const BodyHandle& b) { return "<capecloth.Body " + b.world->bodyName(b.index) + ">"; });

  py::class_<CharacterHandle>(m, "Character",
                              "A URDF character: one kinematic Bullet body per link with shapes.")
      .def_property_readonly("index", [](const CharacterHandle& c) { return c.index; })
      .def_property_readonly("link_names",
                             [](const CharacterHandle& c) { return c.world->linkNames(c.index); })
      .def_property_readonly("joint_names",
                             [](const CharacterHandle& c) { return c.world->jointNames(c.index); })
      .def_property_readonly("spherical_joint_names",
                             [](const CharacterHandle& c) { return c.world->sphericalJointNames(c.index); })
      .def_property_readonly("warnings",
                             [](const CharacterHandle& c) { return c.world->characterWarnings(c.index); })
      .def_property_readonly("root_height",
                             [](const CharacterHandle& c) { return c.world->rootHeight(c.index); })
      .def_property_readonly("time", [](const CharacterHandle& c) { return c.world->characterTime(c.index); })
      .def(
          "advance_to", [](const CharacterHandle& c, double t) { c.world->advanceCharacter(c.index, t); },
          "t"_a, "Poses the character by its gait at time t (s); a t not after the last is a jump.")
      .def(
          "set_motion",
          [](const CharacterHandle& c, double t, const py::object& root, const py::object& joints,
             const py::object& rotations, const std::string& order) {
            const QuatOrder o = parseQuatOrder(order);
            cape::character::JointPose jp;
            if (!joints.is_none())
              for (const auto& [name, value] : joints.cast<py::dict>())
                jp.emplace_back(name.cast<std::string>(), value.cast<double>());
            cape::character::JointRotations jr;
            if (!rotations.is_none())
              for (const auto& [name, value] : rotations.cast<py::dict>())
                jr.emplace_back(name.cast<std::string>(),
                                quatFromObject(value, o, "rotation of " + name.cast<std::string>()));
            c.world->setCharacterMotion(c.index, t, poseFromObject(root, o, "root_pose"), jp, jr);
          },
          "t"_a, "root_pose"_a, "joints"_a = py::none(), "rotations"_a = py::none(), "order"_a = "xyzw",
          "Your own motion at time t (s): the URDF root link's world pose, joint positions by name (rad, or "
          "m), "
          "spherical joints' rotations by name.")
      .def(
          "set_link_poses",
          [](const CharacterHandle& c, const py::object& poses, bool teleport, const std::string& order) {
            c.world->setLinkPoses(c.index, posesFromObject(poses, parseQuatOrder(order), "poses"), teleport);
          },
          "poses"_a, py::kw_only(), "teleport"_a = false, "order"_a = "xyzw",
          "Moves every link's body to a world pose ((L, 7) or (L, 4, 4), link_names order): a robot's link "
          "poses "
          "from PyBullet or MuJoCo. link_poses() keeps reporting the skeleton's pose.")
      .def(
          "link_poses",
          [](const CharacterHandle& c, const std::string& order) {
            return posesToArray(c.world->linkPoses(c.index), parseQuatOrder(order));
          },
          "order"_a = "xyzw", "(L, 7): each link's world pose from the skeleton (gait or set_motion).")
      .def(
          "attach_cape",
          [](const CharacterHandle& c, int resolution, const std::string& pins, std::optional<double> width,
             std::optional<double> height, const std::optional<cape::CapeSettings>& settings,
             const std::string& fabric) {
            return CapeHandle{c.world,
                              c.world->addCapeOnCharacter(
                                  capeSpec(resolution, pins, width, height, settings, fabric), c.index)};
          },
          "resolution"_a = 20, "pins"_a = "corners", "width"_a = py::none(), "height"_a = py::none(),
          "settings"_a = py::none(), "fabric"_a = "",
          "A cape fitted to the character's shoulders at its current pose (call before it moves): width and "
          "height in m, fitted when not given; fabric: a preset's name (fabric_names()).");

  py::class_<CapeHandle>(m, "Cape", "A cape in the world: its mesh, settings and metrics.")
      .def_property_readonly("index", [](const CapeHandle& c) { return c.index; })
      .def_property_readonly("description",
                             [](const CapeHandle& c) { return c.world->capeDescription(c.index); })
      .def_property(
          "settings", [](const CapeHandle& c) { return c.world->capeSettings(c.index); },
          [](const CapeHandle& c, const cape::CapeSettings& s) { c.world->setCapeSettings(c.index, s); },
          "A copy of the settings; assign a changed copy back (ValueError on bad values).")
      .def_property(
          "wind", [](const CapeHandle& c) { return c.world->capeSettings(c.index).wind; },
          [](const CapeHandle& c, const cape::WindSettings& w) {
            cape::CapeSettings s = c.world->capeSettings(c.index);
            s.wind = w;
            c.world->setCapeSettings(c.index, s);
          })
      .def_property(
          "self_collision", [](const CapeHandle& c) { return c.world->capeSettings(c.index).selfCollision; },
          [](const CapeHandle& c, bool on) {
            cape::CapeSettings s = c.world->capeSettings(c.index);
            s.selfCollision = on;
            c.world->setCapeSettings(c.index, s);
          })
      .def_property(
          "count_self_intersections",
          [](const CapeHandle& c) { return c.world->countSelfIntersections(c.index); },
          [](const CapeHandle& c, bool on) { c.world->setCountSelfIntersections(c.index, on); },
          "Count intersecting triangle pairs in the per-frame metrics (off by default: a pass over the "
          "triangles for a grid cape that lies flat, a spatial hash and exact tests for one that folds).")
      .def_property_readonly(
          "positions", [](const CapeHandle& c) { return pointsToArray(c.world->capePositions(c.index)); },
          "(N, 3) float32, m, world.")
      .def_property_readonly(
          "animated_positions",
          [](const CapeHandle& c) { return pointsToArray(c.world->capeAnimatedPositions(c.index)); },
          "(N, 3) float32, m, world: each particle's animated position of the last step (the rest shape "
          "fitted to the pins), what set_motion_constraints holds the cape to.")
      .def(
          "set_motion_constraints",
          [](const CapeHandle& c, const py::object& maxDistance, const py::object& backstopRadius,
             const py::object& backstopDistance, const py::object& drive, bool backstopAlongNormal) {
            const Eigen::Index n = c.world->capePositions(c.index).rows();
            // None: off; a number: the same for every particle; else one value per particle (a weight map).
            const auto values = [n](const py::object& o, const char* name) {
              return perParticle(o, n, name);
            };
            cape::MotionConstraints m;
            m.maxDistance = values(maxDistance, "max_distance");
            m.backstopRadius = values(backstopRadius, "backstop_radius");
            m.backstopDistance = values(backstopDistance, "backstop_distance");
            m.drive = values(drive, "drive");
            m.backstopAlongNormal = backstopAlongNormal;
            c.world->setMotionConstraints(c.index, m);
          },
          py::kw_only(), "max_distance"_a = py::none(), "backstop_radius"_a = py::none(),
          "backstop_distance"_a = py::none(), "drive"_a = py::none(), "backstop_along_normal"_a = false,
          "Motion constraints to each particle's animated position (animated_positions): max_distance (m), "
          "backstop_radius and backstop_distance (m: a sphere behind the animated surface), drive (0..1 per "
          "1/60 s). Each None (off), a number (every particle) or one value per particle (a weight map, e.g. "
          "from the uvs). ValueError on bad values; the old constraints are kept then.")
      .def(
          "set_mass_scale",
          [](const CapeHandle& c, const py::object& scale) {
            c.world->setWeightScale(c.index, true,
                                    perParticle(scale, c.world->capePositions(c.index).rows(), "scale"));
          },
          "scale"_a,
          "Each particle's mass times scale (None: the fabric's masses; a number: every particle; or one "
          "value "
          "per particle, a weight map), in (0, 1e6]. ValueError on bad values; the old scale is kept then.")
      .def(
          "set_detail_level",
          [](const CapeHandle& c, int stepInterval, int substeps, bool coarseFabric) {
            c.world->setDetailLevel(c.index, stepInterval, substeps, coarseFabric);
          },
          "step_interval"_a = 1, "substeps"_a = 0, "coarse_fabric"_a = false,
          "Level of detail: the cape steps once every step_interval (1..64) internal steps of the world, "
          "over their time together, with substeps per 1/60 s (0: the settings' own), and with coarse_fabric "
          "on the grid's coarse level (a 20 x 20 cape's 10 x 10), its particles interpolated from it. No "
          "particle jumps at a switch. (1, 0, False), the default, is full detail. ValueError on a bad "
          "level; "
          "the old one is kept then.")
      .def_property_readonly(
          "detail_level", [](const CapeHandle& c) { return c.world->detailLevel(c.index); },
          "The level of detail: (step_interval, substeps, coarse_fabric).")
      .def(
          "set_stiffness_scale",
          [](const CapeHandle& c, const py::object& scale) {
            c.world->setWeightScale(c.index, false,
                                    perParticle(scale, c.world->capePositions(c.index).rows(), "scale"));
          },
          "scale"_a,
          "Each spring's stiffness times the mean of its ends' scale, each bending hinge's times its "
          "middle's "
          "(None: unscaled; a number; or one value per particle), in (0, 1e6]. ValueError on bad values.")
      .def_property_readonly(
          "normals", [](const CapeHandle& c) { return pointsToArray(c.world->capeNormals(c.index)); },
          "(N, 3) float32 unit area-weighted vertex normals.")
      .def_property_readonly(
          "velocities", [](const CapeHandle& c) { return pointsToArray(c.world->capeVelocities(c.index)); },
          "(N, 3) float32, m/s.")
      .def_property_readonly(
          "triangles",
          [](const CapeHandle& c) {
            const std::vector<std::uint32_t> t = c.world->capeTriangles(c.index);
            py::array_t<std::uint32_t> out({static_cast<py::ssize_t>(t.size() / 3), py::ssize_t(3)});
            std::copy(t.begin(), t.end(), out.mutable_data());
            return out;
          },
          "(M, 3) uint32, counter-clockwise seen from the front.")
      .def_property_readonly(
          "uvs",
          [](const CapeHandle& c) {
            const std::vector<Eigen::Vector2f> uv = c.world->capeUvs(c.index);
            py::array_t<float> out({static_cast<py::ssize_t>(uv.size()), py::ssize_t(2)});
            for (std::size_t i = 0; i < uv.size(); ++i)
              for (int k = 0; k < 2; ++k) out.mutable_at(static_cast<py::ssize_t>(i), k) = uv[i][k];
            return out;
          },
          "(N, 2) float32.")
      .def_property_readonly("pinned_particles",
                             [](const CapeHandle& c) {
                               const std::vector<std::uint32_t> p = c.world->capePinnedParticles(c.index);
                               py::array_t<std::uint32_t> out(static_cast<py::ssize_t>(p.size()));
                               std::copy(p.begin(), p.end(), out.mutable_data());
                               return out;
                             })
      .def_property_readonly("particle_count",
                             [](const CapeHandle& c) { return c.world->capePositions(c.index).rows(); })
      .def_property_readonly("asleep", [](const CapeHandle& c) { return c.world->capeAsleep(c.index); })
      .def_property_readonly("warnings", [](const CapeHandle& c) { return c.world->capeWarnings(c.index); })
      .def(
          "metrics", [](const CapeHandle& c) { return metricsDict(c.world->capeMetrics(c.index)); },
          "The last frame's metrics (docs/SCENES.md): strain, penetration (m), pin error (m), mean speed "
          "(m/s).")
      .def(
          "summary", [](const CapeHandle& c) { return summaryDict(c.world->capeSummary(c.index)); },
          "Every frame so far, summarised (cape::RunSummary).");
}

void bindWorld(py::module_& m) {
  py::class_<World, WorldPtr>(m, "World", "A Bullet btDiscreteDynamicsWorld that owns what is added to it.")
      .def(py::init([](const std::string& up, bool ground, double groundHeight, const py::object& gravity) {
             WorldSettings s;
             if (up == "y") {
               s.up = cape::character::UpAxis::Y;
             } else if (up == "z") {
               s.up = cape::character::UpAxis::Z;
             } else {
               throw std::invalid_argument("up must be \"y\" or \"z\", not \"" + up + "\"");
             }
             s.ground = ground;
             s.groundHeight = groundHeight;
             if (!gravity.is_none()) s.gravity = vec3FromObject(gravity, "gravity");
             return std::make_shared<World>(s);
           }),
           py::kw_only(), "up"_a = "y", "ground"_a = true, "ground_height"_a = 0.0, "gravity"_a = py::none())
      .def_property_readonly("up",
                             [](const World& w) { return w.up() == cape::character::UpAxis::Y ? "y" : "z"; })
      .def_property_readonly("time", &World::time, "s simulated so far.")
      .def_property_readonly("gravity", [](const World& w) { return vec3ToArray(w.gravity()); })
      .def(
          "add_sphere",
          [](const WorldPtr& w, double radius, const py::object& pose, const std::string& name) {
            return addBody(w, BodyShape::Sphere, Eigen::Vector3d(radius, 0, 0), 1, pose, name);
          },
          "radius"_a, "pose"_a = py::none(), "name"_a = "", "A kinematic sphere, radius in m.")
      .def(
          "add_box",
          [](const WorldPtr& w, const py::object& halfExtents, const py::object& pose,
             const std::string& name) {
            return addBody(w, BodyShape::Box, vec3FromObject(halfExtents, "half_extents"), 1, pose, name);
          },
          "half_extents"_a, "pose"_a = py::none(), "name"_a = "", "A kinematic box, half extents in m.")
      .def(
          "add_capsule",
          [](const WorldPtr& w, double radius, double halfHeight, const std::string& axis,
             const py::object& pose, const std::string& name) {
            return addBody(w, BodyShape::Capsule, Eigen::Vector3d(radius, halfHeight, 0), parseAxis(axis),
                           pose, name);
          },
          "radius"_a, "half_height"_a, "axis"_a = "y", "pose"_a = py::none(), "name"_a = "",
          "A kinematic capsule: radius and half the distance between its sphere centres (m), along a local "
          "axis.")
      .def_property_readonly("bodies",
                             [](const WorldPtr& w) {
                               std::vector<BodyHandle> out;
                               for (int i = 0; i < w->bodyCount(); ++i) out.push_back(BodyHandle{w, i});
                               return out;
                             })
      .def(
          "set_body_poses",
          [](const WorldPtr& w, const py::object& poses, bool teleport, const std::string& order) {
            w->setBodyPoses(posesFromObject(poses, parseQuatOrder(order), "poses"), teleport);
          },
          "poses"_a, py::kw_only(), "teleport"_a = false, "order"_a = "xyzw",
          "Moves every body at once: (N, 7) or (N, 4, 4), in the order they were added.")
      .def(
          "add_humanoid",
          [](const WorldPtr& w, const std::string& gait, double scale, const py::object& offset) {
            CharacterSpec spec;
            spec.gait = gait;
            spec.scale = scale;
            return addCharacter(w, spec, offset);
          },
          py::kw_only(), "gait"_a = "stand", "scale"_a = 1.0, "offset"_a = py::none(),
          "The shipped humanoid, standing on the ground.")
      .def(
          "load_urdf",
          [](const WorldPtr& w, const std::string& path, const std::vector<std::string>& packagePaths,
             const std::string& gait, double scale, const py::object& offset, const std::string& modelUp) {
            if (path.empty()) throw std::invalid_argument("load_urdf: an empty path");
            CharacterSpec spec;
            spec.path = path;
            spec.packagePaths = packagePaths;
            spec.gait = gait;
            spec.scale = scale;
            spec.modelUp = modelUp;
            return addCharacter(w, spec, offset);
          },
          "path"_a, py::kw_only(), "package_paths"_a = std::vector<std::string>(), "gait"_a = "stand",
          "scale"_a = 1.0, "offset"_a = py::none(), "model_up"_a = "auto",
          "A URDF file; package://NAME/... meshes are looked up in package_paths (then ROS_PACKAGE_PATH).")
      .def(
          "load_urdf_string",
          [](const WorldPtr& w, const std::string& text, const std::vector<std::string>& packagePaths,
             const std::string& gait, double scale, const py::object& offset, const std::string& modelUp) {
            if (text.empty()) throw std::invalid_argument("load_urdf_string: an empty text");
            CharacterSpec spec;
            spec.text = text;
            spec.packagePaths = packagePaths;
            spec.gait = gait;
            spec.scale = scale;
            spec.modelUp = modelUp;
            return addCharacter(w, spec, offset);
          },
          "text"_a, py::kw_only(), "package_paths"_a = std::vector<std::string>(), "gait"_a = "stand",
          "scale"_a = 1.0, "offset"_a = py::none(), "model_up"_a = "auto")
      .def_property_readonly("characters",
                             [](const WorldPtr& w) {
                               std::vector<CharacterHandle> out;
                               for (int i = 0; i < w->characterCount(); ++i)
                                 out.push_back(CharacterHandle{w, i});
                               return out;
                             })
      .def(
          "add_cape",
          [](const WorldPtr& w, const std::vector<BodyHandle>& bodies, const py::object& frame,
             int resolution, const std::string& pins, std::optional<double> width,
             std::optional<double> height, const std::optional<cape::CapeSettings>& settings,
             const std::string& fabric) {
            std::vector<int> indices;
            for (const BodyHandle& b : bodies) {
              if (b.world != w) throw std::invalid_argument("a body of another world");
              indices.push_back(b.index);
            }
            const Eigen::Isometry3d f =
                frame.is_none() ? defaultFrame(*w) : poseFromObject(frame, QuatOrder::Xyzw, "frame");
            return CapeHandle{
                w,
                w->addCapeOnBodies(capeSpec(resolution, pins, width, height, settings, fabric), f, indices)};
          },
          "bodies"_a, py::kw_only(), "frame"_a = py::none(), "resolution"_a = 20, "pins"_a = "corners",
          "width"_a = py::none(), "height"_a = py::none(), "settings"_a = py::none(), "fabric"_a = "",
          "The canonical cape (cape::makeCapeRig) of docs/SCENES.md in a character frame: pins at frame * "
          "(+-width/2, 1.56, 0.15), each on the nearest of `bodies`.")
      .def_property_readonly("capes",
                             [](const WorldPtr& w) {
                               std::vector<CapeHandle> out;
                               for (int i = 0; i < w->capeCount(); ++i) out.push_back(CapeHandle{w, i});
                               return out;
                             })
      .def(
          "colliders",
          [](const World& w, const std::string& order) {
            return collidersDict(w.colliders(), parseQuatOrder(order));
          },
          "order"_a = "xyzw",
          "Every kinematic body's colliders: owner, shape, radius, half_height, axis, half_extents (m), "
          "poses.")
      .def("step", &World::step, "dt"_a = 1.0 / 60.0, py::kw_only(), "frames"_a = 1, "max_substeps"_a = 8,
           "fixed_step"_a = 1.0 / 240.0, py::call_guard<py::gil_scoped_release>(),
           "Steps `frames` frames of dt s (Bullet's stepSimulation(dt, max_substeps, fixed_step) each), the "
           "GIL "
           "released; then measures every cape.")
      .def("start_recording", &World::startRecording, "Records every frame from now on for write_gltf().")
      .def_property_readonly("recording", &World::recording)
      .def_property_readonly("recorded_frames", &World::recordedFrames)
      .def(
          "write_gltf",
          [](World& w, const py::object& path) {
            return w.writeRecording(py::str(path).cast<std::string>());
          },
          "path"_a, "Writes the recording as a glTF binary (.glb) and ends it; returns the frames written.");
}

}  // namespace
}  // namespace capepy

PYBIND11_MODULE(capecloth, m) {
  m.doc() = "CapeCloth: an XPBD cape on kinematic Bullet bodies and URDF characters (docs/PYTHON.md).";
  m.attr("__version__") = CAPECLOTH_VERSION;
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const capepy::FileNotFound& e) {
      PyErr_SetString(PyExc_FileNotFoundError, e.what());
    }
  });
  capepy::bindSettings(m);
  m.def(
      "fabric_names",
      [] {
        std::vector<std::string> names;
        for (const cape::FabricMaterial& f : cape::fabricPresets()) names.push_back(f.name);
        return names;
      },
      "The fabric presets (cape/core/FabricPresets.h), from the most drapey to the stiffest.");
  m.def(
      "fabric_material",
      [](const std::string& name) {
        const cape::FabricMaterial* f = cape::findFabric(name);
        if (!f)
          throw std::invalid_argument("no fabric \"" + name + "\"; the presets are " + cape::fabricNames());
        return py::dict("name"_a = f->name, "areal_density"_a = f->arealDensity,
                        "stretch_stiffness"_a = f->stretchStiffness, "shear_stiffness"_a = f->shearStiffness,
                        "bending_rigidity"_a = f->bendingRigidity, "bending_length"_a = f->bendingLength(),
                        "damping"_a = f->damping, "drag_coefficient"_a = f->dragCoefficient,
                        "lift_coefficient"_a = f->liftCoefficient, "source"_a = f->source);
      },
      "name"_a,
      "A preset's material per area: areal_density kg/m^2, stretch and shear stiffness N/m, bending_rigidity "
      "N m, bending_length m, damping 1/s, drag and lift coefficients, and its sources.");
  m.def(
      "simd_level", [] { return std::string(cape::simdLevelName(cape::simdLevel())); },
      "The instruction set of the solver's kernels now: \"portable\" or \"avx2\" (cape/core/Simd.h).");
  m.def(
      "simd_available", [] { return std::string(cape::simdLevelName(cape::simdAvailable())); },
      "The widest instruction set of the solver's kernels this processor runs: \"portable\" or \"avx2\".");
  m.def(
      "set_simd_level",
      [](const std::string& name) {
        if (name != "portable" && name != "avx2")
          throw std::invalid_argument("set_simd_level: \"portable\" or \"avx2\", not \"" + name + "\"");
        const cape::Status s =
            cape::setSimdLevel(name == "avx2" ? cape::SimdLevel::Avx2 : cape::SimdLevel::Portable);
        if (!s.ok()) throw std::invalid_argument(s.message());
      },
      "name"_a,
      "Chooses the instruction set of the solver's kernels for the whole process (\"portable\" forces the "
      "portable ones); every one gives the same bits. ValueError for a name that is neither, or \"avx2\" on "
      "a processor without it.");
  capepy::bindHandles(m);
  capepy::bindWorld(m);
}
