#include "hapticlab/renderer/energy.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "hapticlab/core/status.hpp"

namespace hapticlab::renderer {

double ClosedFormEnergyNorm(double k, double a, double l) {
  const double pi = std::numbers::pi;
  return k * a * a / 2.0 +
         k * l * l / (4 * pi * pi) * (1.0 - std::sqrt(l * l + 4 * a * a * pi * pi) / l);
}

EnergyResult ComputeEnergy(const MaterialModel& material, ForceAlgorithm algorithm,
                           double amplitude_m, double wavelength_m, const EnergyPath& path) {
  HL_REQUIRE(amplitude_m > 0 && wavelength_m > 0, "sine amplitude and wavelength must be positive");
  HL_REQUIRE(path.steps >= 10, "energy path needs at least 10 steps per side");
  MaterialModel m = material;
  // h(x) = A + A sin(2 pi x / l) >= 0: the mean surface sits at z = layer + A.
  m.geometry =
      std::make_shared<HeightMap>(HeightMap::Sine(amplitude_m, wavelength_m, amplitude_m, 8192));
  const double z_mean = m.contact.layer_thickness_m + amplitude_m;
  // Keep the base out of reach of path A so only the texture layer acts (as in eq. 5.2).
  ForceModel model(m, algorithm, /*base stiffness*/ 1.0);

  struct P {
    double x, z;
  };
  P corners[4];
  if (path.kind == EnergyPath::Kind::kA) {
    const double q = wavelength_m / 4;
    corners[0] = {0, z_mean};
    corners[1] = {q, z_mean};
    corners[2] = {q, z_mean + amplitude_m};
    corners[3] = {0, z_mean + amplitude_m};
  } else {
    const double top = z_mean;  // h(0) = A: the surface at x = 0
    corners[0] = {0, top};
    corners[1] = {0, top - path.dz_max_m};
    corners[2] = {path.dx_max_m, top - path.dz_max_m};
    corners[3] = {path.dx_max_m, top};
  }
  double work_x = 0, work_z = 0;
  ToolState s;
  // Start at the first corner, at rest.
  s.p_m = {corners[0].x, 0, corners[0].z};
  model.Step(s);
  for (int side = 0; side < 4; ++side) {
    const P a = corners[side], b = corners[(side + 1) % 4];
    const double len = std::hypot(b.x - a.x, b.z - a.z);
    const Eigen::Vector3d dir(len > 0 ? (b.x - a.x) / len : 0, 0, len > 0 ? (b.z - a.z) / len : 0);
    const double h = len / path.steps;
    for (int i = 0; i < path.steps; ++i) {
      // Force at the midpoint of the piece, tool moving along the path.
      const double t = (i + 0.5) / path.steps;
      s.p_m = {a.x + t * (b.x - a.x), 0, a.z + t * (b.z - a.z)};
      s.v_mps = path.speed_mps * dir;
      const ForceOutput f = model.Step(s);
      work_z += f.force_N.z() * dir.z() * h;
      work_x += f.force_N.x() * dir.x() * h;
    }
  }
  EnergyResult r;
  r.energy_J = work_x + work_z;
  r.normal_energy_J = work_z;
  r.tangential_energy_J = work_x;
  const auto& hc = m.contact.texture;
  const bool linear = hc.n == 1.0 && hc.B == 0.0;
  const bool friction_alg =
      algorithm == ForceAlgorithm::kFric1 || algorithm == ForceAlgorithm::kFric2;
  if (algorithm == ForceAlgorithm::kNorm && path.kind == EnergyPath::Kind::kA && linear &&
      m.friction.mu_k == 0.0 && m.friction.mu_b_Ns_per_m == 0.0) {
    r.has_closed_form = true;
    r.closed_form_J = ClosedFormEnergyNorm(hc.K, amplitude_m, wavelength_m);
  }
  const double pi = std::numbers::pi;
  if (path.kind == EnergyPath::Kind::kB) {
    r.bound_J = hc.K * m.friction.mu_k * m.friction.mu_k * path.dx_max_m * path.dz_max_m;
    r.gain_bound_J =
        hc.K * (2 * pi * amplitude_m / wavelength_m) * path.dx_max_m * path.dz_max_m + r.bound_J;
    if (friction_alg && linear) {
      // Normal part on path B: down at x = 0, up at x = dx (T(dx) - T(0) = A sin(2 pi dx / l)).
      r.has_closed_form = true;
      r.closed_form_J =
          hc.K * amplitude_m * std::sin(2 * pi * path.dx_max_m / wavelength_m) * path.dz_max_m;
    }
  }
  return r;
}

}  // namespace hapticlab::renderer
