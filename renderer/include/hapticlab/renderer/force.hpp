#pragma once
/// @file Force generation: thin texture layer over a stiff base, Dahl friction, and the
/// force-texture algorithms of Table 5.1 (dissertation ch. IV.4, V.1.1).
///
/// Frame and signs: z is the nominal surface normal pointing out of the surface; the base is
/// at z = 0 and the texture layer's top at T(x) = layer_thickness_m + h(x) - min h. Every
/// force is the force the surface exerts on the tool [N]. Penetrations are positive into
/// the surface.
///
///   d_t = 0 (z > T), T - z (0 < z < T), T (z < 0)                       eq. (4.14)
///   F_m = (K_t d_t^n + B_t d_t^n d_t') z_hat  (>= 0)                      eq. (4.11)
///   F_b = K_b d_b z_hat (linear, ch. V) or (K_b d_b^nb + B_b d_b^nb d_b') z_hat, d_b = -z
///   f_n = |F_m + F_b|; F_f = -(F_D + mu_b v_t), F_D the Dahl state          eqs. (4.6)-(4.7)
///   wall, none: F_b' + F_f on a flat surface at z = T_min (no texture)
///   norm:   |F_m| n_t + F_b + F_f        (n_t the texture normal)        Table 5.1, A
///   fric1:  F_m + F_b + (1 - h_norm(x)) F_f                              Table 5.1, B
///   fric2:  F_m + F_b + (1 + sin θ_t) F_f                                Table 5.1, proposed
///
/// The discrete Dahl model is advanced per tick by the exact solution of
/// dF_D/ds = κ (e - F_D / f_C) along the tick's tangential displacement ds e:
///   F_D <- f_C e + (F_D - f_C e) exp(-κ |ds| / f_C),
/// which composes over consecutive ticks to eq. (4.6)'s exp(-κ |x - x0| / f_C) from the
/// last rest point x0, and extends it to 2-D motion and reversals without a reset rule.

#include <Eigen/Core>
#include <cstdint>

#include "hapticlab/core/tool_state.hpp"
#include "hapticlab/renderer/material.hpp"

namespace hapticlab::renderer {

/// Force-texture algorithm (Table 5.1 plus the flat references of the studies).
enum class ForceAlgorithm { kWall, kNorm, kFric1, kFric2, kNone };

/// Parses "wall", "norm", "fric1", "fric2", "none"; throws InputError naming `source` (the
/// file or "<command line>" the name came from) and the field "algorithm" otherwise.
ForceAlgorithm ParseForceAlgorithm(const std::string& name,
                                   const std::string& source = "<command line>");
const char* ToString(ForceAlgorithm a);

/// sin θ_t of the proposed algorithm (our reading, docs/renderer.md): θ_t is the slope angle
/// of the height map along the direction of motion u, so with s = ∇h · u,
/// sin θ_t = s / sqrt(1 + s^2): uphill raises friction, downhill lowers it, flat gives 0.
/// The single place to change for another reading.
double SinThetaT(double dhdx, double dhdy, double ux, double uy) noexcept;

/// Tool state as read from the device (core/tool_state.hpp, shared with devices/).
using hapticlab::ToolState;

/// Result of one force tick.
struct ForceOutput {
  Eigen::Vector3d force_N = Eigen::Vector3d::Zero();  ///< force on the tool [N]
  double normal_force_N = 0;                          ///< f_n = |F_m + F_b| [N]
  double friction_N = 0;                              ///< |F_f| after modulation [N]
  double tangential_speed_mps = 0;                    ///< |v_xy| [m/s]
  double penetration_m = 0;                           ///< d_t + d_b [m]
  bool in_contact = false;
};

/// Stateful force model of one material (the Dahl state and previous position).
/// Step is noexcept, allocation-free and bounded.
class ForceModel {
 public:
  /// @param base_stiffness_N_per_m used when the material's base K is 0 (ch. V: half the
  ///        device's maximum stiffness)
  ForceModel(const MaterialModel& m, ForceAlgorithm algorithm, double base_stiffness_N_per_m);
  void Reset() noexcept;
  ForceOutput Step(const ToolState& s) noexcept;
  ForceAlgorithm algorithm() const { return algorithm_; }

 private:
  ContactParams contact_;
  FrictionParams friction_;
  std::shared_ptr<const HeightMap> geometry_;
  ForceAlgorithm algorithm_;
  Eigen::Vector2d dahl_N_ = Eigen::Vector2d::Zero();  // F_D, along the motion
  Eigen::Vector2d prev_xy_m_ = Eigen::Vector2d::Zero();
  bool had_contact_ = false;
};

/// Hunt-Crossley force K d^n + B d^n d', clamped at zero (a surface never pulls).
inline double HuntCrossleyForce(const HuntCrossleyParams& p, double d_m, double ddot_mps) noexcept;

}  // namespace hapticlab::renderer

#include <cmath>
namespace hapticlab::renderer {
inline double HuntCrossleyForce(const HuntCrossleyParams& p, double d_m, double ddot_mps) noexcept {
  if (!(d_m > 0)) return 0.0;
  const double dn = p.n == 1.0 ? d_m : std::pow(d_m, p.n);
  const double f = p.K * dn + p.B * dn * ddot_mps;
  return f > 0 ? f : 0.0;
}
}  // namespace hapticlab::renderer
