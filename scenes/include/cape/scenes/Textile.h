/// \file
/// The textile industry's own tests of a fabric, run on the solver core: Peirce's cantilever bending length
/// (ASTM D1388, BS 3356) and Cusick's drape coefficient (BS 5058, ISO 9073-9). Tests check the fabric presets
/// with them and the demo `cape_textile` reruns them; the methods and the figures are in docs/SOLVER.md,
/// "Validation".
#pragma once

#include "cape/core/Cape.h"
#include "cape/core/FabricPresets.h"
#include "cape/scenes/Export.h"

#include <vector>

namespace cape {

/// Peirce's cantilever (1930, "The 'handle' of cloth as a measurable quantity", J. Text. Inst. 21:T377): a
/// strip lies on a platform with `overhang` of it beyond the edge; under its own weight the overhang droops,
/// and the chord from the edge to the tip falls theta below the horizontal. Here the platform is two pinned
/// rows of particles (the tangent at the edge held flat) and the strip a grid of `columns` particles across
/// and `segments` hinges along the overhang, its mass spread by area (GridDesc::massByArea), in standard
/// gravity; it settles for `seconds`.
struct CAPE_SCENES_API CantileverSpec {
  float overhang = 0.0f;  ///< m; 0 chooses twice the fabric's bending length (the standard's 41.5 degrees)
  int segments = 16;      ///< hinges along the overhang, >= 1
  int columns = 3;        ///< particles across the strip, >= 2
  int substeps = 200;     ///< per 1/60 s: a converged solve (the game's 3 x 1 droops the strip more)
  int iterations = 20;    ///< per substep
  float seconds = 2.0f;   ///< settling time, s
  float damping = 30.0f;  ///< 1/s: settles the strip sooner; its rest shape does not depend on it
};

/// What the cantilever measured.
struct CAPE_SCENES_API CantileverResult {
  Status status = Status::success();  ///< Why nothing was measured (bad material or spec).
  float overhang = 0.0f;              ///< m
  float theta = 0.0f;                 ///< rad, the tip's droop below the edge
  /// Peirce's bending length from theta, L (cos(theta / 2) / (8 tan theta))^(1/3), m.
  float bendingLength = 0.0f;
  float expected = 0.0f;  ///< (B / w)^(1/3), the material's FabricMaterial::bendingLength(), m
  float maxSpeed = 0.0f;  ///< m/s at the end: whether it settled
  Points positions;       ///< The settled strip, m (platform rows first)
  FabricPtr fabric;       ///< The strip's fabric (its triangles, for pictures)
};

/// Runs the cantilever test of material `m` (the settings from applyFabric at the strip's spacing).
CAPE_SCENES_API CantileverResult runCantilever(const FabricMaterial& m, const CantileverSpec& spec = {});

/// Cusick's drape test (Cusick 1968, J. Text. Inst. 59:253; BS 5058, ISO 9073-9): a circular specimen is
/// clamped between two discs of a smaller diameter; the ring outside them falls into folds, and the
/// coefficient (S - Sd) / (Sf - Sd) of its shadow area S (Sd the disc's area, Sf the flat specimen's) says
/// how stiff it is: 0 hangs straight down, 1 stays flat. The specimen is an equilateral triangle mesh
/// (every direction bends alike) of edge `spacing`, horizontal, every particle within the disc pinned; a
/// deterministic ripple of `perturbation` breaks the symmetry as a real specimen's irregularities do.
struct CAPE_SCENES_API DrapeSpec {
  float specimenDiameter = 0.30f;  ///< m (BS 5058: 30 cm)
  float discDiameter = 0.18f;      ///< m (BS 5058: 18 cm)
  float spacing = 0.0075f;         ///< m, the mesh's edge length
  int substeps = 40;               ///< per 1/60 s
  int iterations = 10;             ///< per substep
  float seconds = 3.0f;            ///< settling time, s
  float damping = 10.0f;           ///< 1/s, added to the fabric's (settles it sooner)
  float perturbation = 2e-4f;      ///< m, the height of the starting ripple
  unsigned seed = 1;               ///< of the ripple
  bool selfCollision = true;       ///< neighbouring folds may not pass through each other
};

/// What the drape test measured.
struct CAPE_SCENES_API DrapeResult {
  Status status = Status::success();  ///< Why nothing was measured (bad material or spec).
  float coefficient = 0.0f;           ///< (S - Sd) / (Sf - Sd)
  int folds = 0;                      ///< nodes of the shadow's outline (lobes beyond its mean radius)
  float shadowArea = 0.0f;            ///< S, m^2
  float specimenArea = 0.0f;          ///< Sf, m^2 (the mesh's flat shadow)
  float discArea = 0.0f;              ///< Sd, m^2
  float maxSpeed = 0.0f;              ///< m/s at the end: whether it settled
  Points positions;                   ///< The settled specimen, m (y up, the disc at y = 0)
  FabricPtr fabric;                   ///< The specimen's fabric (its triangles, for pictures)
};

/// The drape specimen: an equilateral triangle mesh of edge `spacing` clipped to the specimen's circle, in
/// the x-z plane (y = 0, counter-clockwise seen from +y), its mass the material's per area (empty
/// positions on a bad spec).
CAPE_SCENES_API MeshDesc drapeSpecimen(const FabricMaterial& m, const DrapeSpec& spec);

/// The area of the triangles' shadow on the x-z plane (their projection along y, overlaps counted once),
/// m^2: the mesh rasterised at `pixel` m (centre sampling).
CAPE_SCENES_API float shadowArea(const Points& positions, const std::vector<std::uint32_t>& triangles,
                                 float pixel = 5e-4f);

/// The number of folds (nodes) of a draped specimen: the lobes of its outline's radius about the y axis
/// (the largest radius of the particles in each degree, smoothed over 15 degrees) beyond its mean.
CAPE_SCENES_API int countFolds(const Points& positions);

/// Runs the drape test of material `m` (the settings from applyFabric at the mesh's spacing).
CAPE_SCENES_API DrapeResult runDrape(const FabricMaterial& m, const DrapeSpec& spec = {});

}  // namespace cape
