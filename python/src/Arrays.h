// NumPy arrays in and out of the capecloth module: poses (7 numbers or a 4x4 matrix), vectors, point sets,
// each checked (shape, finite, a rotation that is one) with a message naming what was wrong.
#pragma once

#include "cape/core/Types.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace capepy {

namespace py = pybind11;

/// The order of a quaternion's four numbers in a pose: x, y, z, w (PyBullet, ROS, Eigen's coeffs) or
/// w, x, y, z (MuJoCo).
enum class QuatOrder { Xyzw, Wxyz };
/// "xyzw" or "wxyz"; ValueError otherwise.
QuatOrder parseQuatOrder(const std::string& order);

/// A pose from a (7,) array (x, y, z in m, then the quaternion in `order`) or a (4, 4) homogeneous matrix
/// (rotation orthonormal within 1e-3, last row 0 0 0 1). Quaternions are normalised (zero: ValueError).
Eigen::Isometry3d poseFromObject(const py::handle& object, QuatOrder order, const std::string& what);
/// N poses from an (N, 7) or (N, 4, 4) array.
std::vector<Eigen::Isometry3d> posesFromObject(const py::handle& object, QuatOrder order,
                                               const std::string& what);
/// A pose from a position (3,) and an optional quaternion (4,) in `order`.
Eigen::Isometry3d poseFromParts(const py::handle& position, const py::handle& quaternion, QuatOrder order,
                                const std::string& what);
Eigen::Vector3d vec3FromObject(const py::handle& object, const std::string& what);
Eigen::Quaterniond quatFromObject(const py::handle& object, QuatOrder order, const std::string& what);

py::array_t<double> poseToArray(const Eigen::Isometry3d& pose, QuatOrder order);
py::array_t<double> posesToArray(const std::vector<Eigen::Isometry3d>& poses, QuatOrder order);
py::array_t<double> matrixToArray(const Eigen::Isometry3d& pose);
py::array_t<double> vec3ToArray(const Eigen::Vector3d& v);
/// (N, 3) float32, row i = point i.
py::array_t<float> pointsToArray(const cape::Points& points);

}  // namespace capepy
