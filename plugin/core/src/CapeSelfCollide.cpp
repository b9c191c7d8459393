// Self-collision: predictive particle-triangle contacts (Lewin 2018, "Cloth Self Collision with Predictive
// Contacts", GDC). At the start of a step every particle that could come within the thickness of a triangle
// it does not belong to during the step is paired with it, and the side of the triangle it is on is noted.
// The substeps then keep the particle on that side, at least the thickness away: as long as the cape starts
// the step free of intersections, no particle can pass through a triangle, however fast the fold.
#include "cape/core/Cape.h"

#include "cape/core/Geometry.h"

#include <algorithm>
#include <cmath>

namespace cape {

namespace {

/// Barycentric weights of p's projection onto the plane of (a, b, c), unclamped; false if degenerate.
bool planeBarycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, float& wa, float& wb, float& wc) {
  const Vec3 v0 = b - a, v1 = c - a, v2 = p - a;
  const float d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
  const float den = d00 * d11 - d01 * d01;
  if (!(den > 1e-20f)) return false;
  wb = (d11 * d20 - d01 * d21) / den;
  wc = (d00 * d21 - d01 * d20) / den;
  wa = 1.0f - wb - wc;
  return true;
}

/// A particle over a triangle grown by this fraction of itself (in barycentric terms) keeps its side: the
/// grown triangles of a vertex's ring overlap, so a particle heading straight for a vertex or an edge of the
/// other layer (two halves of a folded grid line up exactly) is caught as surely as one heading for a face.
constexpr float kFaceMargin = 0.25f;

inline bool overFace(float wa, float wb, float wc) { return wa >= -kFaceMargin && wb >= -kFaceMargin && wc >= -kFaceMargin; }

inline Vec3 at(const Points& x, std::uint32_t i) { return Vec3(x(i, 0), x(i, 1), x(i, 2)); }

inline std::uint32_t bucketOf(int ix, int iy, int iz, std::uint32_t mask) {
  const std::uint32_t h = static_cast<std::uint32_t>(ix) * 73856093u ^ static_cast<std::uint32_t>(iy) * 19349663u ^
                          static_cast<std::uint32_t>(iz) * 83492791u;
  return h & mask;
}

}  // namespace

float Cape::selfThickness() const {
  // As set, or 0.35 of the mean spacing (CapeSettings::selfCollisionThickness explains the measurement).
  constexpr float kAutoThickness = 0.35f;
  return settings_.selfCollisionThickness > 0.0f ? settings_.selfCollisionThickness : kAutoThickness * meanSpacing_;
}

void Cape::findSelfContacts(float dt) {
  selfContacts_.clear();
  const Points& x = state_.positions;
  // A cape that is no longer finite has blown up (the metrics report it); there is nothing to keep apart.
  if (!x.allFinite() || !state_.velocities.allFinite()) return;
  const Eigen::Index n = x.rows();
  const float thickness = selfThickness();

  // How far each particle may move in this step, less the motion the whole cape shares (walking carries
  // every particle 2 cm per frame, which brings no two of them closer): v dt + g dt^2 / 2 (pinned particles
  // move at the velocity their pin gave them).
  stepMotion_ = state_.velocities * dt;
  for (int c = 0; c < 3; ++c) stepMotion_.col(c) += (0.5f * dt * dt * settings_.gravity[c]) * freeMask_;
  const Eigen::RowVector3f mean = stepMotion_.colwise().mean();
  stepMotion_.rowwise() -= mean;
  Eigen::VectorXf& motion = stepMotionNorm_;
  motion = stepMotion_.rowwise().norm();  // same size every step: no allocation

  // A pair can close in by at most their relative motion; the solver's own corrections (springs, collisions)
  // add some more, which a quarter of the spacing allows for.
  const float slack = 0.25f * meanSpacing_;

  // Bin the triangles, each grown by the thickness, the slack and its own motion, into the cells of a hashed
  // grid; each particle then visits the cells of its own motion's box. Cells twice the spacing: a triangle
  // spans one or two per axis.
  const std::vector<std::uint32_t>& tri = fabric_->triangles();
  const std::size_t triangles = tri.size() / 3;
  const float cell = 2.0f * meanSpacing_;
  const float invCell = 1.0f / cell;
  const std::uint32_t buckets = static_cast<std::uint32_t>(hashStart_.size() - 1);
  const std::uint32_t mask = buckets - 1;
  // floor() is a library call in a portable (pre-SSE4.1) build: truncate and correct instead.
  auto cellOf = [invCell](float v) {
    const float f = v * invCell;
    const int i = static_cast<int>(f);
    return i - (f < static_cast<float>(i) ? 1 : 0);
  };
  // A box spanning more cells than this per axis (a fast or huge motion) is not binned: such triangles go on
  // a list every particle checks, and such a particle checks every triangle. Bounded work, whatever the motion.
  constexpr int kMaxSpan = 6;
  auto spans = [&](const Vec3& lo, const Vec3& hi) {
    return cellOf(hi.x()) - cellOf(lo.x()) > kMaxSpan || cellOf(hi.y()) - cellOf(lo.y()) > kMaxSpan ||
           cellOf(hi.z()) - cellOf(lo.z()) > kMaxSpan;
  };
  largeTriangles_.clear();
  triangleBuckets_.clear();
  std::fill(hashStart_.begin(), hashStart_.end(), 0u);
  for (std::size_t t = 0; t < triangles; ++t) {
    triangleBucketStart_[t] = static_cast<std::uint32_t>(triangleBuckets_.size());
    const std::uint32_t ia = tri[3 * t], ib = tri[3 * t + 1], ic = tri[3 * t + 2];
    const Vec3 a = at(x, ia), b = at(x, ib), c = at(x, ic);
    const float triMotion = std::max({motion[ia], motion[ib], motion[ic]});
    const float grow = thickness + slack + triMotion;
    const Vec3 lo = a.cwiseMin(b).cwiseMin(c).array() - grow;
    const Vec3 hi = a.cwiseMax(b).cwiseMax(c).array() + grow;
    float* box = &triangleBoxes_[8 * t];
    for (int k = 0; k < 3; ++k) {
      box[k] = lo[k];
      box[3 + k] = hi[k];
    }
    // A bounding sphere for a quick rejection: about the centroid, out to the farthest corner.
    const Vec3 centroid = (a + b + c) / 3.0f;
    box[6] = triMotion;
    box[7] = std::sqrt(std::max({(a - centroid).squaredNorm(), (b - centroid).squaredNorm(), (c - centroid).squaredNorm()}));
    if (spans(lo, hi)) {
      largeTriangles_.push_back(static_cast<std::uint32_t>(t));
      continue;
    }
    // The buckets of its cells, kept for the fill below (at most (kMaxSpan + 1)^3; usually 1 to 8).
    for (int ix = cellOf(lo.x()); ix <= cellOf(hi.x()); ++ix)
      for (int iy = cellOf(lo.y()); iy <= cellOf(hi.y()); ++iy)
        for (int iz = cellOf(lo.z()); iz <= cellOf(hi.z()); ++iz) {
          const std::uint32_t bucket = bucketOf(ix, iy, iz, mask);
          ++hashStart_[bucket + 1];
          triangleBuckets_.push_back(bucket);  // grows rarely: capacity kept between steps
        }
  }
  triangleBucketStart_[triangles] = static_cast<std::uint32_t>(triangleBuckets_.size());
  for (std::uint32_t b = 0; b < buckets; ++b) hashStart_[b + 1] += hashStart_[b];  // [b] = start of bucket b
  if (hashEntries_.size() < hashStart_[buckets]) hashEntries_.resize(hashStart_[buckets]);  // grows rarely
  // Fill in triangle order (deterministic), each bucket's start serving as its cursor...
  for (std::size_t t = 0; t < triangles; ++t) {
    const float* box = &triangleBoxes_[8 * t];
    const HashEntry entry{{box[0], box[1], box[2]}, {box[3], box[4], box[5]}, static_cast<std::uint32_t>(t)};
    for (std::uint32_t k = triangleBucketStart_[t]; k < triangleBucketStart_[t + 1]; ++k)
      hashEntries_[hashStart_[triangleBuckets_[k]]++] = entry;
  }
  // ...which leaves [b] at the end of bucket b: shift back so bucket b is [hashStart_[b], hashStart_[b + 1]).
  for (std::uint32_t b = buckets; b > 0; --b) hashStart_[b] = hashStart_[b - 1];
  hashStart_[0] = 0;

  // One particle against one triangle: the exact filter, and the contact with the side it is on.
  auto consider = [&](std::uint32_t q, const Vec3& p, float mq, std::uint32_t t, const float* lo, const float* hi) {
    if (p.x() + mq < lo[0] || p.y() + mq < lo[1] || p.z() + mq < lo[2] || p.x() - mq > hi[0] || p.y() - mq > hi[1] ||
        p.z() - mq > hi[2])
      return;
    if (triangleStamp_[t] == q) return;  // met already through another cell
    triangleStamp_[t] = q;
    const float* box = &triangleBoxes_[8 * t];
    const std::uint32_t ia = tri[3 * t], ib = tri[3 * t + 1], ic = tri[3 * t + 2];
    if (q == ia || q == ib || q == ic) return;
    // How much closer the two may come: the particle's motion relative to the triangle's corners.
    const Vec3 mqv = stepMotion_.row(q).transpose();
    const float closing = std::sqrt(std::max({(mqv - stepMotion_.row(ia).transpose()).squaredNorm(),
                                              (mqv - stepMotion_.row(ib).transpose()).squaredNorm(),
                                              (mqv - stepMotion_.row(ic).transpose()).squaredNorm()}));
    const float within = thickness + slack + closing;
    // The bounding sphere first: it rejects the cape's own neighbourhood (near, but moving along) cheaply.
    const Vec3 a = at(x, ia), b = at(x, ib), c = at(x, ic);
    const float reach = within + box[7];
    if ((p - (a + b + c) / 3.0f).squaredNorm() > reach * reach) return;
    const TriangleNearest w = nearestOnTriangle(p, a, b, c);
    const Vec3 nearest = w.wa * a + w.wb * b + w.wc * c;
    if ((p - nearest).squaredNorm() > within * within) return;
    float side = 0.0f, wa, wb, wc;
    if (planeBarycentric(p, a, b, c, wa, wb, wc) && overFace(wa, wb, wc))
      side = (b - a).cross(c - a).dot(p - a) >= 0.0f ? 1.0f : -1.0f;
    selfContacts_.push_back({q, t, side});
  };

  std::fill(triangleStamp_.begin(), triangleStamp_.end(), ~0u);
  for (Eigen::Index qi = 0; qi < n; ++qi) {
    const std::uint32_t q = static_cast<std::uint32_t>(qi);
    const Vec3 p = at(x, q);
    const float mq = motion[q];
    if (spans(p.array() - mq, p.array() + mq)) {
      for (std::size_t t = 0; t < triangles; ++t)
        consider(q, p, mq, static_cast<std::uint32_t>(t), &triangleBoxes_[8 * t], &triangleBoxes_[8 * t + 3]);
      continue;
    }
    for (int ix = cellOf(p.x() - mq); ix <= cellOf(p.x() + mq); ++ix)
      for (int iy = cellOf(p.y() - mq); iy <= cellOf(p.y() + mq); ++iy)
        for (int iz = cellOf(p.z() - mq); iz <= cellOf(p.z() + mq); ++iz) {
          const std::uint32_t bucket = bucketOf(ix, iy, iz, mask);
          for (std::uint32_t e = hashStart_[bucket]; e < hashStart_[bucket + 1]; ++e) {
            const HashEntry& entry = hashEntries_[e];
            consider(q, p, mq, entry.triangle, entry.lo, entry.hi);
          }
        }
    for (const std::uint32_t t : largeTriangles_) consider(q, p, mq, t, &triangleBoxes_[8 * t], &triangleBoxes_[8 * t + 3]);
  }
}

void Cape::solveSelfContacts(const float* w) {
  Points& x = state_.positions;
  const float thickness = selfThickness();
  // The deepest a particle can have crossed within one step and still be brought back: half the spacing.
  const float maxCrossing = 0.5f * meanSpacing_;
  const std::vector<std::uint32_t>& tri = fabric_->triangles();
  for (SelfContact& k : selfContacts_) {
    const std::uint32_t ia = tri[3 * k.triangle], ib = tri[3 * k.triangle + 1], ic = tri[3 * k.triangle + 2];
    const Vec3 p = at(x, k.particle), a = at(x, ia), b = at(x, ib), c = at(x, ic);
    const TriangleNearest bary = nearestOnTriangle(p, a, b, c);
    Vec3 normal;
    float distance;
    float wa, wb, wc;
    if (planeBarycentric(p, a, b, c, wa, wb, wc) && overFace(wa, wb, wc)) {
      // Over the (grown) face: keep to the side the particle started the step on, or first came over it from.
      Vec3 faceNormal = (b - a).cross(c - a);
      const float len = faceNormal.norm();
      if (!(len > 0.0f)) continue;
      faceNormal /= len;
      if (k.side == 0.0f) k.side = faceNormal.dot(p - a) >= 0.0f ? 1.0f : -1.0f;
      normal = k.side * faceNormal;
      distance = normal.dot(p - a);  // negative: it has crossed, and is brought back
      // Far on the other side is not a crossing within this step (the region over a face reaches out along
      // its normal without end, and a triangle that turns over carries its side with it): pulling such a
      // particle back through the cloth would throw it across the cape, so the pair is let go.
      if (distance < -maxCrossing) continue;
      // The correction goes to the corners by the weights of the nearest point of the real triangle.
    } else {
      // Beside an edge or a corner: a plain distance, no side to keep.
      const Vec3 d = p - (bary.wa * a + bary.wb * b + bary.wc * c);
      distance = d.norm();
      if (!(distance > 1e-9f)) continue;
      normal = d / distance;
    }
    if (distance >= thickness) continue;
    // PBD point-triangle constraint C = n . (p - sum w_k x_k) - thickness >= 0, gradients n and -w_k n.
    const float invP = w[k.particle], invA = w[ia], invB = w[ib], invC = w[ic];
    const float denominator = invP + bary.wa * bary.wa * invA + bary.wb * bary.wb * invB + bary.wc * bary.wc * invC;
    if (!(denominator > 0.0f)) continue;
    const Vec3 step = ((thickness - distance) / denominator) * normal;
    x.row(k.particle) += invP * step.transpose();
    x.row(ia) -= (invA * bary.wa) * step.transpose();
    x.row(ib) -= (invB * bary.wb) * step.transpose();
    x.row(ic) -= (invC * bary.wc) * step.transpose();
  }
}

}  // namespace cape
