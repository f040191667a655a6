#pragma once
/// @file Workbench models (DESIGN.md §4): a material model is a set of named physical effects
/// with parameters. Each effect adds terms to one channel:
///  - normal force   f_n = K d^n + B d^n d_dot + extra(d)            (Hunt-Crossley, eq. 4.11)
///  - friction       the surface's tangential force -(F_D + mu_b v), F_D a vector Dahl bristle
///                   whose Coulomb level is f_C = f_n,meas (mu_k S + mu_add)   (eqs. 4.6-4.7)
///  - vibration      log band powers of 0.128 s windows as a linear model in features of the
///                   window's speed, load and direction.
/// Units: see each ParamSpec (unit field); lengths in the normal-force terms are relative to
/// 1 mm of penetration (K1mm_N is the force at 1 mm, not renderer material.hpp's K [N/m^n]; the
/// conversion is in workbench_params.hpp, ContactParameters). The names other code refers to
/// are declared once in workbench_params.hpp.

#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "hapticlab/core/enum_names.hpp"
#include "hapticlab/modeling/workbench_params.hpp"
#include "hapticlab/modeling/workbench_replay.hpp"

namespace hapticlab::renderer {
struct MaterialModel;
}  // namespace hapticlab::renderer

namespace hapticlab::modeling::wb {

struct VibrationSpectra;  // workbench_vibration.hpp
struct Model;

/// A model's output channels, declared in the order reports list them (by name): a map keyed by
/// Channel iterates as the reports print the channels.
enum class Channel { kFriction, kNormal, kVibration };
inline constexpr EnumTable<Channel, 3> kChannelNames{{{Channel::kFriction, "friction"},
                                                      {Channel::kNormal, "normal_force"},
                                                      {Channel::kVibration, "vibration"}}};
/// NameOf(kChannelNames, c) as a C string: "friction", "normal_force", "vibration".
const char* ChannelName(Channel c);

/// One parameter of an effect. Fitted parameters are optimized (Ceres) within [lo, hi]; fixed
/// ones (e.g. the tile grid's bounds) are set from the data when the effect is added.
struct ParamSpec {
  std::string name, unit;
  double init = 0, lo = -1e300, hi = 1e300;
  double scale = 1;  ///< typical magnitude (the optimizer works on value / scale)
  bool fitted = true;
  std::string doc;
};

/// Per-sample terms of the normal-force channel that effects set:
/// f_n = (d / 1 mm)^n (K + B d_dot) + extra_N, with K the force at 1 mm [N] and B the damping
/// at 1 mm [N s/m] (well-conditioned for fitting whatever n is).
struct NormalTerms {
  double K = 0, n = 1, B = 0, extra_N = 0;
};
/// Per-sample terms of the friction channel: f_C = f_n (mu_k * mu_scale + mu_add);
/// kappa = 0 means no pre-sliding (ideal Coulomb, smoothed over 0.5 mm/s).
struct FrictionTerms {
  double mu_k = 0, mu_scale = 1, mu_add = 0, kappa = 0, mu_b = 0;
};

struct Residuals;

/// One sample of the ground-truth simulator (workbench_sim.hpp) as an effect's truth sees it:
/// the simulated contact's state, noise-free.
struct TruthSample {
  double x_m = 0, y_m = 0;  ///< position in the plane [m]
  double u = 0, w = 0;      ///< x_m, y_m over half the side of the stroked square [1]
  double d_m = 0;           ///< penetration [m]
  double ddot_mps = 0;      ///< penetration rate [m/s] (0 where the static law is inverted)
  double speed_mps = 0;     ///< sliding speed [m/s]
  double dir_rad = 0;       ///< direction of the last motion faster than 1 mm/s [rad]
  double fn_N = 0;          ///< the truth's normal force (0 in the normal channel's own hook) [N]
  double rate_hz = 0;       ///< sample rate [Hz]
};
/// Per-sample terms of the truth's friction: Coulomb level f_C = f_n mu with
/// mu = mu_k mu_scale + dmu_s exp(-(v / v_s)^2) (sim_truth::StribeckFriction), a Dahl bristle
/// of stiffness kappa when kappa > 0 (else Coulomb smoothed over 0.5 mm/s), plus mu_b v.
struct TruthFrictionTerms {
  double mu_k = 0;                   ///< [1]
  double mu_scale = 1;               ///< product of the modulations [1] (starts at the drift)
  double dmu_s = 0;                  ///< [1]
  double stribeck_speed_mps = 1e-3;  ///< v_s [m/s]
  double kappa_N_per_m = 0;          ///< 0: no pre-sliding
  double mu_b_Ns_per_m = 0;          ///< [N s/m]
};
/// Per-sample terms of the truth's vibration: an AR(2) resonance at `resonance_hz` excited
/// with variance `power` [(m/s^2)^2] while sliding in contact.
struct TruthVibrationTerms {
  double resonance_hz = 200;
  double power = 0;  ///< starts at the core's level squared; effects scale it
};

/// What the current model's residuals say about an effect: the pattern as measured, and the
/// cause it would point to. Reports assert the cause only for supported effects.
struct EvidenceNote {
  std::string pattern;       ///< the residual pattern in words with numbers (no causal claim)
  std::string cause;         ///< what the pattern means when the effect is supported
  bool contradicts = false;  ///< the pattern is not the one this effect produces (or is absent)
  std::string Sentence(bool supported) const {
    return supported && !cause.empty() ? pattern + ": " + cause : pattern;
  }
};

/// A physical effect of the catalogue. Implementations live in modeling/src/effects/, one
/// file each, registered by one line in effects/registry.cpp (docs/workbench.md, "Adding an
/// effect"). An effect states its physics twice: for the model (Params, Normal, Friction,
/// VibrationFeatures, fitted to measurements) and for the ground-truth simulator (TruthSpecs
/// and the Truth* hooks, workbench_sim.hpp), written apart so that the simulator's
/// measurements do not test the model against itself.
class Effect {
 public:
  virtual ~Effect() = default;
  virtual std::string_view name() const = 0;
  virtual Channel channel() const = 0;
  /// One paragraph: the physics, the formula, when it matters.
  virtual std::string_view description() const = 0;
  /// Effects this one modifies (e.g. dahl needs coulomb).
  virtual std::vector<std::string_view> requires_effects() const { return {}; }
  /// Its parameters with initial (neutral) values from the data.
  virtual std::vector<ParamSpec> Params(const Replay& r) const = 0;
  virtual void Normal(const double* /*p*/, const Replay::Sample& /*s*/, NormalTerms& /*t*/) const {}
  virtual void Friction(const double* /*p*/, const Replay::Sample& /*s*/,
                        FrictionTerms& /*t*/) const {}
  /// Vibration effects add regression columns for the log band powers.
  virtual int VibrationColumns() const { return 0; }
  virtual void VibrationFeatures(const double* /*p*/, const Replay::Window& /*w*/,
                                 double* /*out*/) const {}
  /// What pattern of the current model's residuals points to this effect, and whether the
  /// residuals show it.
  virtual EvidenceNote Evidence(const Replay& r, const Residuals& res) const = 0;

  // The ground truth (workbench_sim.hpp): the simulator calls the hook of the effect's channel
  // for every sample of a truth that has the effect, with the truth's values of TruthSpecs.
  /// The truth's parameters: name, unit, default (`init`), bounds [lo, hi], doc.
  virtual std::vector<ParamSpec> TruthSpecs() const { return {}; }
  virtual void TruthNormal(const double* /*p*/, const TruthSample& /*s*/,
                           NormalTerms& /*t*/) const {}
  virtual void TruthFriction(const double* /*p*/, const TruthSample& /*s*/,
                             TruthFrictionTerms& /*t*/) const {}
  virtual void TruthVibration(const double* /*p*/, const TruthSample& /*s*/,
                              TruthVibrationTerms& /*t*/) const {}
  /// Writes the truth's values `p` into a model that has this effect (TruthModel; `half_side_m`:
  /// half the side of the stroked square [m]). By default each truth parameter named like one
  /// of the model's sets it.
  virtual void TruthToModel(const double* p, double half_side_m, Model* m) const;
};

/// The catalogue, in a fixed order: the built-in effects (effects/registry.cpp), then those
/// registered. The core ("contact": K and the vibration intercept) is not an entry: every
/// model has it.
const std::vector<std::unique_ptr<Effect>>& Catalogue();
/// Adds an effect after the others for as long as it lives (a plug-in keeps one for the
/// program's life; a test's toy effect is gone after the test). Register before threads use
/// the catalogue. Precondition (HL_REQUIRE): a new name, not the core's.
class EffectRegistration {
 public:
  explicit EffectRegistration(std::unique_ptr<Effect> effect);
  ~EffectRegistration();
  EffectRegistration(const EffectRegistration&) = delete;
  EffectRegistration& operator=(const EffectRegistration&) = delete;

 private:
  std::string name_;
};
/// The entry named `name`, or nullptr.
const Effect* FindEffect(std::string_view name);
/// The thesis's model: coulomb, viscous, dahl, hc-damping, hc-exponent, vibration-speed,
/// vibration-force (Coulomb + viscous + Dahl friction, Hunt-Crossley with damping, AR bank
/// over speed x force).
std::vector<std::string> BaselineEffects();
/// The catalogue's names, comma-separated.
std::string CatalogueNames();
/// Checks user-given effect names. @throws InputError (file `source`, e.g. a model file or
/// "<command line>", and `field`) listing every unknown name and the catalogue.
void RequireKnownEffects(const std::vector<std::string>& names, const std::string& source,
                         const std::string& field);

/// A model: effect names and every parameter's values (fitted and fixed). Vibration
/// coefficients are stored as "coef" (bands x columns, row-major) per vibration effect and
/// under the core; "core" holds K and the intercepts.
struct Model {
  std::string name;
  std::vector<std::string> effects;
  std::map<std::string, std::map<std::string, double>> params;  ///< effect -> name -> value
  std::map<std::string, std::vector<double>> coef;              ///< vibration coefficients
  std::vector<double> band_edges_hz;  ///< bands the vibration coefficients refer to
  /// A vibration model the workbench scores but does not fit (workbench_vibration.hpp): a
  /// material's AR bank or neural model. Used by Predict when the model has no band model; Fit
  /// leaves it as it is. Set by AttachVibrationModel.
  std::shared_ptr<const renderer::MaterialModel> vibration_model;
  /// Its spectra by condition, computed once and shared by the copies of the model (a neural
  /// model's synthesis is costly; diagnose predicts with many copies). Set with vibration_model.
  std::shared_ptr<VibrationSpectra> vibration_spectra;
  bool HasVibration() const { return coef.count(std::string(effect::kCore)) > 0; }
  bool Has(std::string_view e) const;
  /// The value of parameter `k`, or `fallback` when the model holds none (whether or not the
  /// model lists the effect).
  double Get(ParamKey k, double fallback) const;
  /// The value of parameter `k`. Precondition (HL_REQUIRE): the model holds it.
  double At(ParamKey k) const;
  /// Sets parameter `k` (the effect is not added to `effects`).
  void Set(ParamKey k, double value);
};

/// Adds effects (with their dependencies) to a model, initializing their parameters from the
/// data. Precondition (HL_REQUIRE): every name is in the catalogue (RequireKnownEffects).
void AddEffects(Model* m, const std::vector<std::string>& names, const Replay& r);

}  // namespace hapticlab::modeling::wb
