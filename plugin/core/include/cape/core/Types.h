/// \file
/// Basic types of the cape core: vectors, poses and the status value that reports bad input.
#pragma once

#include "cape/core/Export.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

/// CapeCloth. The solver core (cape/core: Eigen only, no Bullet, no I/O, no threads), the canonical scenes
/// and their metrics (cape/scenes) and the simple body as Bullet bodies (cape/scenes/BulletSimpleBody.h).
/// Lengths are metres, times seconds, masses kilograms, angles radians.
namespace cape {

/// A point or a vector of the core, float; a position in m, a velocity in m/s, ... (each use says which).
using Vec3 = Eigen::Vector3f;
/// A rotation of the core: a unit quaternion, float.
using Quat = Eigen::Quaternionf;

/// Particle data as structure of arrays: row i is particle i, column 0 holds every x, column 1 every y,
/// column 2 every z (Eigen's column-major storage keeps each coordinate contiguous, so per-particle loops
/// vectorise).
using Points = Eigen::Matrix<float, Eigen::Dynamic, 3>;

/// A rigid transform: x_world = rotation * x_local + position. Units: metres.
struct CAPE_CORE_API Pose {
  Vec3 position = Vec3::Zero();      ///< Where the local origin is, m.
  Quat rotation = Quat::Identity();  ///< Unit quaternion.

  /// The world point of a local point, m: rotation * local + position.
  Vec3 apply(const Vec3& local) const { return rotation * local + position; }
  /// The local point of a world point, m: the inverse of apply().
  Vec3 applyInverse(const Vec3& world) const { return rotation.conjugate() * (world - position); }
  /// Whether every coordinate of the position and the rotation is finite.
  bool isFinite() const;

  /// Pose a fraction s in [0, 1] of the way from a to b: positions interpolated linearly, rotations along
  /// the shortest arc (slerp). s = 0 gives a and s = 1 gives b exactly.
  static Pose interpolate(const Pose& a, const Pose& b, float s);
};

/// The result of an operation that can fail on bad data: ok, or an error message meant for a person.
class CAPE_CORE_API Status {
 public:
  /// Success: ok() and an empty message.
  static Status success() { return Status(); }
  /// An error with a message meant for a person (an empty message becomes "unknown error").
  static Status error(std::string message) { return Status(std::move(message)); }
  /// True for success.
  bool ok() const { return message_.empty(); }
  /// The same as ok().
  explicit operator bool() const { return ok(); }
  /// What went wrong; empty on success.
  const std::string& message() const { return message_; }

 private:
  Status() = default;
  explicit Status(std::string message) : message_(std::move(message)) {
    if (message_.empty()) message_ = "unknown error";
  }
  std::string message_;
};

/// Whether every coordinate of `v` is finite.
inline bool isFinite(const Vec3& v) {
  return v.allFinite();
}

}  // namespace cape
