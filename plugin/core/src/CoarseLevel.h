/// \file
/// Cape::CoarseLevel: the coarse level of detail's cape (Cape::setCoarseLevel) and the tables that carry
/// state between it and the fine cape, both grids over one rectangle.
#pragma once

#include "cape/core/Cape.h"

#include <cstdint>
#include <vector>

namespace cape {

namespace detail {
/// One grid line's place on another grid over the same span: value = (1 - weight) v[first] +
/// weight v[first + 1].
struct GridTap {
  int first = 0;
  float weight = 0.0f;
};
}  // namespace detail

struct Cape::CoarseLevel {
  /// A coarse cape of `coarseFabric` with the fine cape's settings and overrides, placed where its
  /// reference pose stands.
  CoarseLevel(FabricPtr coarseFabric, const Cape& fine);

  using Tap = detail::GridTap;

  /// Turns the fading detail with the cape (a teleport's or a carry's rotation), while it lasts.
  void turnOffset(const Eigen::Matrix3f& rotation) {
    if (!(blend > 0.0f)) return;
    for (Eigen::Index i = 0; i < offset.rows(); ++i)
      offset.row(i) = (rotation * offset.row(i).transpose()).transpose();
  }
  /// One fine pin's share of a coarse pin's target.
  struct PinSource {
    std::uint32_t coarsePin = 0;
    std::uint32_t finePin = 0;
    float weight = 0.0f;
  };

  Cape cape;
  std::vector<Tap> fineRows, fineColumns;      ///< Each fine row and column on the coarse grid.
  std::vector<Tap> coarseRows, coarseColumns;  ///< Each coarse row and column on the fine grid.
  std::vector<PinSource> pinSources;           ///< The coarse pins' targets from the fine pins'.
  std::vector<std::int32_t> finePinOf;         ///< Per fine particle: its pin's index, or -1.
  std::vector<std::int32_t> nodePin;           ///< Per coarse particle: its pin's index, or -1.
  std::vector<float> nodeShare;                ///< Per coarse particle: fine pins taken by nearness.
  Eigen::VectorXf along;                       ///< interpolate()'s first pass (sized once).
  Points offset;               ///< The fine detail at the switch: fine less interpolated coarse, m.
  std::uint32_t restored = 0;  ///< Fine particles found lost at the last switch (for the guard's report).
  float blend = 0.0f;     ///< How much of `offset` the fine particles still show (1 at the switch, then 0).
  bool stale = true;      ///< Sample the fine state before the next coarse step.
  bool pinsStale = true;  ///< Rebuild the coarse pins from the fine pins before the next coarse step.
};

}  // namespace cape
