#include "cape/core/FabricPresets.h"

#include <cmath>
#include <limits>
#include <string>

namespace cape {

namespace {

// Units of the Kawabata Evaluation System for Fabrics (KES-F; Kawabata 1980, "The Standardization and
// Analysis of Hand Evaluation", 2nd ed., Textile Machinery Society of Japan) and their SI values.
//  - W, mass per area, mg/cm^2: 1 mg/cm^2 = 1e-6 kg / 1e-4 m^2 = 1e-2 kg/m^2.
//  - B, bending rigidity, gf·cm^2/cm (moment per width per curvature): 1 gf = 9.80665e-3 N, 1 cm^2 = 1e-4
//  m^2,
//    1 / cm = 1e2 / m, so 1 gf·cm^2/cm = 9.80665e-3 * 1e-4 * 1e2 N·m = 9.80665e-5 N·m.
//  - G, shear rigidity, gf/cm/degree (shear force per width per degree of shear angle):
//    1 gf/cm = 9.80665e-3 N / 1e-2 m = 0.980665 N/m, per degree = 180/pi per radian.
//  - EMT, extension (%) at the standard maximum load of 500 gf/cm (KES-FB1 tensile test): the secant membrane
//    stiffness to that load is (500 gf/cm) / (EMT / 100), and 500 gf/cm = 490.3325 N/m.
constexpr double kGramForce = 9.80665e-3;  // N
constexpr double kPi = 3.14159265358979323846;

constexpr float fromMgPerCm2(double w) {
  return static_cast<float>(w * 1e-2);
}
constexpr float fromGfCm2PerCm(double b) {
  return static_cast<float>(b * kGramForce * 1e-4 * 1e2);
}
constexpr float fromGfPerCmDegree(double g) {
  return static_cast<float>(g * kGramForce / 1e-2 * 180.0 / kPi);
}
constexpr float fromEmtPercent(double emt) {
  return static_cast<float>(500.0 * kGramForce / 1e-2 / (emt / 100.0));
}

// Air, for the still-air damping below.
constexpr double kAirDensity = 1.2;           // kg/m^3, at about 20 C and sea level
constexpr double kDampingReferenceSpeed = 1;  // m/s: a cape's typical speed through the air when walking
// Normal drag coefficient of a flat plate broadside to the flow: 1.17 for a square plate (Hoerner 1965,
// "Fluid-Dynamic Drag", ch. 3, flat plates normal to the flow). Dense woven cloth and leather let little air
// through, so the plate's figure stands for all five; porosity (chiffon, voile) would lower it.
constexpr float kPlateDrag = 1.17f;
// The wind model's lift term adds force across the flow beyond what the plate's normal force already gives
// (Wind.h). No measurement of it for cloth was found; this is WindSettings' default, not a measured figure.
constexpr float kClothLift = 0.2f;

// CapeSettings::damping stands in for still air's drag (CapeSettings.h): the drag of a piece of area A moving
// broadside at v, 1/2 rho Cd A v^2, is m c v with m = rho_A A for c = rho Cd v / (2 rho_A), taken at the
// reference speed. So a light silk is damped by the air far more than a heavy leather.
constexpr float stillAirDamping(float arealDensity, float dragCoefficient) {
  return static_cast<float>(kAirDensity * dragCoefficient * kDampingReferenceSpeed / (2.0 * arealDensity));
}

FabricMaterial material(const char* name, float arealDensity, float stretch, float shear, float bending,
                        const char* source) {
  FabricMaterial m;
  m.name = name;
  m.arealDensity = arealDensity;
  m.stretchStiffness = stretch;
  m.shearStiffness = shear;
  m.bendingRigidity = bending;
  m.dragCoefficient = kPlateDrag;
  m.liftCoefficient = kClothLift;
  m.damping = stillAirDamping(arealDensity, kPlateDrag);
  m.source = source;
  return m;
}

std::vector<FabricMaterial> makePresets() {
  std::vector<FabricMaterial> p;
  // Silk habutae / crepe de chine, a light plain weave (women's thin dress). W 5.0 mg/cm^2, B 0.015
  // gf·cm^2/cm, G 0.3 gf/cm/deg, EMT 8 %: representative of the KES-F ranges for silk filament weaves
  // (Matsudaira, "Characteristics of mechanical properties and handles of silk filament weaves", Kanazawa
  // University: silk weaves are very stretchy and have extremely small shear stiffness at small strain).
  p.push_back(material("silk", fromMgPerCm2(5.0), fromEmtPercent(8.0), fromGfPerCmDegree(0.3),
                       fromGfCm2PerCm(0.015),
                       "silk habutae: KES-F W 5.0 mg/cm2, B 0.015 gf.cm2/cm, G 0.3 gf/cm/deg, EMT 8 % "
                       "(representative of Matsudaira, silk filament weaves, KES-FB); drag Hoerner 1965"));
  // Cotton shirting (broadcloth). W 11 mg/cm^2, B 0.06 gf·cm^2/cm, G 0.8 gf/cm/deg, EMT 4 %.
  p.push_back(material("cotton", fromMgPerCm2(11.0), fromEmtPercent(4.0), fromGfPerCmDegree(0.8),
                       fromGfCm2PerCm(0.06),
                       "cotton shirting: KES-F W 11 mg/cm2, B 0.06 gf.cm2/cm, G 0.8 gf/cm/deg, EMT 4 % "
                       "(representative of Kawabata 1980's shirting ranges); drag Hoerner 1965"));
  // Wool suiting (men's winter suit). W 20 mg/cm^2, B 0.10 gf·cm^2/cm, G 0.6 gf/cm/deg, EMT 6 %.
  p.push_back(
      material("wool", fromMgPerCm2(20.0), fromEmtPercent(6.0), fromGfPerCmDegree(0.6), fromGfCm2PerCm(0.10),
               "wool suiting: KES-F W 20 mg/cm2, B 0.10 gf.cm2/cm, G 0.6 gf/cm/deg, EMT 6 % "
               "(representative of Kawabata and Niwa 1989, J. Text. Inst. 80:19, men's suiting); drag "
               "Hoerner 1965"));
  // Denim. B 0.227 gf·cm^2/cm, G 3.398 gf/cm/deg, EMT 4.695 %: sample C of "Regenerated cellulose-based denim
  // fabric for tropical regions", Journal of Textiles 2016, article 4614168, Table 5 (KES-FB); its weight is
  // not used (the table's unit is doubtful). W 40.7 mg/cm^2 is 12 oz/yd^2 (1 oz/yd^2 = 33.906 g/m^2), the
  // standard weight of jeans denim.
  p.push_back(material("denim", fromMgPerCm2(12.0 * 3.3906), fromEmtPercent(4.695), fromGfPerCmDegree(3.398),
                       fromGfCm2PerCm(0.227),
                       "denim: KES-FB B 0.227 gf.cm2/cm, G 3.398 gf/cm/deg, EMT 4.695 % (J. Textiles 2016, "
                       "4614168, Table 5, sample C); W 12 oz/yd2; drag Hoerner 1965"));
  // Sheep garment leather (nappa), 0.64-0.96 mm thick with a drape coefficient of 47-70 % (Memon, Chaklie,
  // Yesuf and Zhu 2021, "Study on effect of leather rigidity and thickness on drapability of sheep garment
  // leather", Materials 14:4553). W 60 mg/cm^2: their mean thickness 0.8 mm at a leather density of
  // 0.75 g/cm^3. No KES-F bending figure for garment leather was at hand: B 0.45 gf·cm^2/cm is fitted to
  // their drape, the middle of 47-70 % in the Cusick test of cape/scenes/Textile.h (0.60-0.63 at 7.5 mm and
  // 1 cm meshes; docs/SOLVER.md), a bending length of 1.96 cm, stiffer than the cloths. Leather is a fibre
  // felt, not a weave: its membrane is stiff in shear as in tension (E t ~ 10 MPa * 0.8 mm).
  p.push_back(
      material("leather", fromMgPerCm2(60.0), 8000.0f, 3000.0f, fromGfCm2PerCm(0.45),
               "sheep garment leather: thickness and drape from Memon et al. 2021, Materials 14:4553; "
               "W from 0.8 mm at 0.75 g/cm3; B 0.45 gf.cm2/cm fitted to that drape in the Cusick test; "
               "stretch and shear are estimates, not measurements; drag Hoerner 1965"));
  return p;
}

bool finitePositive(float v) {
  return std::isfinite(v) && v > 0.0f;
}
bool finiteNonNegative(float v) {
  return std::isfinite(v) && v >= 0.0f;
}

}  // namespace

float FabricMaterial::bendingLength() const {
  return std::cbrt(bendingRigidity / (arealDensity * kStandardGravity));
}

Status FabricMaterial::validate() const {
  const std::string who = "FabricMaterial '" + name + "': ";
  if (name.empty()) return Status::error("FabricMaterial: the name is empty");
  if (!finitePositive(arealDensity)) return Status::error(who + "arealDensity must be finite and > 0 kg/m^2");
  if (!finitePositive(stretchStiffness))
    return Status::error(who + "stretchStiffness must be finite and > 0 N/m");
  if (!finiteNonNegative(shearStiffness))
    return Status::error(who + "shearStiffness must be finite and >= 0 N/m");
  if (!(shearStiffness < stretchStiffness))
    return Status::error(who + "shearStiffness must be below stretchStiffness (the grid's diagonals carry " +
                         "both; docs/SOLVER.md, \"Fabric presets\")");
  if (!finitePositive(bendingRigidity))
    return Status::error(who + "bendingRigidity must be finite and > 0 N·m");
  if (!finiteNonNegative(damping)) return Status::error(who + "damping must be finite and >= 0 1/s");
  if (!finiteNonNegative(dragCoefficient))
    return Status::error(who + "dragCoefficient must be finite and >= 0");
  if (!std::isfinite(liftCoefficient)) return Status::error(who + "liftCoefficient must be finite");
  if (!finitePositive(bendingLength()))
    return Status::error(who + "its bending length (B / (rho_A g))^(1/3) is not a finite positive length");
  return Status::success();
}

const std::vector<FabricMaterial>& fabricPresets() {
  static const std::vector<FabricMaterial> presets = makePresets();
  return presets;
}

const FabricMaterial* findFabric(std::string_view name) {
  for (const FabricMaterial& m : fabricPresets())
    if (m.name == name) return &m;
  return nullptr;
}

std::string fabricNames() {
  std::string names;
  for (const FabricMaterial& m : fabricPresets()) {
    if (!names.empty()) names += ", ";
    names += m.name;
  }
  return names;
}

// A square grid of spacing h (docs/SOLVER.md, "Fabric presets", has the derivations): a cell has one
// structural spring along each axis (its four edges each shared by two cells) and two diagonals.
//  - Shear: a shear angle gamma stretches one diagonal and shortens the other by h gamma / sqrt(2) each, so a
//    cell stores 2 * 1/2 k_d (h gamma / sqrt 2)^2 = 1/2 k_d h^2 gamma^2: per area 1/2 k_d gamma^2, the
//    membrane's 1/2 G gamma^2 for k_d = G.
//  - Stretch: a strain eps along an axis stretches that axis's spring by h eps and each diagonal by
//    h eps / sqrt 2: per area 1/2 (k_s + k_d) eps^2, the membrane's 1/2 Y eps^2 for k_s = Y - G.
float fabricShearStiffness(const FabricMaterial& m, float spacing) {
  (void)spacing;  // independent of the spacing: a spring of a square cell spans as much width as length
  return m.shearStiffness;
}

float fabricStructuralStiffness(const FabricMaterial& m, float spacing) {
  (void)spacing;
  return m.stretchStiffness - m.shearStiffness;
}

//  - Bending: the fabric's flexural rigidity B itself, CapeSettings::bendingRigidity, for the linear hinges
//    of Fabric::hinges() (a moment linear in the hinge's angle, its energy the plate's 1/2 B kappa^2 over the
//    hinge's area: independent of the spacing). The skip-one bend springs are switched off: a distance
//    spring has no stiffness at small angles and a moment cubic in the angle, so it can match the fabric at
//    one curvature only.
Status checkFabric(const FabricMaterial& m, float spacing) {
  const Status s = m.validate();
  if (!s.ok()) return s;
  if (!finitePositive(spacing))
    return Status::error("applyFabric: the grid spacing must be finite and > 0 m (got " +
                         std::to_string(spacing) + ")");
  return Status::success();
}

CapeSettings applyFabric(const FabricMaterial& m, float spacing, CapeSettings base) {
  if (!checkFabric(m, spacing).ok()) return base;
  base.structuralStiffness = fabricStructuralStiffness(m, spacing);
  base.shearStiffness = fabricShearStiffness(m, spacing);
  base.bendStiffness = 0.0f;
  base.bendingRigidity = m.bendingRigidity;
  base.damping = m.damping;
  base.wind.dragCoefficient = m.dragCoefficient;
  base.wind.liftCoefficient = m.liftCoefficient;
  return base;
}

float fabricMass(const FabricMaterial& m, float width, float height) {
  if (!finiteNonNegative(width) || !finiteNonNegative(height) || !finitePositive(m.arealDensity)) return 0.0f;
  return m.arealDensity * width * height;
}

}  // namespace cape
