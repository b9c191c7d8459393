#include "SceneOptions.h"

namespace cape::demo {

void addSceneOptions(CLI::App& app, SceneCli& cli) {
  app.add_option("--scene", cli.scene, "hang | walk | sprint-turn | wind | crowd")
      ->check(CLI::IsMember({"hang", "walk", "sprint-turn", "wind", "crowd"}))
      ->capture_default_str();
  app.add_option("--size", cli.size, "particles per side of the N x N cape")
      ->check(CLI::Range(2, 256))
      ->capture_default_str();
  app.add_option("--attachment", cli.attachment, "corners (the two top corners) | collar (the whole top row)")
      ->check(CLI::IsMember({"corners", "collar"}))
      ->capture_default_str();
  app.add_option("--seconds", cli.seconds, "simulated length, s (default: the scene's own length)")
      ->check(CLI::PositiveNumber);
  app.add_option("--characters", cli.characters, "characters in the crowd scene")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  app.add_flag("--simple-body", cli.simpleBody,
               "use the simple body of docs/SCENES.md instead of a URDF character");
  app.add_option("--urdf", cli.urdf, "character URDF file (default: the shipped humanoid)")
      ->check(CLI::ExistingFile);
  app.add_option("--attach", cli.attach,
                 "comma-separated links the cape pins to (default: links named *shoulder*)");
}

RunOptions toRunOptions(const SceneCli& cli) {
  RunOptions o;
  parseSceneKind(cli.scene, o.scene);
  parsePinLayout(cli.attachment, o.pinLayout);
  o.size = cli.size;
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
  return o;
}

}  // namespace cape::demo
