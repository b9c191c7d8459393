/// \file
/// FabricPresets: real fabrics as per-area material data (from published measurements), and their mapping
/// onto the solver's per-spring stiffnesses for a grid of a given spacing, so that a coarse and a fine cape
/// of one fabric bend alike. The derivations are in docs/SOLVER.md, "Fabric presets"; each preset's sources
/// are in FabricPresets.cpp beside its numbers.
#pragma once

#include "cape/core/CapeSettings.h"
#include "cape/core/Export.h"

#include <string>
#include <string_view>
#include <vector>

namespace cape {

/// A real fabric, per unit area: independent of any grid. Warp and weft are taken alike (the mean of the two
/// directions where a source gives both).
struct CAPE_CORE_API FabricMaterial {
  std::string name;               ///< "silk", "cotton", "wool", "denim", "leather"
  float arealDensity = 0.0f;      ///< kg/m^2: mass per area (KES-F W; 1 mg/cm^2 = 0.01 kg/m^2).
  float stretchStiffness = 0.0f;  ///< N/m: membrane tensile stiffness, force per width per unit strain.
  float shearStiffness = 0.0f;    ///< N/m: in-plane shear force per width per radian of shear angle.
  /// N·m: flexural rigidity per unit width, bending moment per width per unit curvature (KES-F B;
  /// 1 gf·cm²/cm = 9.80665e-5 N·m).
  float bendingRigidity = 0.0f;
  float damping = 0.0f;  ///< 1/s: the linear velocity damping of CapeSettings::damping for this fabric.
  float dragCoefficient = 0.0f;  ///< Normal (pressure) drag coefficient, for WindSettings.
  float liftCoefficient = 0.0f;  ///< Lift coefficient, for WindSettings.
  std::string source;            ///< Where the numbers come from (citations).

  /// The bending length c = (B / w)^(1/3) of Peirce (1930) and ASTM D1388, m, with w = arealDensity * g the
  /// weight per area under standard gravity g = 9.80665 m/s^2.
  float bendingLength() const;
  /// Whether every number is finite and in range (name not empty; density, stretch and bending > 0; shear,
  /// damping, drag >= 0; shear below stretch, since the grid's diagonals carry both; lift finite): a clear
  /// message otherwise.
  Status validate() const;
};

/// Standard gravity, m/s^2: the g that turns a mass per area into the weight per area of the textile tests.
constexpr float kStandardGravity = 9.80665f;

/// The presets: silk, cotton (shirting), wool (suiting), denim, leather, from the most drapey to the
/// stiffest.
CAPE_CORE_API const std::vector<FabricMaterial>& fabricPresets();
/// The preset of that name (exact, lower case, as fabricNames() lists), nullptr if unknown.
CAPE_CORE_API const FabricMaterial* findFabric(std::string_view name);
/// The presets' names, comma separated ("silk, cotton, ..."): for --help and error messages.
CAPE_CORE_API std::string fabricNames();

/// The settings of a cape of material `m` on a grid whose rest spacing is `spacing` (m; Fabric::meanSpacing()
/// of a square grid): per-spring structural and shear stiffness derived from the material (for a square
/// cell they do not depend on the spacing), the linear bending's rigidity (`bendingRigidity` = the
/// material's B, the bend springs off: `bendStiffness` 0), the fabric's damping and the wind's drag and lift
/// coefficients; every other field is `base`'s.
/// Bad input (an invalid material, spacing not finite and > 0) returns `base` unchanged: checkFabric() says
/// why.
CAPE_CORE_API CapeSettings applyFabric(const FabricMaterial& m, float spacing,
                                       CapeSettings base = CapeSettings());
/// Whether applyFabric(m, spacing) can be applied: the material's validate(), then the spacing (m, finite and
/// > 0).
CAPE_CORE_API Status checkFabric(const FabricMaterial& m, float spacing);

/// The mass of a width x height piece of the fabric, kg (width and height in m; 0 for negative or non-finite
/// sizes).
CAPE_CORE_API float fabricMass(const FabricMaterial& m, float width, float height);

/// The per-spring stiffness of one family for material `m` at grid spacing `spacing` (m), N/m: what
/// applyFabric() puts into CapeSettings (exposed for tests and tools). Structural Y - G and shear G do not
/// depend on the spacing (Y = stretchStiffness, G = shearStiffness).
CAPE_CORE_API float fabricStructuralStiffness(const FabricMaterial& m, float spacing);
/// The shear family's per-spring stiffness, N/m (see fabricStructuralStiffness).
CAPE_CORE_API float fabricShearStiffness(const FabricMaterial& m, float spacing);
}  // namespace cape
