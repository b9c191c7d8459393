#include "SceneOptions.h"

#include "CliNumbers.h"

#include "cape/character/Character.h"
#include "cape/core/FabricPresets.h"
#include "cape/core/Version.h"

#include <LinearMath/btScalar.h>

#include <cmath>
#include <string>

namespace cape::demo {

void addVersionFlag(CLI::App& app, const std::string& tool) {
#ifdef BT_USE_DOUBLE_PRECISION
  const char* precision = "double";
#else
  const char* precision = "single";
#endif
  const int bullet = btGetVersion();
  app.set_version_flag("--version", tool + " " + cape::version() + " (CapeCloth " + cape::version() +
                                        ", Bullet " + std::to_string(bullet / 100) + "." +
                                        std::to_string(bullet % 100) + ", " + precision + " precision)");
}

void addSceneOptions(CLI::App& app, SceneCli& cli) {
  app.add_option("--scene", cli.scene, "hang | walk | sprint-turn | wind | crowd")
      ->check(CLI::IsMember({"hang", "walk", "sprint-turn", "wind", "crowd"}))
      ->capture_default_str();
  app.add_option("--size", cli.size,
                 "particles per side of the N x N cape; with --width or --height, particles across (the "
                 "rows keep the cells square)")
      ->transform(strictInteger(2, kMaxGridSide))
      ->capture_default_str();
  app.add_option("--width", cli.width,
                 "the cape's width, m (default: 0.6, or fitted to a URDF character's shoulders)")
      ->transform(strictReal(kMinCapeSide, kMaxCapeSide));
  app.add_option("--height", cli.height,
                 "the cape's length from its top row down, m (default: 1.0, or fitted to a URDF character's "
                 "pin height)")
      ->transform(strictReal(kMinCapeSide, kMaxCapeSide));
  app.add_option("--fabric", cli.fabric,
                 "a real fabric for the cape: " + fabricNames() +
                     " (its mass per area, stretch, shear and bending stiffness, damping and drag; "
                     "default: wool for --cape cape, none for --cape canonical)")
      ->check(CLI::Validator(
          [](std::string& name) {
            return findFabric(name) ? std::string()
                                    : "unknown fabric '" + name + "'; give one of " + fabricNames();
          },
          "NAME"));
  app.add_option("--cape", cli.cape,
                 "cape: gathered along a collar across the shoulders, of wool, folding as it hangs, with "
                 "self-collision | "
                 "canonical: docs/SCENES.md's comparison cape, pinned by its two top corners, with the "
                 "canonical stiffness (what cape_compare and the benchmarks use); --attachment and --fabric "
                 "change either")
      ->check(CLI::IsMember({"cape", "canonical"}))
      ->capture_default_str();
  app.add_option("--attachment", cli.attachment,
                 "corners (the two top corners) | collar (the whole top row, straight) | gathered (the whole "
                 "top row gathered onto a collar from shoulder to shoulder; default: the --cape's)")
      ->check(CLI::IsMember({"corners", "collar", "gathered"}));
  app.add_option("--seconds", cli.seconds,
                 "simulated length, s, up to 24 h, rounded to whole 1/60 s frames (default: the scene's "
                 "own length)")
      ->transform(strictReal(kMinSeconds, kMaxSeconds));
  app.add_option("--characters", cli.characters,
                 "characters in the crowd scene, on a square grid 2 m apart (rows of ceil(sqrt(K)))")
      ->transform(strictInteger(1, kMaxCharacters))
      ->capture_default_str();
  app.add_flag("--simple-body", cli.simpleBody,
               "use the simple body of docs/SCENES.md instead of a URDF character");
  app.add_option("--urdf", cli.urdf, "character URDF file (default: the shipped humanoid)")
      ->check(CLI::ExistingFile);
  app.add_option("--attach", cli.attach,
                 "comma-separated links the cape pins to (default: where the joint mapping finds the "
                 "shoulders)");
  app.add_option("--package-path", cli.packagePaths,
                 "folder where package://NAME/... mesh URIs are looked up (as DIR/NAME/...; repeatable; "
                 "then ROS_PACKAGE_PATH)");
  app.add_option("--up", cli.up, "the world's up axis: y (docs/SCENES.md) | z (ROS, PyBullet)")
      ->check(CLI::IsMember({"y", "z"}))
      ->capture_default_str();
  app.add_option("--root-height", cli.rootHeight,
                 "height of the URDF's root link above the ground, m (default: its lowest collision point "
                 "touches the ground)")
      ->transform(strictReal(-kMaxRootHeight, kMaxRootHeight));
  app.add_option("--model-up", cli.modelUp,
                 "the axis the URDF model stands along in its file: auto (z, with a warning when it looks "
                 "Y-up) | z (REP 103) | y (Y-up tools, e.g. PyBullet's DeepMimic humanoid)")
      ->check(CLI::IsMember({"auto", "z", "y"}))
      ->capture_default_str();
  app.add_option("--scale", cli.scale,
                 "uniform scale of the URDF model (e.g. 0.25 for a model in other units)")
      ->transform(strictReal(1e-3, 1e3))
      ->capture_default_str();
  app.add_option("--pose", cli.pose,
                 "starting joint positions, rad (or m): name=value,name=value; the gait moves from there");
  app.add_option("--origin", cli.origin,
                 "starts the scene at this world position, m: X,Y,Z (default 0,0,0; where the character "
                 "starts)")
      ->check(strictVector3(kMaxOrigin));
  app.add_option("--motion", cli.motion,
                 "a motion clip the character plays instead of the procedural gait: joint-trajectory CSV, "
                 "DeepMimic (.txt/.json) or BVH (character/README.md, \"Motion clips\")")
      ->check(CLI::ExistingFile);
  app.add_option("--motion-format", cli.motionFormat, "auto (from the file) | csv | deepmimic | bvh")
      ->check(CLI::IsMember({"auto", "csv", "deepmimic", "bvh"}))
      ->capture_default_str();
  app.add_option("--motion-scale", cli.motionScale,
                 "BVH: metres per BVH unit (0.01 for centimetres, 0.0254 for inches; default: guessed from "
                 "the skeleton's height)")
      ->transform(strictReal(1e-6, 1e3));
  app.add_option("--motion-speed", cli.motionSpeed, "playback speed (clip seconds per second)")
      ->transform(strictReal(1e-3, 1e3))
      ->capture_default_str();
  app.add_option("--motion-start", cli.motionStart, "clip time at the first frame, s")
      ->transform(strictReal(-kMaxSeconds, kMaxSeconds))
      ->capture_default_str();
  app.add_flag("--motion-in-place", cli.motionInPlace,
               "play the clip in place (its root's horizontal motion left out)");
  app.add_flag(
      "--motion-once", cli.motionOnce,
      "play the clip once and hold its last pose (default: loop it, the root carried over each loop; "
      "a DeepMimic file with \"Loop\": \"none\" is held too)");
  app.add_option("--motion-frame", cli.motionFrame,
                 "CSV: the frame of the root columns: urdf (z up, x forward) | world (the world of --up)")
      ->check(CLI::IsMember({"urdf", "world"}))
      ->capture_default_str();
  app.add_option("--motion-map", cli.motionMap,
                 "BVH: joints the naming schemes miss, as bvh_joint=role,... (roles: hips, spine, neck, "
                 "left_hip, left_knee, left_ankle, left_shoulder, left_elbow, right_...)");
}

bool toRunOptions(const SceneCli& cli, RunOptions& o, std::string& error) {
  o = RunOptions();
  o.packagePaths = cli.packagePaths;
  o.up = cli.up == "z" ? character::UpAxis::Z : character::UpAxis::Y;
  o.rootHeight = cli.rootHeight;
  o.modelUp = cli.modelUp == "y"   ? character::UrdfLoadOptions::Up::Y
              : cli.modelUp == "z" ? character::UrdfLoadOptions::Up::Z
                                   : character::UrdfLoadOptions::Up::Auto;
  o.scale = cli.scale;
  if (!cli.pose.empty()) {
    const character::Status s = character::parsePose(cli.pose, o.pose);
    if (!s.ok()) {
      error = "--pose: " + s.message();
      return false;
    }
  }
  if (o.rootHeight && !std::isfinite(*o.rootHeight)) {
    error = "--root-height must be a finite number of metres";
    return false;
  }
  if (!cli.origin.empty()) {
    const std::string why = parseVector3(cli.origin, kMaxOrigin, o.origin);
    if (!why.empty()) {
      error = "--origin: " + why;
      return false;
    }
  }
  if (!cli.motion.empty()) {
    if (cli.simpleBody) {
      error = "--motion needs a URDF character (the simple body has no joints to play)";
      return false;
    }
    o.motion = cli.motion;
    (void)character::parseMotionFormat(cli.motionFormat, o.motionLoad.format);
    o.motionLoad.csv.frame =
        cli.motionFrame == "world" ? character::MotionFrame::World : character::MotionFrame::Urdf;
    o.motionLoad.bvh.scale = cli.motionScale;
    for (std::size_t start = 0; start <= cli.motionMap.size();) {
      const std::size_t comma = cli.motionMap.find(',', start);
      const std::string item =
          cli.motionMap.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
      if (!item.empty()) {
        const std::size_t eq = item.find('=');
        if (eq == std::string::npos || eq == 0 || eq + 1 == item.size()) {
          error = "--motion-map: '" + item + "' is not bvh_joint=role";
          return false;
        }
        o.motionLoad.bvh.roles.emplace_back(item.substr(0, eq), item.substr(eq + 1));
      }
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    o.playback.speed = cli.motionSpeed;
    o.playback.startTime = cli.motionStart;
    o.playback.rootMotion = !cli.motionInPlace;
    o.playback.loop = !cli.motionOnce;
  }
  parseSceneKind(cli.scene, o.scene);
  // The cape's own attachment and fabric unless asked for others.
  const bool canonical = cli.cape == "canonical";
  o.capeStyle = canonical ? "canonical" : "cape";
  o.pinLayout = canonical ? PinLayout::Corners : PinLayout::Gathered;
  if (!cli.attachment.empty()) parsePinLayout(cli.attachment, o.pinLayout);
  o.size = cli.size;
  if (cli.width) o.capeWidth = static_cast<float>(*cli.width);
  if (cli.height) o.capeHeight = static_cast<float>(*cli.height);
  if (!cli.fabric.empty())
    o.fabric = findFabric(cli.fabric);  // checked by the option
  else if (!canonical)
    o.fabric = findFabric("wool");
  o.seconds = cli.seconds;
  o.characters = o.scene == SceneKind::Crowd ? cli.characters : 1;
  o.simpleBody = cli.simpleBody;
  o.urdf = cli.urdf;
  for (std::size_t start = 0; start <= cli.attach.size();) {
    const std::size_t comma = cli.attach.find(',', start);
    const std::string link =
        cli.attach.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (!link.empty()) o.attachLinks.push_back(link);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return true;
}

}  // namespace cape::demo
