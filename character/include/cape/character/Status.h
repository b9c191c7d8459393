/// \file
/// The error value of the character module: bad data (a URDF file, an unknown joint name) never throws and
/// never crashes; it comes back as a Status with a code a program can test and a message meant for a person.
#pragma once

#include "cape/character/Export.h"

#include <string>
#include <utility>

/// The character (library cape::character): a URDF humanoid (urdfdom) as a Skeleton with forward
/// kinematics, its links as kinematic Bullet bodies, a procedural gait, motion clips, and where a cape hangs.
namespace cape::character {

/// What went wrong, for a program to test (Status::code()).
enum class ErrorCode : int {
  Ok = 0,         ///< Success.
  FileNotFound,   ///< The URDF path does not name a readable regular file.
  MalformedXml,   ///< The text is not well-formed XML (unclosed or mismatched tags, bad attributes, ...).
  InvalidModel,   ///< Well-formed XML but no valid URDF (no `<robot>`, a revolute joint without limits, ...).
  MissingLink,    ///< A joint names a parent or child link that is not defined.
  NotATree,       ///< No single root, or links unreachable from it: a cycle or a disconnected part.
  UnknownJoint,   ///< No joint of that name.
  UnknownLink,    ///< No link of that name.
  OutsideLimits,  ///< A joint value outside its limits: it was clamped (see the message) and applied.
  NotMovable,     ///< A fixed (or floating/planar) joint has no single position to set.
  InvalidArgument,  ///< A non-finite value, a non-positive scale or time step, ...
};

/// The code in words ("ok", "file not found", ...).
CAPE_CHARACTER_API const char* toString(ErrorCode code);

/// The result of an operation that can fail on bad data: ok, or an ErrorCode and a message meant for a
/// person.
class CAPE_CHARACTER_API Status {
 public:
  Status() = default;  ///< Success.
  /// Success.
  static Status success() { return Status(); }
  /// An error (an empty message becomes the code's toString()).
  static Status error(ErrorCode code, std::string message) { return Status(code, std::move(message)); }

  /// True for success (ErrorCode::Ok).
  bool ok() const { return code_ == ErrorCode::Ok; }
  /// The same as ok().
  explicit operator bool() const { return ok(); }
  /// What went wrong (ErrorCode::Ok on success).
  ErrorCode code() const { return code_; }
  /// What went wrong, for a person; empty on success.
  const std::string& message() const { return message_; }

 private:
  Status(ErrorCode code, std::string message) : code_(code), message_(std::move(message)) {
    if (code_ != ErrorCode::Ok && message_.empty()) message_ = toString(code_);
  }
  ErrorCode code_ = ErrorCode::Ok;
  std::string message_;
};

}  // namespace cape::character
