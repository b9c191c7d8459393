/// \file
/// Wind: the air's velocity field and the forces it puts on the cape.
///
/// Two models (WindSettings::Model):
///  - SineWave, the seed's: the air moves uniformly in space along `direction` at
///    speed * (1 + gustAmplitude * sin(2 pi gustFrequency t)); each particle feels the quadratic drag of its
///    share of the cloth's area, F_i = 1/2 rho Cd A_i |u| u, u = v_air - v_i, whatever the cloth's
///    orientation.
///  - Aerodynamic: per-triangle pressure drag and lift from the air's velocity relative to the triangle (both
///    sides alike), in a deterministic gusty field: the mean wind plus gusts and cross-wind turbulence made
///    of travelling waves whose frequencies, wave vectors and phases are drawn from `seed`.
#pragma once

#include "cape/core/CapeSettings.h"
#include "cape/core/Export.h"

namespace cape {

/// The air's velocity at a world point and time, m/s. Deterministic: the same settings (seed included), point
/// and time give the same bits. Zero for Model::None.
CAPE_CORE_API Vec3 windVelocity(const WindSettings& wind, const Vec3& point, double time);

/// The same at many points at once (vectorised), one row per point; `out` must have as many rows as `points`.
/// The points may be given in a frame whose origin is the world point `origin` (a cape's frame,
/// Cape::origin): the field is the world's, its phases taken at origin + point in double.
CAPE_CORE_API void windVelocities(const WindSettings& wind, const Points& points, double time, Points& out,
                                  const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

/// The aerodynamic force on one triangle, N (Model::Aerodynamic). `relativeAir` is the air's velocity
/// relative to the triangle, u (m/s); `areaNormal` is the triangle's normal scaled by its area, A n (m^2;
/// either side: the force does not depend on the sign of n). With q = rho / 2:
/// \verbatim
///   drag  F_d = q Cd A |u| (u . n) n                        (pressure on the normal component; for a plate
///                                                             inclined at angle of attack a: |F_d| ~ sin a)
///   lift  F_l = q Cl A |u| (u . n) (n - (n . u^) u^)         (perpendicular to u, |F_l| = q Cl A |u|^2 cos
///   sin)
/// \endverbatim
/// so that a plate broadside to the flow feels pure drag and one edge-on feels nothing.
CAPE_CORE_API Vec3 aerodynamicForce(const Vec3& relativeAir, const Vec3& areaNormal, float airDensity,
                                    float dragCoefficient, float liftCoefficient);

}  // namespace cape
