// The collision stage of a substep: every free particle against every collider's sweep over the substep.
#include "BodyCollision.h"

#include "ShapeDistance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace cape::detail {

namespace {

// Radius of a sphere about the collider's origin that holds the whole shape (infinite for planes).
float boundingRadius(const Collider& c) {
  switch (c.shape) {
    case ColliderShape::Sphere:
      return c.radius;
    case ColliderShape::Capsule:
      return c.radius + c.halfHeight;
    case ColliderShape::Cylinder:
      return std::hypot(c.radius, c.halfHeight);
    case ColliderShape::Box:
      return c.halfExtents.norm();
    case ColliderShape::ConvexHull:
      return c.hull->radius;
    case ColliderShape::Plane:
    case ColliderShape::TriangleMesh:
      return std::numeric_limits<float>::infinity();
  }
  return std::numeric_limits<float>::infinity();
}

/// What one collider's pass needs besides the particles.
struct PassArrays {
  std::vector<Cape::Contact>* contacts;
  std::vector<Eigen::Vector4f>* planes;  ///< per contact: a triangle mesh's contact plane (n, offset)
  std::uint32_t collider;
  float maxTravel;                         ///< the largest distance any particle moved in this substep, m
  Eigen::ArrayXf* distance2;               ///< scratch, one per particle
  std::vector<std::uint32_t>* candidates;  ///< scratch
  /// Per block of kCullBlock consecutive particles: the centre of its box and the radius about it that
  /// holds the block (x, y, z, radius), at the particles' positions before this pass.
  const std::vector<Eigen::Vector4f>* blocks;
};

/// One collider's motion over the substep: its poses at s0 (A) and s1 (B), and bounds of how far a point at
/// rest in the world moves relative to it.
struct Sweep {
  Pose A, B;
  Eigen::Matrix3f invRA, invRB, RB;
  float bound;   ///< radius about the collider's origin holding the shape, m (inf for planes)
  float shift;   ///< |B.position - A.position|, m
  float turn;    ///< rotation angle from A to B, rad
  float margin;  ///< the cape's thickness plus the collider's, m
  Sweep(const Collider& c, float s0, float s1, float margin_)
      : A(Pose::interpolate(c.previous, c.current, s0)),
        B(Pose::interpolate(c.previous, c.current, s1)),
        invRA(A.rotation.conjugate().toRotationMatrix()),
        invRB(B.rotation.conjugate().toRotationMatrix()),
        RB(B.rotation.toRotationMatrix()),
        bound(boundingRadius(c)),
        shift((B.position - A.position).norm()),
        turn(A.rotation.angularDistance(B.rotation)),
        margin(margin_) {}
};

/// Moves particle i from x to its corrected position xn (world). The seed's explicit mode moves positions
/// only, so there the velocity follows the correction.
inline void placeParticle(const CollisionArrays& p, Eigen::Index i, const Vec3& x, const Vec3& xn, float invH,
                          bool explicitMode) {
  if (explicitMode) {
    p.vx[i] += (xn.x() - x.x()) * invH;
    p.vy[i] += (xn.y() - x.y()) * invH;
    p.vz[i] += (xn.z() - x.z()) * invH;
  }
  p.px[i] = xn.x();
  p.py[i] = xn.y();
  p.pz[i] = xn.z();
}

/// The particles of a cull block (BodyCollision::collide's boxes): consecutive indices, so a grid's rows.
constexpr Eigen::Index kCullBlock = 16;

/// One pass over the particles before the colliders' passes: returns the largest squared distance a particle
/// moved in this substep, and sets each block's sphere (kCullBlock consecutive particles: the centre of their
/// box, and half its diagonal, a little more for rounding). Minima and maxima pass over NaN (a NaN particle
/// fails every test of the broad phase anyway); an infinite coordinate makes its block's radius infinite, and
/// such a block is never passed over.
float travelAndBlocks(const CollisionArrays& p, std::vector<Eigen::Vector4f>& blocks) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  blocks.resize(static_cast<std::size_t>((p.n + kCullBlock - 1) / kCullBlock));
  float maxTravel2 = 0.0f;
  for (Eigen::Index first = 0, b = 0; first < p.n; first += kCullBlock, ++b) {
    const Eigen::Index last = std::min(p.n, first + kCullBlock);
    float lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
    Eigen::Index i = first;
#if defined(__SSE2__)
    // max(new, old) and min(new, old) keep the old value when the new one is NaN, as the scalar tail does.
    __m128 travel = _mm_setzero_ps(), lx = _mm_set1_ps(kInf), ly = lx, lz = lx, hx = _mm_set1_ps(-kInf),
           hy = hx, hz = hx;
    for (; i + 4 <= last; i += 4) {
      const __m128 x = _mm_loadu_ps(p.px + i), y = _mm_loadu_ps(p.py + i), z = _mm_loadu_ps(p.pz + i);
      const __m128 dx = _mm_sub_ps(x, _mm_loadu_ps(p.sx + i)), dy = _mm_sub_ps(y, _mm_loadu_ps(p.sy + i)),
                   dz = _mm_sub_ps(z, _mm_loadu_ps(p.sz + i));
      travel = _mm_max_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz)),
                          travel);
      lx = _mm_min_ps(x, lx);
      ly = _mm_min_ps(y, ly);
      lz = _mm_min_ps(z, lz);
      hx = _mm_max_ps(x, hx);
      hy = _mm_max_ps(y, hy);
      hz = _mm_max_ps(z, hz);
    }
    alignas(16) float lanes[7][4];
    _mm_store_ps(lanes[0], travel);
    _mm_store_ps(lanes[1], lx);
    _mm_store_ps(lanes[2], ly);
    _mm_store_ps(lanes[3], lz);
    _mm_store_ps(lanes[4], hx);
    _mm_store_ps(lanes[5], hy);
    _mm_store_ps(lanes[6], hz);
    for (int k = 0; k < 4; ++k) {
      maxTravel2 = std::max(maxTravel2, lanes[0][k]);
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], lanes[1 + a][k]);
        hi[a] = std::max(hi[a], lanes[4 + a][k]);
      }
    }
#endif
    for (; i < last; ++i) {
      const float x[3] = {p.px[i], p.py[i], p.pz[i]};
      const float dx = x[0] - p.sx[i], dy = x[1] - p.sy[i], dz = x[2] - p.sz[i];
      maxTravel2 = std::max(maxTravel2, dx * dx + dy * dy + dz * dz);
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], x[a]);
        hi[a] = std::max(hi[a], x[a]);
      }
    }
    const float ex = hi[0] - lo[0], ey = hi[1] - lo[1], ez = hi[2] - lo[2];
    const float radius = 0.5f * std::sqrt(ex * ex + ey * ey + ez * ez) * (1.0f + 1e-6f);
    blocks[static_cast<std::size_t>(b)] = {0.5f * (lo[0] + hi[0]), 0.5f * (lo[1] + hi[1]),
                                           0.5f * (lo[2] + hi[2]), std::isnan(radius) ? kInf : radius};
  }
  return maxTravel2;
}

/// Broad phase, vectorised over all particles: the free particles that could reach the collider (a lower
/// bound of the distance to its shape, or to the plane) within this substep go on to the exact test.
template <ColliderShape S>
void gatherCandidates(const Collider& c, const CollisionArrays& p, const PassArrays& q, const Sweep& w) {
  std::vector<std::uint32_t>& candidates = *q.candidates;
  candidates.clear();
  if constexpr (S == ColliderShape::Plane) {
    const Vec3 nw = w.B.rotation * c.normal;
    const float cw = c.constant + nw.dot(w.B.position);
    Eigen::Map<const Eigen::ArrayXf> X(p.px, p.n), Y(p.py, p.n), Z(p.pz, p.n);
    Eigen::ArrayXf& d2 = *q.distance2;
    d2 = X * nw.x() + Y * nw.y() + Z * nw.z() - cw;  // signed distance to the plane at s1
    const float reach =
        w.turn > 0.0f ? std::numeric_limits<float>::infinity() : w.margin + w.shift + q.maxTravel;
    for (Eigen::Index i = 0; i < p.n; ++i)
      if (d2[i] <= reach && p.w[i] != 0.0f) candidates.push_back(static_cast<std::uint32_t>(i));
    return;
  } else {
    if (!(w.turn < 0.5f)) {
      // Turning too fast to bound: every particle at a finite distance goes on to the exact test.
      const float ox = w.B.position.x(), oy = w.B.position.y(), oz = w.B.position.z();
      for (Eigen::Index i = 0; i < p.n; ++i) {
        const float d2 = (p.px[i] - ox) * (p.px[i] - ox) + (p.py[i] - oy) * (p.py[i] - oy) +
                         (p.pz[i] - oz) * (p.pz[i] - oz);
        if (d2 <= std::numeric_limits<float>::infinity() && p.w[i] != 0.0f)
          candidates.push_back(static_cast<std::uint32_t>(i));
      }
      return;
    }
    // In the collider's frame at s1, a lower bound of each particle's signed distance to the shape (exact
    // for spheres, capsules and inside boxes and cylinders; the largest axis gap outside them), less the
    // most it can move relative to the collider in this substep: the narrow phase's test with every
    // particle's travel replaced by the largest, so it keeps every particle that test could keep. A plain
    // loop over flat arrays, vectorised by the compiler. The slack (0.1 mm) covers the rounding of a
    // different evaluation order.
    constexpr float kSlack = 1e-4f;
    Eigen::Matrix3f M = w.invRB;
    if constexpr (S == ColliderShape::Capsule || S == ColliderShape::Cylinder) {
      if (c.axis != 0) M.row(0).swap(M.row(c.axis));  // row 0 along the axis, rows 1 and 2 across it
    }
    const float m00 = M(0, 0), m01 = M(0, 1), m02 = M(0, 2), m10 = M(1, 0), m11 = M(1, 1), m12 = M(1, 2);
    const float m20 = M(2, 0), m21 = M(2, 1), m22 = M(2, 2);
    const float ox = w.B.position.x(), oy = w.B.position.y(), oz = w.B.position.z();
    const float hx = c.halfExtents.x(), hy = c.halfExtents.y(), hz = c.halfExtents.z();
    const float radius = S == ColliderShape::ConvexHull ? c.hull->radius : c.radius;
    const float halfHeight = c.halfHeight, turn = w.turn;
    const float fixedReach = w.margin + w.shift + q.maxTravel * (1.0f + turn) + kSlack;
    // The lower bound at (rx, ry, rz) from the collider's origin, |r| = relNorm. 1-Lipschitz in r for every
    // shape (a distance, or the largest of distances to planes), which the block test below relies on.
    const auto lowerBound = [=](float rx, float ry, float rz, float relNorm) {
      if constexpr (S == ColliderShape::Sphere || S == ColliderShape::ConvexHull) {
        (void)rx, (void)ry, (void)rz;
        return relNorm - radius;  // a hull's bounding sphere
      } else {
        (void)relNorm;
        const float b0 = m00 * rx + m01 * ry + m02 * rz;
        const float b1 = m10 * rx + m11 * ry + m12 * rz;
        const float b2 = m20 * rx + m21 * ry + m22 * rz;
        if constexpr (S == ColliderShape::Box) {
          return std::max(std::max(std::abs(b0) - hx, std::abs(b1) - hy), std::abs(b2) - hz);
        } else if constexpr (S == ColliderShape::Capsule) {
          const float beyond = std::abs(b0) - halfHeight;  // past the end of the segment, along the axis
          const float along =
              0.5f * (beyond + std::abs(beyond));  // max(beyond, 0), exactly, without a branch
          return std::sqrt(along * along + b1 * b1 + b2 * b2) - radius;
        } else {
          return std::max(std::sqrt(b1 * b1 + b2 * b2) - radius, std::abs(b0) - halfHeight);
        }
      }
    };
    const float* __restrict px = p.px;
    const float* __restrict py = p.py;
    const float* __restrict pz = p.pz;
    float* __restrict gap = q.distance2->data();
    const std::vector<Eigen::Vector4f>& blocks = *q.blocks;
    const float originSize = std::abs(ox) + std::abs(oy) + std::abs(oz);
    for (Eigen::Index b = 0, first = 0; first < p.n; ++b, first += kCullBlock) {
      const Eigen::Index last = std::min(p.n, first + kCullBlock);
      // The whole block first: every particle of it is within `rho` of the centre, so (the bound being
      // 1-Lipschitz) its bound is at least the centre's less rho, and its distance from the origin at most
      // the centre's plus rho. A block that clears the reach by more than the rounding of either evaluation
      // is passed over: the particles' own test would keep none of it. A block that is not finite is not.
      const Eigen::Vector4f& block = blocks[static_cast<std::size_t>(b)];
      const float cx = block.x() - ox, cy = block.y() - oy, cz = block.z() - oz, rho = block.w();
      const float centreNorm = std::sqrt(cx * cx + cy * cy + cz * cz);
      const float tolerance = 1e-4f + 1e-5f * (originSize + std::abs(block.x()) + std::abs(block.y()) +
                                               std::abs(block.z()) + centreNorm + rho + fixedReach);
      const float blockGap =
          lowerBound(cx, cy, cz, centreNorm) - rho - (fixedReach + turn * (centreNorm + rho));
      if (blockGap > tolerance) continue;
      for (Eigen::Index i = first; i < last; ++i) {
        const float rx = px[i] - ox, ry = py[i] - oy, rz = pz[i] - oz;
        const float relNorm = std::sqrt(rx * rx + ry * ry + rz * rz);
        gap[i] = lowerBound(rx, ry, rz, relNorm) - (fixedReach + turn * relNorm);
      }
      for (Eigen::Index i = first; i < last; ++i)
        if (gap[i] <= 0.0f && p.w[i] != 0.0f) candidates.push_back(static_cast<std::uint32_t>(i));
    }
  }
}

/// The narrow phase of one particle, in the collider's frame: it moves from a (its start, in the frame at
/// s0) to b (its prediction, in the frame at s1). Returns whether it touched; then `bn` is where it ends,
/// outside the skin, and `normal` the contact normal.
template <ColliderShape S>
bool resolveSweep(const Collider& c, float margin, const Vec3& a, const Vec3& b, const SurfaceDistance& sb,
                  Vec3& bn, Vec3& normal) {
  const SurfaceDistance sa = shapeDistance<S>(c, a);
  bn = b;
  normal = sb.normal;
  bool touched = false;
  const Vec3 ab = b - a;
  const float len = ab.norm();
  // Started clear and either ended inside the skin or moved far enough to tunnel through a thin part
  // (along the segment d >= (d(a) + d(b) - len) / 2): conservative advancement from a finds the first
  // contact, and the particle leaves through the face it came in by — not through whichever face is
  // nearest to where it ended, which near a box's edge would tear neighbouring particles apart.
  if (sa.distance >= margin && sa.distance + sb.distance - len < 2.0f * margin) {
    float t = 0.0f;
    SurfaceDistance s = sa;
    bool hit = false;
    for (int iter = 0; iter < 32; ++iter) {
      const float gap = s.distance - margin;
      if (gap < 1e-5f) {
        hit = true;
        break;
      }
      // The rest of the segment clears the margin: no contact.
      if (s.distance + sb.distance - (1.0f - t) * len >= 2.0f * margin) break;
      t += gap / len;
      if (t >= 1.0f) break;
      s = shapeDistance<S>(c, a + t * ab);
    }
    if (hit) {
      // Stop at the contact: keep only the motion along the tangent plane of the contact point.
      const Vec3 pc = a + t * ab;
      normal = s.normal;
      bn = b + std::max(0.0f, (pc - b).dot(normal)) * normal;
      touched = true;
    }
  }
  // Whatever the sweep found, end outside the skin: push out to the nearest surface point plus the margin
  // (the seed's push-out; it also covers particles that started inside, e.g. after a pose jump).
  const SurfaceDistance sn = touched ? shapeDistance<S>(c, bn) : sb;
  if (sn.distance < margin) {
    bn += (margin - sn.distance) * sn.normal;
    if (!touched) normal = sn.normal;
    touched = true;
  }
  return touched;
}

/// Coulomb friction on the tangential displacement relative to the collider (Macklin et al. 2014, "Unified
/// Particle Physics for Real-Time Applications"): static while within mu times the normal correction,
/// otherwise shortened by that much.
inline void applyFriction(float mu, const Vec3& a, const Vec3& b, const Vec3& normal, Vec3& bn) {
  const float normalCorrection = (bn - b).norm();
  if (mu > 0.0f && normalCorrection > 0.0f) {
    const Vec3 moved = bn - a;
    const Vec3 tangential = moved - moved.dot(normal) * normal;
    const float tl = tangential.norm();
    const float limit = mu * normalCorrection;
    bn -= tl <= limit ? tangential : Vec3(tangential * (limit / tl));
  }
}

/// One collider against every free particle. In the collider's own frame the collider is still and the
/// particle moves from its start to its prediction: relative motion, so a fast collider and a fast particle
/// are the same problem.
template <ColliderShape S>
__attribute__((flatten)) void collideWith(const Collider& c, const CollisionArrays& p, const PassArrays& q,
                                          float s0, float s1, float margin, float mu, float invH,
                                          bool explicitMode) {
  const Sweep w(c, s0, s1, margin);
  gatherCandidates<S>(c, p, q, w);
  for (const std::uint32_t i : *q.candidates) {
    const Vec3 x(p.px[i], p.py[i], p.pz[i]);
    const Vec3 x0(p.sx[i], p.sy[i], p.sz[i]);
    const Vec3 rel = x - w.B.position;
    const float travel = (x - x0).norm();
    float sweep = travel + w.shift;
    if constexpr (S != ColliderShape::Plane) {
      // How far the particle moves relative to the collider's frame, at most: its own travel plus the
      // collider's translation and its rotation at this distance from the origin.
      const float relNorm = rel.norm();
      sweep += w.turn * (relNorm + travel);
      if (relNorm > w.bound + margin + sweep) continue;  // cannot touch in this substep
    }
    const Vec3 b = w.invRB * rel;
    // The signed distance is 1-Lipschitz: if the end is farther than the whole relative motion, the segment
    // never came within the margin.
    if (shapeDistanceOnly<S>(c, b) >= margin + sweep) continue;
    const SurfaceDistance sb = shapeDistance<S>(c, b);
    const Vec3 a = w.invRA * (x0 - w.A.position);
    Vec3 bn, normal;
    if (!resolveSweep<S>(c, margin, a, b, sb, bn, normal)) continue;
    applyFriction(mu, a, b, normal, bn);
    placeParticle(p, i, x, w.RB * bn + w.B.position, invH, explicitMode);
    q.contacts->push_back({i, q.collider});
    q.planes->push_back(Eigen::Vector4f::Zero());
  }
}

/// One particle of a triangle mesh's pass, in the mesh's frame: at b (its prediction), against its candidate
/// triangles, each on the side of its plane the particle was on at the start of the step. Returns whether
/// it touched; then bn is where it ends and `plane` the last contact plane (n, offset).
inline bool resolveMesh(const TriangleSoup& soup, const MeshCandidate* begin, const MeshCandidate* end,
                        float margin, const Vec3& b, Vec3& bn, Vec3& normal, Eigen::Vector4f& plane) {
  // Over a face by barycentric weights of the projection with this tolerance: a point over the edge two
  // triangles share is over both, never beside both.
  constexpr float kOverFace = 1e-4f;
  bn = b;
  bool touched = false;
  for (const MeshCandidate* k = begin; k != end; ++k) {
    const Vec3 &v0 = soup.corners[3 * k->triangle], &v1 = soup.corners[3 * k->triangle + 1],
               &v2 = soup.corners[3 * k->triangle + 2];
    const Vec3 e1 = v1 - v0, e2 = v2 - v0;
    Vec3 n = e1.cross(e2);
    const float len = n.norm();
    if (!(len > 1e-12f)) continue;
    n *= k->side / len;  // towards the side the particle started the step on
    const float d = n.dot(bn - v0);
    if (d >= margin) continue;  // on its side and clear of the plane: clear of the triangle
    // The projection's barycentric weights (wb along e1, wc along e2).
    const Vec3 r = bn - v0;
    const float d00 = e1.dot(e1), d01 = e1.dot(e2), d11 = e2.dot(e2), d20 = r.dot(e1), d21 = r.dot(e2);
    const float den = d00 * d11 - d01 * d01;
    const float wb = (d11 * d20 - d01 * d21) / den, wc = (d00 * d21 - d01 * d20) / den;
    if (wb >= -kOverFace && wc >= -kOverFace && wb + wc <= 1.0f + kOverFace) {
      // Over the face: back to its side (a particle that crossed the face in this step comes back), at least
      // the margin away.
      bn += (margin - d) * n;
      normal = n;
      plane = Eigen::Vector4f(n.x(), n.y(), n.z(), n.dot(v0));
    } else {
      // Beside an edge or a corner: out along the plain distance, unless behind the plane there (past the
      // mesh's border, or over a neighbour, whose face brings it back).
      const TriangleNearest w = nearestOnTriangle(bn, v0, v1, v2);
      const Vec3 q = w.wa * v0 + w.wb * v1 + w.wc * v2;
      const Vec3 e = bn - q;
      const float dist = e.norm();
      if (d < 0.0f || !(dist < margin && dist > 1e-9f)) continue;
      normal = e / dist;
      bn = q + margin * normal;
      plane = Eigen::Vector4f(normal.x(), normal.y(), normal.z(), normal.dot(q));
    }
    touched = true;
  }
  return touched;
}

/// Pushes the contact's particle back out of its collider (pose at the substep's end) if the constraint
/// solve moved it into the skin.
template <ColliderShape S>
void reprojectOne(const Collider& c, const Pose& B, float margin, float* px, float* py, float* pz,
                  std::uint32_t i) {
  const Vec3 x(px[i], py[i], pz[i]);
  const Vec3 b = B.applyInverse(x);
  const SurfaceDistance s = shapeDistance<S>(c, b);
  if (s.distance >= margin) return;
  const Vec3 xn = B.apply(b + (margin - s.distance) * s.normal);
  px[i] = xn.x();
  py[i] = xn.y();
  pz[i] = xn.z();
}

/// A triangle mesh's contact: out of its contact plane (n, offset in the mesh's frame at B) to the margin.
inline void reprojectPlane(const Eigen::Vector4f& plane, const Pose& B, float margin, float* px, float* py,
                           float* pz, std::uint32_t i) {
  const Vec3 b = B.applyInverse(Vec3(px[i], py[i], pz[i]));
  const Vec3 n = plane.head<3>();
  const float d = n.dot(b) - plane[3];
  if (d >= margin) return;
  const Vec3 xn = B.apply(b + (margin - d) * n);
  px[i] = xn.x();
  py[i] = xn.y();
  pz[i] = xn.z();
}

}  // namespace

BodyCollision::BodyCollision(std::size_t particles) {
  colliderEnd_.reserve(64);
  contacts_.reserve(4 * particles);
  contactPlanes_.reserve(4 * particles);
  distance2_.resize(static_cast<Eigen::Index>(particles));
  candidates_.reserve(particles);
  const auto block = static_cast<std::size_t>(kCullBlock);
  blocks_.resize((particles + block - 1) / block);  // the broad phase's spheres: no step allocates
}

void BodyCollision::collide(const CollisionArrays& p, const CapeSettings& settings, float h, float s0,
                            float s1, ColliderSpan colliders, bool explicitMode) {
  PassArrays q{&contacts_, &contactPlanes_, 0, 0.0f, &distance2_, &candidates_, &blocks_};
  q.maxTravel = std::sqrt(travelAndBlocks(p, blocks_));
  const float invH = 1.0f / h;
  contacts_.clear();
  contactPlanes_.clear();
  colliderEnd_.clear();
  for (const Collider& c : colliders) {
    colliderEnd_.push_back(Pose::interpolate(c.previous, c.current, s1));
    q.collider = static_cast<std::uint32_t>(colliderEnd_.size() - 1);
    if (!c.validate().ok()) continue;  // documented: an invalid collider (NaN pose, bad size) is skipped
    const float margin = settings.collisionThickness + c.thickness;
    const float mu = c.friction >= 0.0f ? c.friction : settings.friction;
    const std::size_t contactsBefore = contacts_.size();
    switch (c.shape) {
      case ColliderShape::Sphere:
        collideWith<ColliderShape::Sphere>(c, p, q, s0, s1, margin, mu, invH, explicitMode);
        break;
      case ColliderShape::Capsule:
        collideWith<ColliderShape::Capsule>(c, p, q, s0, s1, margin, mu, invH, explicitMode);
        break;
      case ColliderShape::Cylinder:
        collideWith<ColliderShape::Cylinder>(c, p, q, s0, s1, margin, mu, invH, explicitMode);
        break;
      case ColliderShape::Box:
        collideWith<ColliderShape::Box>(c, p, q, s0, s1, margin, mu, invH, explicitMode);
        break;
      case ColliderShape::Plane:
        collideWith<ColliderShape::Plane>(c, p, q, s0, s1, margin, mu, invH, explicitMode);
        break;
      case ColliderShape::ConvexHull:
        collideWith<ColliderShape::ConvexHull>(c, p, q, s0, s1, margin, mu, invH, explicitMode);
        break;
      case ColliderShape::TriangleMesh:
        collideMesh(c, p, q.collider, s0, s1, margin, mu, invH, explicitMode);
        break;
    }
    for (std::size_t k = contactsBefore; k < contacts_.size(); ++k) {
      const std::uint32_t i = contacts_[k].particle;
      Eigen::Vector4f& block = blocks_[i / static_cast<std::uint32_t>(kCullBlock)];
      const float dx = p.px[i] - block.x(), dy = p.py[i] - block.y(), dz = p.pz[i] - block.z();
      block.w() = std::max(block.w(), std::sqrt(dx * dx + dy * dy + dz * dz) * (1.0f + 1e-6f));
    }
  }
}

void BodyCollision::beginStep(const CapeState& state, ColliderSpan colliders, const CapeSettings& settings,
                              float dt, float slack) {
  // Each free particle's candidate triangles of each mesh: those whose box overlaps the box of the
  // particle's predicted path over the step in the mesh's frame (from where it is, at the mesh's start pose,
  // to x + v dt + g dt^2 / 2 at its end pose), grown by the margin, the slack and half the path (the
  // solver's corrections). Each with the side of its plane the particle is on now.
  meshSlot_.assign(colliders.size, -1);
  meshStart_.clear();
  meshCandidates_.clear();
  const Eigen::Index n = state.positions.rows();
  int slots = 0;
  for (std::size_t ci = 0; ci < colliders.size; ++ci) {
    const Collider& c = colliders.data[ci];
    if (c.shape != ColliderShape::TriangleMesh || !c.validate().ok()) continue;
    meshSlot_[ci] = slots++;
    const float margin = settings.collisionThickness + c.thickness;
    for (Eigen::Index i = 0; i < n; ++i) {
      meshStart_.push_back(static_cast<std::uint32_t>(meshCandidates_.size()));
      if (state.inverseMasses[i] == 0.0f) continue;
      const Vec3 x = state.positions.row(i).transpose();
      const Vec3 predicted =
          x + dt * Vec3(state.velocities.row(i).transpose()) + (0.5f * dt * dt) * settings.gravity;
      const Vec3 p0 = c.previous.applyInverse(x), p1 = c.current.applyInverse(predicted);
      if (!p0.allFinite() || !p1.allFinite()) continue;
      const float grow = margin + slack + 0.5f * (p1 - p0).norm();
      gatherTriangles(*c.triangles, p0, p0.cwiseMin(p1).array() - grow, p0.cwiseMax(p1).array() + grow);
    }
    meshStart_.push_back(static_cast<std::uint32_t>(meshCandidates_.size()));
  }
}

void BodyCollision::gatherTriangles(const TriangleSoup& soup, const Vec3& p0, const Vec3& lo,
                                    const Vec3& hi) {
  for (std::size_t t = 0; t < soup.size(); ++t) {
    const Vec3 &a = soup.corners[3 * t], &b = soup.corners[3 * t + 1], &c = soup.corners[3 * t + 2];
    if ((a.cwiseMin(b).cwiseMin(c).array() > hi.array()).any() ||
        (a.cwiseMax(b).cwiseMax(c).array() < lo.array()).any())
      continue;
    const float side = (b - a).cross(c - a).dot(p0 - a) >= 0.0f ? 1.0f : -1.0f;
    meshCandidates_.push_back({static_cast<std::uint32_t>(t), side});
  }
}

void BodyCollision::collideMesh(const Collider& c, const CollisionArrays& p, std::uint32_t ci, float s0,
                                float s1, float margin, float mu, float invH, bool explicitMode) {
  if (ci >= meshSlot_.size() || meshSlot_[ci] < 0) return;  // not seen by beginStep: no candidates
  const Sweep w(c, s0, s1, margin);
  const std::uint32_t* start =
      &meshStart_[static_cast<std::size_t>(meshSlot_[ci]) * static_cast<std::size_t>(p.n + 1)];
  for (Eigen::Index i = 0; i < p.n; ++i) {
    if (start[i] == start[i + 1] || p.w[i] == 0.0f) continue;
    const Vec3 x(p.px[i], p.py[i], p.pz[i]);
    const Vec3 a = w.invRA * (Vec3(p.sx[i], p.sy[i], p.sz[i]) - w.A.position);
    const Vec3 b = w.invRB * (x - w.B.position);
    Vec3 bn, normal;
    Eigen::Vector4f plane;
    if (!resolveMesh(*c.triangles, &meshCandidates_[start[i]], meshCandidates_.data() + start[i + 1], margin,
                     b, bn, normal, plane))
      continue;
    applyFriction(mu, a, b, normal, bn);
    placeParticle(p, i, x, w.RB * bn + w.B.position, invH, explicitMode);
    contacts_.push_back({static_cast<std::uint32_t>(i), ci});
    contactPlanes_.push_back(plane);
  }
}

void BodyCollision::reproject(const CollisionArrays& p, const CapeSettings& settings,
                              ColliderSpan colliders) {
  for (std::size_t j = 0; j < contacts_.size(); ++j) {
    const Cape::Contact& k = contacts_[j];
    const Collider& c = colliders.data[k.collider];
    const Pose& B = colliderEnd_[k.collider];
    const float margin = settings.collisionThickness + c.thickness;
    switch (c.shape) {
      case ColliderShape::Sphere:
        reprojectOne<ColliderShape::Sphere>(c, B, margin, p.px, p.py, p.pz, k.particle);
        break;
      case ColliderShape::Capsule:
        reprojectOne<ColliderShape::Capsule>(c, B, margin, p.px, p.py, p.pz, k.particle);
        break;
      case ColliderShape::Cylinder:
        reprojectOne<ColliderShape::Cylinder>(c, B, margin, p.px, p.py, p.pz, k.particle);
        break;
      case ColliderShape::Box:
        reprojectOne<ColliderShape::Box>(c, B, margin, p.px, p.py, p.pz, k.particle);
        break;
      case ColliderShape::Plane:
        reprojectOne<ColliderShape::Plane>(c, B, margin, p.px, p.py, p.pz, k.particle);
        break;
      case ColliderShape::ConvexHull:
        reprojectOne<ColliderShape::ConvexHull>(c, B, margin, p.px, p.py, p.pz, k.particle);
        break;
      case ColliderShape::TriangleMesh:
        reprojectPlane(contactPlanes_[j], B, margin, p.px, p.py, p.pz, k.particle);
        break;
    }
  }
}

}  // namespace cape::detail
