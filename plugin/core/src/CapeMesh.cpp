#include "cape/core/CapeMesh.h"

namespace cape {

void computeVertexNormals(const Points& positions, const std::vector<std::uint32_t>& triangles,
                          Eigen::Ref<Points, 0, Eigen::OuterStride<>> normals) {
  normals.setZero();
  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3) {
    const std::uint32_t a = triangles[t], b = triangles[t + 1], c = triangles[t + 2];
    const Vec3 pa = positions.row(a), pb = positions.row(b), pc = positions.row(c);
    const Vec3 n = (pb - pa).cross(pc - pa);  // |n| = 2 * area: area weighting for free
    normals.row(a) += n.transpose();
    normals.row(b) += n.transpose();
    normals.row(c) += n.transpose();
  }
  for (Eigen::Index i = 0; i < normals.rows(); ++i) {
    const float len = normals.row(i).norm();
    if (len > 0.0f)
      normals.row(i) /= len;
    else
      normals.row(i) << 0.0f, 0.0f, 1.0f;  // a degenerate neighbourhood: any unit normal
  }
}

void CapeMesh::allocate(const Fabric& fabric, bool twoSided) {
  twoSided_ = twoSided;
  const Eigen::Index n = static_cast<Eigen::Index>(fabric.particleCount());
  const Eigen::Index total = twoSided ? 2 * n : n;
  positions.resize(total, 3);
  normals.resize(total, 3);
  uvs.assign(fabric.uvs().begin(), fabric.uvs().end());
  indices = fabric.triangles();
  if (twoSided) {
    uvs.insert(uvs.end(), fabric.uvs().begin(), fabric.uvs().end());
    const std::vector<std::uint32_t>& tri = fabric.triangles();
    const std::uint32_t offset = static_cast<std::uint32_t>(n);
    for (std::size_t t = 0; t + 2 < tri.size(); t += 3) {
      // Back face: same corners, reversed winding, on the back copies of the vertices.
      indices.push_back(tri[t] + offset);
      indices.push_back(tri[t + 2] + offset);
      indices.push_back(tri[t + 1] + offset);
    }
  }
}

void CapeMesh::update(const Fabric& fabric, const Points& particlePositions) {
  const Eigen::Index n = particlePositions.rows();
  positions.topRows(n) = particlePositions;
  computeVertexNormals(particlePositions, fabric.triangles(), normals.topRows(n));
  if (!twoSided_) return;
  positions.bottomRows(n) = particlePositions;
  normals.bottomRows(n) = -normals.topRows(n);
}

}  // namespace cape
