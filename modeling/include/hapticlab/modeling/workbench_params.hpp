#pragma once
/// @file Workbench names and typed parameters (DESIGN.md §4). The catalogue is data-driven (an
/// effect declares its parameters as ParamSpecs), so a Model stores values by effect and name;
/// code that reads or writes a known parameter goes through the keys declared here once, or
/// through the typed view ContactParameters, never through string literals.

#include <string_view>

namespace hapticlab::modeling::wb {

/// Effect names of the built-in catalogue (effects/*.cpp) that other code refers to, and the
/// core every model has. A new effect needs a line here only when code outside its file names it.
namespace effect {
inline constexpr std::string_view kCore = "core";
inline constexpr std::string_view kCoulomb = "coulomb";
inline constexpr std::string_view kViscous = "viscous";
inline constexpr std::string_view kDahl = "dahl";
inline constexpr std::string_view kStribeck = "stribeck";
inline constexpr std::string_view kAnisotropicFriction = "anisotropic-friction";
inline constexpr std::string_view kLoadDependentFriction = "load-dependent-friction";
inline constexpr std::string_view kPositionDependentFriction = "position-dependent-friction";
inline constexpr std::string_view kHcDamping = "hc-damping";
inline constexpr std::string_view kHcExponent = "hc-exponent";
inline constexpr std::string_view kBaseLayer = "base-layer";
inline constexpr std::string_view kVibrationSpeed = "vibration-speed";
inline constexpr std::string_view kVibrationForce = "vibration-force";
inline constexpr std::string_view kVibrationDirection = "vibration-direction";
}  // namespace effect

/// A parameter of a model: the effect that owns it and its name in the effect's ParamSpecs
/// (and in model files: [workbench.params.<effect>] <name> = value).
struct ParamKey {
  std::string_view effect, name;
};

/// The parameters code reads or writes by name. Units in the comments; the names are part of
/// the model file format and do not change.
namespace key {
/// Normal force at 1 mm penetration [N] (core).
inline constexpr ParamKey kK1mm_N{effect::kCore, "K1mm_N"};
/// Hunt-Crossley exponent n [1].
inline constexpr ParamKey kN{effect::kHcExponent, "n"};
/// Hunt-Crossley damping at 1 mm penetration [N s/m].
inline constexpr ParamKey kB1mm_Ns_per_m{effect::kHcDamping, "B1mm"};
/// Base-layer stiffness [N/m] and the layer's thickness above it [m].
inline constexpr ParamKey kBaseK_N_per_m{effect::kBaseLayer, "K_b"};
inline constexpr ParamKey kLayer_m{effect::kBaseLayer, "t"};
/// Kinetic friction coefficient [1].
inline constexpr ParamKey kMuK{effect::kCoulomb, "mu_k"};
/// Viscous friction coefficient [N s/m].
inline constexpr ParamKey kMuB_Ns_per_m{effect::kViscous, "mu_b"};
/// Dahl pre-sliding stiffness [N/m].
inline constexpr ParamKey kKappa_N_per_m{effect::kDahl, "kappa"};
/// Stribeck excess of static over kinetic coefficient [1] and Stribeck speed [m/s].
inline constexpr ParamKey kStribeckDmu{effect::kStribeck, "dmu_s"};
inline constexpr ParamKey kStribeckSpeed_mps{effect::kStribeck, "v_s"};
/// Load exponent of load-dependent friction [1] (1: Coulomb).
inline constexpr ParamKey kLoadAlpha{effect::kLoadDependentFriction, "alpha"};
/// Anisotropic friction harmonics [1]: cos phi, sin phi, cos 2 phi, sin 2 phi.
inline constexpr ParamKey kAnisotropy[4] = {{effect::kAnisotropicFriction, "a1"},
                                            {effect::kAnisotropicFriction, "b1"},
                                            {effect::kAnisotropicFriction, "a2"},
                                            {effect::kAnisotropicFriction, "b2"}};
/// Bounds of the position-dependent friction's tile grid [m] (fixed, from the data).
inline constexpr ParamKey kTileX0_m{effect::kPositionDependentFriction, "x0"};
inline constexpr ParamKey kTileX1_m{effect::kPositionDependentFriction, "x1"};
inline constexpr ParamKey kTileY0_m{effect::kPositionDependentFriction, "y0"};
inline constexpr ParamKey kTileY1_m{effect::kPositionDependentFriction, "y1"};
}  // namespace key

/// Parameters of the simulator's ground truth (workbench_sim.hpp, Effect::TruthSpecs) that no
/// model parameter shares; the others have their model parameter's key (key::kMuK, ...).
namespace truth_key {
/// Amplitude of the truth's friction field over the surface [1].
inline constexpr ParamKey kTileAmplitude{effect::kPositionDependentFriction, "amplitude"};
/// Vibration power grows as (v / 50 mm/s)^(2 exponent) [1]; resonance at v / wavelength [m].
inline constexpr ParamKey kSpeedExponent{effect::kVibrationSpeed, "exponent"};
inline constexpr ParamKey kWavelength_m{effect::kVibrationSpeed, "wavelength"};
/// Vibration power grows as (f_n / 1 N)^(2 exponent) [1].
inline constexpr ParamKey kForceExponent{effect::kVibrationForce, "exponent"};
/// Vibration power scales by exp(amplitude cos 2 (phi - 0.3 rad)) [1].
inline constexpr ParamKey kDirectionAmplitude{effect::kVibrationDirection, "amplitude"};
}  // namespace truth_key

/// Names of the parameter families an effect numbers ("knot0", "g01", ...).
inline constexpr std::string_view kKnotPrefix = "knot";   ///< vibration-speed/-force knots
inline constexpr std::string_view kLegendrePrefix = "g";  ///< position-dependent "g<j><k>"

/// Vibration coefficient vectors of a model besides the effects' own (effect::kCore holds the
/// per-band intercepts): the range the predicted ln band power is clamped to.
inline constexpr std::string_view kCoefRangeLo = "range_lo";
inline constexpr std::string_view kCoefRangeHi = "range_hi";

struct Model;

/// The thesis's contact model (Hunt-Crossley normal force with Coulomb, viscous and Dahl
/// friction, eqs. 4.6-4.11) as a typed view of a workbench Model. The workbench measures
/// stiffness and damping at 1 mm of penetration d (well conditioned whatever n is):
///   f_n = (d / 1 mm)^n (K1mm_N + B1mm_Ns_per_m d_dot).
/// renderer material.hpp's Hunt-Crossley K [N/m^n] and B [N s/m^(n+1)] write the same law as
/// f_n = d^n (K + B d_dot), so K = K1mm_N / (1e-3 m)^n and B = B1mm_Ns_per_m / (1e-3 m)^n.
struct ContactParameters {
  double K1mm_N = 1;         ///< normal force at 1 mm penetration [N]
  double n = 1;              ///< Hunt-Crossley exponent [1] (1 without hc-exponent)
  double B1mm_Ns_per_m = 0;  ///< damping at 1 mm penetration [N s/m] (0 without hc-damping)
  double mu_k = 0;           ///< kinetic friction coefficient [1] (0 without coulomb)
  double mu_b_Ns_per_m = 0;  ///< viscous coefficient [N s/m] (0 without viscous)
  double kappa_N_per_m = 0;  ///< Dahl stiffness [N/m] (0: no pre-sliding, without dahl)
  /// The values of a model; a parameter whose effect the model lacks keeps the default above
  /// (kappa_N_per_m: `no_dahl_kappa_N_per_m`).
  static ContactParameters From(const Model& m, double no_dahl_kappa_N_per_m = 0);
  /// Writes every value into the model's parameters (whether or not it has the effect).
  void ToModel(Model* m) const;
  /// renderer material.hpp's units (see above).
  double K_N_per_m_pow_n() const;
  double B_Ns_per_m_pow_n_plus_1() const;
};

}  // namespace hapticlab::modeling::wb
