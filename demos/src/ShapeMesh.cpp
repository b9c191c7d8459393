#include "ShapeMesh.h"

#include <algorithm>
#include <cmath>

namespace cape::demo {

namespace {

/// A point of a lathe profile: radius from the axis and height along it, with the profile's outward normal
/// in the same (radial, axial) plane.
struct ProfilePoint {
  float r, y, nr, ny;
};

/// Revolves strips of profile points about the local Y axis, then turns Y into the collider's axis by a
/// cyclic permutation of the coordinates (which keeps the winding). Each strip runs so that its tangent,
/// turned by -90 degrees in the (r, y) plane, points outwards: bottom to top along a side.
void revolve(const std::vector<std::vector<ProfilePoint>>& strips, int segments, int axis, ShapeMesh& mesh) {
  const float kTwoPi = 6.28318530718f;
  auto put = [&](float x, float y, float z, std::vector<float>& out) {
    // Lathe frame (x, y, z) with the axis along y -> the collider's frame with the axis along `axis`.
    if (axis == 1) {
      out.insert(out.end(), {x, y, z});
    } else if (axis == 0) {
      out.insert(out.end(), {y, z, x});
    } else {
      out.insert(out.end(), {z, x, y});
    }
  };
  for (const std::vector<ProfilePoint>& strip : strips) {
    const auto base = static_cast<std::uint32_t>(mesh.vertexCount());
    const auto ring = static_cast<std::uint32_t>(segments + 1);
    for (const ProfilePoint& p : strip) {
      for (int j = 0; j <= segments; ++j) {
        const float a = kTwoPi * static_cast<float>(j) / static_cast<float>(segments);
        const float c = std::cos(a), s = -std::sin(a);
        put(p.r * c, p.y, p.r * s, mesh.positions);
        put(p.nr * c, p.ny, p.nr * s, mesh.normals);
      }
    }
    for (std::uint32_t i = 0; i + 1 < strip.size(); ++i) {
      for (std::uint32_t j = 0; j < static_cast<std::uint32_t>(segments); ++j) {
        const std::uint32_t a = base + i * ring + j, b = a + 1, d = a + ring, c = d + 1;
        mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
      }
    }
  }
}

/// Half a sphere's meridian (bottom or top hemisphere) shifted by `centre` along the axis.
void hemisphere(float radius, float centre, bool top, int rings, std::vector<ProfilePoint>& out) {
  const float kHalfPi = 1.57079632679f;
  for (int i = 0; i <= rings; ++i) {
    const float t = static_cast<float>(i) / static_cast<float>(rings);
    const float lat = top ? t * kHalfPi : -kHalfPi + t * kHalfPi;  // latitude from the equator
    out.push_back({radius * std::cos(lat), centre + radius * std::sin(lat), std::cos(lat), std::sin(lat)});
  }
}

void box(const Vec3& h, ShapeMesh& mesh) {
  // For each face: the outward axis and sign; the face's corners run counter-clockwise seen from outside.
  for (int axis = 0; axis < 3; ++axis) {
    for (float sign : {-1.0f, 1.0f}) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const auto base = static_cast<std::uint32_t>(mesh.vertexCount());
      const float corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
      for (const auto& c : corners) {
        float p[3], n[3] = {0, 0, 0};
        p[axis] = sign * h[axis];
        // (u, v, axis) is right-handed, so (u, v) counter-clockwise faces +axis; mirror u for -axis.
        p[u] = sign * c[0] * h[u];
        p[v] = c[1] * h[v];
        n[axis] = sign;
        mesh.positions.insert(mesh.positions.end(), p, p + 3);
        mesh.normals.insert(mesh.normals.end(), n, n + 3);
      }
      mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
  }
}

/// Each face of a hull: the vertices on its plane, in order around the face's centre, as a fan.
void hullFaces(const ConvexHull& hull, ShapeMesh& mesh) {
  for (const Eigen::Vector4f& q : hull.planes) {
    const Vec3 n = q.head<3>();
    std::vector<Vec3> face;
    for (const Vec3& v : hull.vertices)
      if (std::abs(n.dot(v) - q[3]) < 1e-4f) face.push_back(v);
    if (face.size() < 3) continue;
    Vec3 centre = Vec3::Zero();
    for (const Vec3& v : face) centre += v / static_cast<float>(face.size());
    const Vec3 t = (face[0] - centre).normalized(), b = n.cross(t);
    std::sort(face.begin(), face.end(), [&](const Vec3& u, const Vec3& v) {
      return std::atan2((u - centre).dot(b), (u - centre).dot(t)) <
             std::atan2((v - centre).dot(b), (v - centre).dot(t));
    });
    const auto first = static_cast<std::uint32_t>(mesh.positions.size() / 3);
    for (const Vec3& v : face) {
      mesh.positions.insert(mesh.positions.end(), {v.x(), v.y(), v.z()});
      mesh.normals.insert(mesh.normals.end(), {n.x(), n.y(), n.z()});
    }
    for (std::uint32_t k = 1; k + 1 < face.size(); ++k)
      mesh.indices.insert(mesh.indices.end(), {first, first + k, first + k + 1});
  }
}

}  // namespace

ShapeMesh colliderMesh(const Collider& c, int segments, float planeHalfSize) {
  segments = std::max(segments, 6);
  const int rings = std::max(segments / 4, 2);
  const int axis = std::clamp(c.axis, 0, 2);
  ShapeMesh mesh;
  switch (c.shape) {
    case ColliderShape::Sphere: {
      std::vector<ProfilePoint> meridian;
      hemisphere(c.radius, 0.0f, false, rings, meridian);
      meridian.pop_back();  // the equator is the top hemisphere's first point
      hemisphere(c.radius, 0.0f, true, rings, meridian);
      revolve({meridian}, segments, 1, mesh);
      break;
    }
    case ColliderShape::Capsule: {
      std::vector<ProfilePoint> meridian;
      hemisphere(c.radius, -c.halfHeight, false, rings, meridian);
      hemisphere(c.radius, c.halfHeight, true, rings, meridian);
      revolve({meridian}, segments, axis, mesh);
      break;
    }
    case ColliderShape::Cylinder: {
      const float r = c.radius, h = c.halfHeight;
      revolve({{{0, -h, 0, -1}, {r, -h, 0, -1}},  // bottom cap, centre to rim
               {{r, -h, 1, 0}, {r, h, 1, 0}},     // side
               {{r, h, 0, 1}, {0, h, 0, 1}}},     // top cap, rim to centre
              segments, axis, mesh);
      break;
    }
    case ColliderShape::Box:
      box(c.halfExtents, mesh);
      break;
    case ColliderShape::Plane: {
      // The plane n . p = constant: a square about constant * n, spanned by two directions in it.
      const Vec3 n = c.normal.normalized();
      const Vec3 t = (std::abs(n.x()) < 0.9f ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized();
      const Vec3 b = n.cross(t);
      const Vec3 o = c.constant * n;
      const float s = planeHalfSize;
      const Vec3 corners[4] = {o - s * t - s * b, o + s * t - s * b, o + s * t + s * b, o - s * t + s * b};
      for (const Vec3& p : corners) {
        mesh.positions.insert(mesh.positions.end(), {p.x(), p.y(), p.z()});
        mesh.normals.insert(mesh.normals.end(), {n.x(), n.y(), n.z()});
      }
      mesh.indices = {0, 1, 2, 0, 2, 3};
      break;
    }
    case ColliderShape::ConvexHull:
      hullFaces(*c.hull, mesh);
      break;
    case ColliderShape::TriangleMesh:
      for (std::size_t t = 0; t < c.triangles->size(); ++t) {
        const Vec3* v = &c.triangles->corners[3 * t];
        const Vec3 n = (v[1] - v[0]).cross(v[2] - v[0]).normalized();
        for (int k = 0; k < 3; ++k) {
          mesh.indices.push_back(static_cast<std::uint32_t>(mesh.positions.size() / 3));
          mesh.positions.insert(mesh.positions.end(), {v[k].x(), v[k].y(), v[k].z()});
          mesh.normals.insert(mesh.normals.end(), {n.x(), n.y(), n.z()});
        }
      }
      break;
  }
  return mesh;
}

}  // namespace cape::demo
