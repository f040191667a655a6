// ValidateMaterial: the ranges every material model must satisfy, whoever built it (a file,
// a fit, an import), in a file of its own.

#include <fmt/format.h>

#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/fields.hpp"
#include "hapticlab/renderer/material.hpp"
#include "material_fields.hpp"

namespace hapticlab::renderer {

void ValidateMaterial(const MaterialModel& m) {
  Diagnostics d;
  const std::string& f = m.source_path;
  // Every number within the range the file's field tables declare (docs/formats.md).
  fields::CheckFields(internal::ContactFields(), m.contact, "contact", f, &d);
  fields::CheckFields(internal::FrictionFields(), m.friction, "friction", f, &d);
  fields::CheckFields(internal::HybridFields(), m, "hybrid", f, &d);
  const auto& b = m.vibration;
  if (!b.empty()) {
    fields::CheckFields(internal::VibrationFields(), b, "vibration", f, &d);
    for (std::size_t i = 0; i < b.cells.size(); ++i)
      fields::CheckFields(internal::CellFields(), b.cells[i], fmt::format("vibration.cells[{}]", i),
                          f, &d);
    if (!(b.max_speed_mps == 0 || b.max_speed_mps > kSaturationMarginSpeed_mps))
      d.Add(f, 0, "vibration.max_speed_mps",
            fmt::format("must be 0 (no limit) or > {:g}", kSaturationMarginSpeed_mps));
    if (!(b.max_force_N == 0 || b.max_force_N > kSaturationMarginForce_N))
      d.Add(f, 0, "vibration.max_force_N",
            fmt::format("must be 0 (no limit) or > {:g}", kSaturationMarginForce_N));
    const std::size_t p = b.cells[0].coeffs.size();
    for (std::size_t i = 0; i < b.cells.size(); ++i) {
      if (b.cells[i].coeffs.size() != p)
        d.Add(
            f, 0, fmt::format("vibration.cells[{}].ar", i),
            fmt::format("order {} differs from the first cell's {}", b.cells[i].coeffs.size(), p));
      if (b.cells[i].ma.size() != b.cells[0].ma.size())
        d.Add(f, 0, fmt::format("vibration.cells[{}].ma", i),
              "MA order differs from the first cell's");
      if (b.cells[i].lsf.size() != b.cells[i].coeffs.size() ||
          b.cells[i].ma_lsf.size() != b.cells[i].ma.size())
        d.Add(f, 0, fmt::format("vibration.cells[{}]", i), "LSFs missing (unstable filter?)");
    }
    const bool grid = !b.grid_speeds_mps.empty() || !b.grid_forces_N.empty();
    if (grid) {
      const auto n = b.grid_speeds_mps.size() * b.grid_forces_N.size();
      if (n != b.cells.size())
        d.Add(f, 0, "vibration.cells",
              fmt::format("a {} x {} grid needs {} cells, found {}", b.grid_speeds_mps.size(),
                          b.grid_forces_N.size(), n, b.cells.size()));
      for (const auto* axis : {&b.grid_speeds_mps, &b.grid_forces_N})
        for (std::size_t i = 1; i < axis->size(); ++i)
          if (!((*axis)[i] > (*axis)[i - 1]))
            d.Add(f, 0, axis == &b.grid_speeds_mps ? "vibration.speeds_mps" : "vibration.forces_N",
                  "grid values must be strictly ascending");
    } else if (b.cells.size() > 1 && b.triangles.empty()) {
      d.Add(f, 0, "vibration.triangles",
            "scattered cells need a triangulation: give triangles, a grid, or at least 3 "
            "non-collinear cells to triangulate");
    }
  }
  d.ThrowIfAny();
}

}  // namespace hapticlab::renderer
