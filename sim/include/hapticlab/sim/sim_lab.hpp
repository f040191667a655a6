#pragma once
/// @file The simulated lab (DESIGN.md §6): ground-truth "real" samples with richer physics
/// than any fitted model, a simulated participant who strokes like people do, and an
/// observer who rates similarity from perceptual features of the two interactions.
///
/// Real sample (truth): analytic geometry (isotropic and directional components, large-scale
/// patches, and micro-roughness below a photometric map's resolution), Hunt-Crossley
/// contact pushing along the true surface normal, friction with a Stribeck peak and a
/// load exponent, and contact vibration = a resonant noise process whose level grows with
/// speed and load plus the acceleration the micro-geometry imposes on the stylus.
/// Placeholder virtual model (the thesis's baseline, derived from the profile until a lab
/// measures its own): the macro geometry sampled at wavelength/20, Hunt-Crossley, Dahl with
/// Coulomb + viscous friction, and a 3 x 3 AR bank fitted to the truth's resonance.
/// The hand, the simulated devices and the truth under the stylus are in sim_device.hpp: every
/// simulated stimulus runs through the real-time engine like a hardware one.
/// Observer: features F = (vibration power in the Pacinian band, force fluctuation,
/// friction ratio, stiffness, large-scale force pattern), all log-scaled where ratios
/// matter; for criterion c, similarity = L + (U - L) exp(-d_c^2 / 2) + bias + noise, with d_c
/// the feature distance in perceptual units. U = 78 and L = 35 are the dissertation's
/// real-real limits, so identical interactions score near 78, clearly different ones near 35.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/renderer/biquad.hpp"
#include "hapticlab/renderer/hybrid.hpp"

namespace hapticlab::sim {

/// Ground-truth description of a material (a "real sample") for the simulated lab.
struct MaterialProfile {
  std::string id;
  double roughness_m = 20e-6;         ///< RMS of the macro geometry [m]
  double wavelength_m = 1e-3;         ///< dominant spatial wavelength [m]
  double anisotropy = 0.3;            ///< 0 isotropic .. 1 directional (weave)
  double inhomogeneity = 0.3;         ///< 0 homogeneous .. 1 patchy at 10 wavelengths
  double micro_roughness_m = 0.3e-6;  ///< fine roughness no map resolves [m]
  double stiffness_N_per_m = 800;     ///< texture layer K [N/m^n]
  double hc_n = 1.2;                  ///< Hunt-Crossley exponent
  double damping = 2;                 ///< Hunt-Crossley B [N s/m^(n+1)]
  double layer_thickness_m = 1e-3;    ///< texture layer over the stiff base [m]
  double mu_k = 0.35;                 ///< kinetic friction coefficient
  double stribeck_ratio = 1.3;        ///< static / kinetic friction (truth only)
  double stribeck_speed_mps = 0.01;   ///< Stribeck decay speed (truth only) [m/s]
  double load_exponent = 0.9;         ///< friction ∝ f_n^exponent (truth only; models assume 1)
  double vibration_rms_mps2 = 1.0;    ///< contact vibration at 8 cm/s and 1.2 N [m/s^2]
  double vibration_peak_hz = 200;     ///< resonance of the contact vibration [Hz]
  double vibration_q = 2;             ///< its quality factor
  int line = 0;
};

/// Per-criterion part of the observer: how strongly the rendered difference moves the rating
/// and the participant's random effects on that criterion (rating points, SD).
struct CriterionObserver {
  double sensitivity = 1;  ///< multiplies the feature distance d_c
  double offset_sd = 4;    ///< participant's offset on this criterion
  double material_sd = 0;  ///< participant x material
  double method_sd = 0;    ///< participant x method
  double noise_sd = 7;     ///< per rating
};

/// Observer-model constants (perceptual scales are in the features' units). Loaded from the
/// [observer] table of the profiles file or, preferably, from the protocol's `observer`
/// file (studies/shin2019/observer.toml; docs/studies.md "The simulated observer").
struct ObserverParams {
  double upper = 78, lower = 35;  ///< dissertation's real-real limits
  double range_sd =
      0;  ///< log-SD of a participant's scale range (x exp(N(0, sd)) about the midpoint)
  double lapse_rate = 0;  ///< probability that a rating is uniform on the scale
  /// Rating points added to every rating: the recording site's effect (`study run
  /// --site-offset`, `study power --site-sd`; never read from an observer file).
  double site_offset = 0;
  CriterionObserver defaults;  ///< every criterion not in `criteria`
  std::map<std::string, CriterionObserver> criteria;
  // Perceptual scales: a feature difference of one scale is one unit of distance d.
  double scale_vibration = 0.25;   ///< log10 vibration power (x1.8 in RMS)
  double scale_fluctuation = 0.3;  ///< log10 force fluctuation (x2)
  double scale_friction = 0.12;    ///< friction ratio
  double scale_stiffness = 0.25;   ///< log10 stiffness (x1.8)
  double scale_pattern = 0.4;      ///< log10 large-scale force pattern (x2.5)
  const CriterionObserver& For(const std::string& criterion) const {
    const auto it = criteria.find(criterion);
    return it == criteria.end() ? defaults : it->second;
  }
};

/// Reads an observer file: an [observer] table (upper, lower, range_sd, lapse_rate, the
/// perceptual scales and the per-criterion defaults) and optional [criterion.NAME] tables.
/// @throws hapticlab::InputError listing every problem (file, line, key)
ObserverParams LoadObserver(const std::string& path);

/// Profiles file: [[profile]] tables and an optional [observer] table (docs/studies.md).
struct ProfileSet {
  std::map<std::string, MaterialProfile> profiles;
  ObserverParams observer;
};
/// @throws hapticlab::InputError listing every problem (file, line, key)
ProfileSet LoadProfiles(const std::string& path);

/// The thesis-style baseline model of a profile (placeholder until measured).
renderer::MaterialModel PlaceholderModel(const MaterialProfile& p);

/// Perceptual features of one interaction.
struct Features {
  double vibration = 0;    ///< log10 RMS acceleration felt in 40-400 Hz [log10 m/s^2]
  double fluctuation = 0;  ///< log10 RMS of force fluctuation above 2 Hz [log10 N]
  double friction = 0;     ///< mean tangential / mean normal force
  double stiffness = 0;    ///< log10 of normal force per penetration [log10 N/m]
  double pattern = 0;      ///< log10 RMS of the 0.3-5 Hz normal-force variation [log10 N]
  double mean_speed_mps = 0, mean_force_N = 0;
};

/// How a participant explores in one stimulus.
struct Stroke {
  double speed_mps = 0.08;    ///< 2-15 cm/s
  double force_N = 1.2;       ///< target load 0.5-2 N
  double direction_rad = 0;   ///< stroke direction on the surface
  double x0_m = 0, y0_m = 0;  ///< where on the sample the stroke starts
  double length_m = 0.04;     ///< back-and-forth excursion (2-4 cm)
};

/// Draws a participant's stroke for one trial (2-15 cm/s, 0.5-2 N, random direction, 2-4 cm
/// long, centred within 5 mm of the sample's origin).
Stroke DrawStroke(Rng& rng);
/// The same participant's stroke on the trial's other stimulus: the same exploration with
/// about 10 % variation in speed and load, elsewhere on the sample.
Stroke JitterStroke(const Stroke& s, Rng& rng);

/// Perceptual features of what a hand felt, accumulated tick by tick (allocation-free): the
/// force the hand felt at the force rate, the acceleration it felt at the vibration rate.
/// The first `settle_s` of a stimulus are ignored (the hand is still finding the surface).
class FeatureAccumulator {
 public:
  FeatureAccumulator() = default;
  FeatureAccumulator(double force_rate_hz, double vibration_rate_hz, double settle_s = 0.25);
  /// One force tick: felt normal and tangential force [N], tangential speed [m/s], and how
  /// deep the stylus is below where it first met resistance [m].
  void AddForce(double normal_N, double tangential_N, double speed_mps,
                double penetration_m) noexcept;
  /// One felt acceleration sample [m/s^2].
  void AddVibration(double acc_mps2) noexcept;
  Features Result() const;
  std::uint64_t force_samples() const { return n_force_; }

 private:
  std::uint64_t skip_f_ = 0, skip_v_ = 0, n_force_ = 0, n_vib_ = 0;
  renderer::Biquad hp_, hpt_, lp_, hpl_, bhp_, blp_;
  double fl2_ = 0, pat2_ = 0, fn_sum_ = 0, ft_sum_ = 0, pen_sum_ = 0, sp_ = 0, v2_ = 0;
  std::uint64_t cnt_ = 0, vcnt_ = 0;
};

/// A simulated participant. Rating on criterion c of a trial (material m, method k):
///   s0 = L + (U - L) exp(-(g_c d_c)^2 / 2)                 latent similarity
///   s  = mid + r (s0 - mid) + o_c + u_cm + v_ck + a + e   mid = scale midpoint
/// with r = exp(N(0, range_sd)) the participant's scale range, o_c, u_cm, v_ck the
/// participant's offset, participant x material and participant x method effects (drawn
/// from the participant's seed, reproducibly per name), a the site's offset
/// (ObserverParams::site_offset) and e the trial noise; with
/// probability lapse_rate the rating is uniform on the scale instead. Clamped to the scale.
/// The per-rating draws come from the caller's generator (seeded per trial and attempt, so a
/// re-run trial after a crash is rated reproducibly).
class Observer {
 public:
  Observer(const ObserverParams& p, std::uint64_t seed, const std::vector<std::string>& criteria);
  /// Similarity of the two interactions on `criterion` (clamped to [lo, hi]).
  double Rate(const std::string& criterion, const std::string& material, const std::string& method,
              const Features& a, const Features& b, double lo, double hi, Rng& noise) const;
  /// The same from a feature distance (Distance()); used by `study power` to re-rate
  /// recorded interactions.
  double RateDistance(const std::string& criterion, const std::string& material,
                      const std::string& method, double d, double lo, double hi, Rng& noise) const;
  /// Time to answer [s] (lognormal around 4 s).
  static double ResponseTime(Rng& noise);
  /// Feature distance for a criterion, in perceptual units (exposed for tests and docs).
  double Distance(const std::string& criterion, const Features& a, const Features& b) const;

 private:
  double Effect(const char* kind, const std::string& criterion, const std::string& level,
                double sd) const;
  ObserverParams p_;
  std::uint64_t seed_ = 0;
  double range_ = 1;
  std::map<std::string, double> offset_;
};

}  // namespace hapticlab::sim
