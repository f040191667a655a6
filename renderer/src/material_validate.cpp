// ValidateMaterial: the ranges every material model must satisfy, whoever built it (a file,
// a fit, an import), in a file of its own.

#include <fmt/format.h>

#include <string>
#include <utility>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/renderer/material.hpp"

namespace hapticlab::renderer {

void ValidateMaterial(const MaterialModel& m) {
  Diagnostics d;
  const std::string& f = m.source_path;
  auto hc = [&](const HuntCrossleyParams& p, const std::string& prefix, bool allow_zero_k) {
    if (!(p.K > 0) && !(allow_zero_k && p.K == 0))
      d.Add(f, 0, prefix + "_K", "stiffness must be > 0");
    if (p.B < 0) d.Add(f, 0, prefix + "_B", "damping must be >= 0");
    if (!(p.n >= 1 && p.n <= 2)) d.Add(f, 0, prefix + "_n", "exponent must be in [1, 2]");
  };
  hc(m.contact.texture, "contact.texture", false);
  hc(m.contact.base, "contact.base", true);
  if (m.contact.layer_thickness_m < 0) d.Add(f, 0, "contact.layer_thickness_m", "must be >= 0");
  if (!(m.friction.kappa_N_per_m > 0)) d.Add(f, 0, "friction.kappa_N_per_m", "must be > 0");
  if (!(m.friction.mu_k >= 0)) d.Add(f, 0, "friction.mu_k", "must be >= 0");
  if (!(m.friction.mu_b_Ns_per_m >= 0)) d.Add(f, 0, "friction.mu_b_Ns_per_m", "must be >= 0");
  if (!(m.hybrid_cutoff_hz >= 0))
    d.Add(f, 0, "hybrid.cutoff_hz", "must be >= 0 (0: no hybrid split)");
  // Physical ranges (docs/formats.md, "Bounds"): generous for any real sample, but a typo of
  // 1e100 would otherwise reach the force loop.
  auto at_most = [&](double v, double max, const std::string& field, const char* unit) {
    if (v > max) d.Add(f, 0, field, fmt::format("{:g} is above the {:g} {} allowed", v, max, unit));
  };
  for (const auto& [p, prefix] : {std::pair{&m.contact.texture, "contact.texture"},
                                  std::pair{&m.contact.base, "contact.base"}}) {
    at_most(p->K, 1e12, std::string(prefix) + "_K", "N/m^n");
    at_most(p->B, 1e12, std::string(prefix) + "_B", "N s/m^(n+1)");
  }
  at_most(m.contact.layer_thickness_m, 0.1, "contact.layer_thickness_m", "m");
  at_most(m.friction.kappa_N_per_m, 1e9, "friction.kappa_N_per_m", "N/m");
  at_most(m.friction.mu_k, 10, "friction.mu_k", "");
  at_most(m.friction.mu_b_Ns_per_m, 1e4, "friction.mu_b_Ns_per_m", "Ns/m");
  at_most(m.hybrid_cutoff_hz, 1e5, "hybrid.cutoff_hz", "Hz");
  const auto& b = m.vibration;
  if (!b.empty()) {
    if (!(b.sample_rate_hz > 0 && b.sample_rate_hz <= 1e6))
      d.Add(f, 0, "vibration.sample_rate_hz", "must be in (0, 1e6]");
    if (!(b.min_speed_mps >= 0 && b.min_speed_mps <= 100))
      d.Add(f, 0, "vibration.min_speed_mps", "must be in [0, 100]");
    if (!(b.light_force_N >= 0 && b.light_force_N <= 1e3))
      d.Add(f, 0, "vibration.light_force_N", "must be in [0, 1000] N (0: off)");
    at_most(b.max_speed_mps, 100, "vibration.max_speed_mps", "m/s");
    at_most(b.max_force_N, 1e3, "vibration.max_force_N", "N");
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
