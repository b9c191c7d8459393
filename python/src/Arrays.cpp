#include "Arrays.h"

#include <cmath>
#include <stdexcept>

namespace capepy {

namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

std::string shapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t k = 0; k < a.ndim(); ++k) s += (k ? ", " : "") + std::to_string(a.shape(k));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

DoubleArray numbers(const py::handle& object, const std::string& what) {
  if (object.is_none()) throw std::invalid_argument(what + ": None is not an array of numbers");
  DoubleArray a = DoubleArray::ensure(object);
  if (!a) throw std::invalid_argument(what + ": not an array of numbers");
  const double* d = a.data();
  for (py::ssize_t i = 0; i < a.size(); ++i)
    if (!std::isfinite(d[i])) throw std::invalid_argument(what + ": holds a value that is not finite");
  return a;
}

Eigen::Quaterniond quaternion(const double* q, QuatOrder order, const std::string& what) {
  Eigen::Quaterniond r = order == QuatOrder::Xyzw ? Eigen::Quaterniond(q[3], q[0], q[1], q[2])
                                                  : Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
  if (!(r.norm() > 1e-9)) throw std::invalid_argument(what + ": a zero quaternion is no rotation");
  return r.normalized();
}

Eigen::Isometry3d fromSeven(const double* v, QuatOrder order, const std::string& what) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  pose.linear() = quaternion(v + 3, order, what).toRotationMatrix();
  return pose;
}

Eigen::Isometry3d fromMatrix(const double* m, const std::string& what) {
  Eigen::Matrix4d M;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) M(r, c) = m[4 * r + c];
  if ((M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6)
    throw std::invalid_argument(what + ": a 4x4 pose's last row must be 0 0 0 1");
  const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3 || R.determinant() < 0.0)
    throw std::invalid_argument(what +
                                ": a 4x4 pose's upper-left 3x3 must be a rotation (orthonormal, det +1)");
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
  pose.translation() = M.topRightCorner<3, 1>();
  return pose;
}

}  // namespace

QuatOrder parseQuatOrder(const std::string& order) {
  if (order == "xyzw") return QuatOrder::Xyzw;
  if (order == "wxyz") return QuatOrder::Wxyz;
  throw std::invalid_argument("order must be \"xyzw\" or \"wxyz\", not \"" + order + "\"");
}

Eigen::Isometry3d poseFromObject(const py::handle& object, QuatOrder order, const std::string& what) {
  const DoubleArray a = numbers(object, what);
  if (a.ndim() == 1 && a.shape(0) == 7) return fromSeven(a.data(), order, what);
  if (a.ndim() == 2 && a.shape(0) == 4 && a.shape(1) == 4) return fromMatrix(a.data(), what);
  throw std::invalid_argument(
      what + ": a pose is 7 numbers (x, y, z, then the quaternion) or a 4x4 matrix, not " + shapeText(a));
}

std::vector<Eigen::Isometry3d> posesFromObject(const py::handle& object, QuatOrder order,
                                               const std::string& what) {
  const DoubleArray a = numbers(object, what);
  std::vector<Eigen::Isometry3d> poses;
  if (a.ndim() == 2 && a.shape(1) == 7) {
    for (py::ssize_t i = 0; i < a.shape(0); ++i)
      poses.push_back(fromSeven(a.data() + 7 * i, order, what + "[" + std::to_string(i) + "]"));
  } else if (a.ndim() == 3 && a.shape(1) == 4 && a.shape(2) == 4) {
    for (py::ssize_t i = 0; i < a.shape(0); ++i)
      poses.push_back(fromMatrix(a.data() + 16 * i, what + "[" + std::to_string(i) + "]"));
  } else {
    throw std::invalid_argument(what + ": poses are an (N, 7) or an (N, 4, 4) array, not " + shapeText(a));
  }
  return poses;
}

Eigen::Vector3d vec3FromObject(const py::handle& object, const std::string& what) {
  const DoubleArray a = numbers(object, what);
  if (a.ndim() != 1 || a.shape(0) != 3)
    throw std::invalid_argument(what + ": expected 3 numbers, not an array of shape " + shapeText(a));
  return Eigen::Vector3d(a.data()[0], a.data()[1], a.data()[2]);
}

Eigen::Quaterniond quatFromObject(const py::handle& object, QuatOrder order, const std::string& what) {
  const DoubleArray a = numbers(object, what);
  if (a.ndim() != 1 || a.shape(0) != 4)
    throw std::invalid_argument(what + ": a quaternion is 4 numbers, not an array of shape " + shapeText(a));
  return quaternion(a.data(), order, what);
}

Eigen::Isometry3d poseFromParts(const py::handle& position, const py::handle& quaternion, QuatOrder order,
                                const std::string& what) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = vec3FromObject(position, what + " position");
  if (!quaternion.is_none())
    pose.linear() = quatFromObject(quaternion, order, what + " quaternion").toRotationMatrix();
  return pose;
}

namespace {
void writeSeven(const Eigen::Isometry3d& pose, QuatOrder order, double* out) {
  const Eigen::Quaterniond q(pose.rotation());
  for (int k = 0; k < 3; ++k) out[k] = pose.translation()[k];
  const double xyzw[4] = {q.x(), q.y(), q.z(), q.w()};
  for (int k = 0; k < 4; ++k) out[3 + k] = order == QuatOrder::Xyzw ? xyzw[k] : xyzw[(k + 3) % 4];
}
}  // namespace

py::array_t<double> poseToArray(const Eigen::Isometry3d& pose, QuatOrder order) {
  py::array_t<double> out(7);
  writeSeven(pose, order, out.mutable_data());
  return out;
}

py::array_t<double> posesToArray(const std::vector<Eigen::Isometry3d>& poses, QuatOrder order) {
  py::array_t<double> out({static_cast<py::ssize_t>(poses.size()), py::ssize_t(7)});
  for (std::size_t i = 0; i < poses.size(); ++i) writeSeven(poses[i], order, out.mutable_data() + 7 * i);
  return out;
}

py::array_t<double> matrixToArray(const Eigen::Isometry3d& pose) {
  py::array_t<double> out({py::ssize_t(4), py::ssize_t(4)});
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out.mutable_at(r, c) = pose.matrix()(r, c);
  return out;
}

py::array_t<double> vec3ToArray(const Eigen::Vector3d& v) {
  py::array_t<double> out(3);
  for (int k = 0; k < 3; ++k) out.mutable_data()[k] = v[k];
  return out;
}

py::array_t<float> pointsToArray(const cape::Points& points) {
  py::array_t<float> out({static_cast<py::ssize_t>(points.rows()), py::ssize_t(3)});
  float* d = out.mutable_data();
  for (Eigen::Index i = 0; i < points.rows(); ++i)
    for (int k = 0; k < 3; ++k) d[3 * i + k] = points(i, k);
  return out;
}

}  // namespace capepy
