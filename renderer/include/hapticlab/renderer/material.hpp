#pragma once
/// @file Material model: everything the renderer needs to play one texture
/// (DESIGN.md §5, "Material model").

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "hapticlab/renderer/height_map.hpp"
#include "hapticlab/renderer/neural.hpp"

namespace hapticlab::renderer {

/// How the stiff base under the texture layer pushes back (ch. V: linear; eq. 4.15: HC).
enum class BaseModel { kLinear, kHuntCrossley };

/// Hunt-Crossley contact, eq. (4.11): f = K d^n + B d^n d_dot, never pulling (f >= 0).
struct HuntCrossleyParams {
  double K = 1000;  ///< stiffness [N/m^n], > 0
  double B = 0;     ///< damping [N s/m^(n+1)], >= 0
  double n = 1;     ///< exponent (dimensionless), 1 <= n <= 2
};

/// Contact of the texture layer and the base (eqs. 4.13-4.15).
struct ContactParams {
  HuntCrossleyParams texture;  ///< texture layer (K_t, B_t, n_t)
  BaseModel base_model = BaseModel::kLinear;
  HuntCrossleyParams base{0, 0, 1};  ///< base; K = 0 means "half the device's max stiffness"
  double layer_thickness_m = 0;      ///< uniform layer under the height map's lowest point [m]
};

/// Discrete Dahl friction with a viscous term (eqs. 4.6-4.7).
struct FrictionParams {
  double kappa_N_per_m = 2000;  ///< pre-sliding stiffness κ [N/m], > 0
  double mu_k = 0.3;            ///< Coulomb coefficient µ_k (dimensionless), >= 0
  double mu_b_Ns_per_m = 0;     ///< viscous coefficient µ_b [N s/m], >= 0
};

/// One AR model of the vibration bank, identified at one (speed, normal force) condition.
struct ArCell {
  double speed_mps = 0;        ///< scan speed [m/s]
  double force_N = 0;          ///< normal force [N]
  std::vector<double> coeffs;  ///< AR coefficients c_1..c_p (see ar.hpp), dimensionless
  double variance = 0;         ///< excitation (residual) variance [(m/s^2)^2]
  std::vector<double> lsf;     ///< LSFs [rad/sample], filled on load
  /// Optional moving-average part (ARMA models, e.g. the Penn toolkit's 1 kHz variant):
  /// a[k] = sum c_i a[k-i] + gain (e[k] + sum_j ma_j e[k-j]). Empty for pure AR.
  std::vector<double> ma;      ///< MA coefficients b_1..b_q (B(z) = 1 + sum b_j z^-j)
  std::vector<double> ma_lsf;  ///< LSFs of B(z), filled on load
  double gain = 1;             ///< excitation gain (dimensionless)
};

/// How far inside the modelled range a saturated condition is put (the Penn toolkit's
/// 0.01 mm/s and 0.01 N: "slightly inside the convex hull because of rounding errors").
inline constexpr double kSaturationMarginSpeed_mps = 1e-5;
inline constexpr double kSaturationMarginForce_N = 0.01;
/// The force a light load is interpolated at (VibrationBank::light_force_N): the Penn
/// toolkit's 1e-4 N.
inline constexpr double kLightForceAs_N = 1e-4;

/// The AR bank over (speed, normal force). Either a regular grid (`speeds_mps` x `forces_N`,
/// cells row-major with force fastest) or scattered cells with a triangulation.
struct VibrationBank {
  double sample_rate_hz = 2000;  ///< rate the AR models run at [Hz]
  std::vector<ArCell> cells;
  std::vector<double> grid_speeds_mps;        ///< ascending; empty for scattered cells
  std::vector<double> grid_forces_N;          ///< ascending; empty for scattered cells
  std::vector<std::array<int, 3>> triangles;  ///< 0-based cell indices (scattered cells)
  double min_speed_mps = 0.01;                ///< synthesis is off below this speed (1 cm/s)
  /// The modelled range (0: none). Above it the condition saturates just inside, as the Penn
  /// toolkit renders: a speed above max_speed_mps becomes max_speed_mps -
  /// kSaturationMarginSpeed_mps, a force above max_force_N becomes max_force_N -
  /// kSaturationMarginForce_N.
  double max_speed_mps = 0;
  double max_force_N = 0;
  /// The Penn toolkit's light-load rule (0: off): a force below light_force_N (not above
  /// max_force_N) is interpolated as kLightForceAs_N, "essentially zero", near the bank's
  /// force-0 boundary; import-penn sets 0.05 N as the toolkit renders.
  double light_force_N = 0;
  bool empty() const { return cells.empty(); }
  int order() const { return cells.empty() ? 0 : static_cast<int>(cells[0].coeffs.size()); }
};

/// A complete material model.
struct MaterialModel {
  std::string name;
  std::string source_path;           ///< file it was loaded from (for messages)
  std::vector<std::string> effects;  ///< named effects of the workbench catalogue
  ContactParams contact;
  FrictionParams friction;
  std::shared_ptr<const HeightMap> geometry = std::make_shared<HeightMap>(HeightMap::Flat());
  VibrationBank vibration;
  /// f_c of the hybrid filter [Hz] (ch. III.5, V.1.4); 0: no split (force not low-passed,
  /// vibration not high-passed), for models whose vibration carries the whole texture
  double hybrid_cutoff_hz = 100;
  /// Optional neural vibration model (ch. III.3), from `[neural] file = "..."`; when present
  /// the renderer synthesizes with it instead of the AR bank.
  std::shared_ptr<const NeuralModel> neural;
  std::string neural_file;  ///< as written in the file (relative to it)
};

/// Loads and validates a material model TOML file (format in docs/renderer.md). Relative
/// geometry/vibration file paths are resolved against the TOML's directory.
/// @throws hapticlab::InputError listing every problem with file, line and key.
MaterialModel LoadMaterial(const std::string& path);
/// Same from text; `name` is used in messages and as the base for relative paths.
MaterialModel ParseMaterial(const std::string& text, const std::string& name);
/// Validates ranges (K > 0, 1 <= n <= 2, stable AR filters, ...); throws InputError.
void ValidateMaterial(const MaterialModel& m);
/// Serializes a model to TOML (geometry by reference to `geometry_file`, or a flat/none
/// geometry when empty). Round-trips through ParseMaterial.
std::string MaterialToToml(const MaterialModel& m, const std::string& geometry_file = "");

}  // namespace hapticlab::renderer
