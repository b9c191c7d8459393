// A run as a glTF 2.0 binary (.glb) that Blender and web viewers open: every body collider as a node with a
// mesh of its shape, animated by translation and rotation (one LINEAR key per frame); the ground as a
// checkered plane; each cape as a mesh animated by morph targets, one target per frame after the first,
// whose weights step from one target to the next (STEP interpolation), so positions and normals are exactly
// the simulated ones at every frame. glTF has no other standard way to animate free vertices, and Blender
// imports morph targets as shape keys with animated values.
#pragma once

#include "cape/core/Cape.h"
#include "cape/core/CapeMesh.h"

#include <filesystem>
#include <string>
#include <vector>

namespace cape::demo {

class GltfRecorder {
 public:
  /// `characters` capes and collider sets are recorded per frame; frames are `frameTime` seconds apart and
  /// the first recorded frame is at time 0.
  explicit GltfRecorder(int characters, double frameTime = 1.0 / 60.0);

  /// Records character k at the current frame: its cape and its body colliders (ground excluded). A frame
  /// is complete once every character has been recorded; characters come in order 0, 1, ... The colliders
  /// must be the same shapes in the same order in every frame (only their poses change).
  void record(int character, const Cape& cape, const std::vector<Collider>& colliders);
  /// The same from a cape's fabric and particle positions (m; e.g. turned into glTF's Y-up from a Z-up
  /// world).
  void record(int character, const Fabric& fabric, const Points& positions,
              const std::vector<Collider>& colliders);

  /// Frames recorded so far (complete or not).
  int frames() const { return frames_; }

  /// Writes the .glb. False, with a one-line reason, if nothing was recorded or the file cannot be written.
  /// Frees the recording as it goes: call once.
  bool write(const std::filesystem::path& file, std::string& error);

 private:
  struct ColliderTrack {
    Collider shape;                   ///< Shape, size and name (poses ignored).
    std::vector<float> translations;  ///< x, y, z per frame.
    std::vector<float> rotations;     ///< x, y, z, w per frame.
  };
  struct CharacterTrack {
    std::vector<ColliderTrack> colliders;
    CapeMesh mesh;  ///< Scratch for positions and normals.
    std::size_t vertices = 0;
    std::vector<float> basePositions;  ///< First frame, x, y, z per vertex.
    std::vector<float> baseNormals;
    std::vector<std::uint32_t> indices;
    std::vector<float> uvs;     ///< u, v per vertex.
    std::vector<float> morphs;  ///< Per later frame: position deltas then normal deltas (3n each).
    std::vector<float> morphMin, morphMax;  ///< Per later frame: bounds of the position deltas (x, y, z).
  };
  int characters_;
  double frameTime_;
  int frames_ = 0;
  std::vector<CharacterTrack> tracks_;
  Vec3 sceneMin_ = Vec3::Constant(1e30f), sceneMax_ = Vec3::Constant(-1e30f);  ///< Collider centres seen.
};

}  // namespace cape::demo
