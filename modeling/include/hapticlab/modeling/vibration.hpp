#pragma once
/// @file Vibration modeling from contact-acceleration recordings (dissertation ch. III.3-III.5,
/// V.1.3; the LPC method of Romano and Culbertson): preprocessing, AR fits by
/// Levinson-Durbin, the spectral error E_s (eq. 3.1), the stationarity cut-off by the
/// augmented Dickey-Fuller test, the AR bank over (speed, force) and its cross-validation.
/// The recordings themselves are read by vibration_recording.hpp.

#include <cstdint>
#include <string>
#include <vector>

#include "hapticlab/modeling/vibration_recording.hpp"
#include "hapticlab/renderer/material.hpp"

namespace hapticlab::modeling {

/// The SoX resampler's recipes: best = very high quality (175 dB), medium = high quality
/// (20-bit, the default), fastest = medium quality (16-bit).
enum class ResampleQuality { kBest, kMedium, kFastest };
/// Rational resampling with the SoX resampler library (libsoxr): linear-phase polyphase
/// filtering, delay compensated.
std::vector<double> Resample(const std::vector<double>& x, double from_hz, double to_hz,
                             ResampleQuality q = ResampleQuality::kMedium);
/// Band-limits to [lo_hz, hi_hz]: 4th-order Butterworth high-pass and low-pass (two biquads
/// each), run forward then backward so there is no phase shift.
std::vector<double> BandLimit(const std::vector<double>& x, double rate_hz, double lo_hz,
                              double hi_hz);

/// Model order selection.
enum class OrderCriterion { kAic, kBic };

struct ArFit {
  std::vector<double> coeffs;  ///< c_1..c_p (renderer convention: a[k] = sum c_i a[k-i] + e)
  double variance = 0;         ///< residual (prediction-error) variance
  int order = 0;
  double criterion = 0;  ///< AIC or BIC of the chosen order
};
/// Autocorrelation-method AR fit by Levinson-Durbin (always minimum phase). `order` > 0 fixes
/// it; 0 chooses 1..max_order by the criterion.
ArFit FitAr(const std::vector<double>& x, int order, int max_order = 30,
            OrderCriterion criterion = OrderCriterion::kAic);

/// E_s (eq. 3.1): RMS(|A| - |B|) / RMS(|A|) over the DFT magnitudes of the measured (A) and
/// synthesized (B) signals, with the spectra smoothed as the thesis plots them: Welch
/// averages of Hann-windowed segments (`segment` samples, 50 % overlap), magnitudes as the
/// square root of the averaged power. Bins from DC to Nyquist; computed with FFTW.
double SpectralError(const std::vector<double>& measured, const std::vector<double>& synthesized,
                     int segment = 512);

/// The smoothed magnitude spectrum E_s compares: Welch average of Hann-windowed segments,
/// sqrt of the averaged power, bins 0..segment/2 (bin k at k rate / segment Hz).
std::vector<double> WelchMagnitude(const std::vector<double>& x, int segment = 512);

struct AdfResult {
  double statistic = 0;      ///< t statistic of gamma in dy = a + gamma y[-1] + sum d_i dy[-i]
  double critical_5pct = 0;  ///< MacKinnon (2010) 5 % critical value, constant, no trend
  int lags = 0;              ///< lag order chosen by AIC
  bool rejects_unit_root = false;
};
/// Augmented Dickey-Fuller test with a constant; lags 0..max_lags chosen by AIC (default
/// max 12 (T/100)^(1/4), Schwert's rule), every order fitted on the same sample from one QR of
/// the largest design.
AdfResult AugmentedDickeyFuller(const std::vector<double>& x, int max_lags = -1);

struct CutoffResult {
  bool found = false;
  double cutoff_hz = 0;  ///< smallest cut-off whose high-passed signal rejects a unit root
  /// The lowest cut-off tried already rejects a unit root: the recording is stationary at every
  /// tested cut-off, and the search range bounds f_c from above only (cutoff_hz is `lo`, a
  /// property of the range, not of the recording).
  bool stationary_at_every_cutoff = false;
  std::size_t samples = 0;  ///< samples the test ran on
  std::vector<std::pair<double, AdfResult>> tried;
};
/// Ch. III.5: high-pass at each cut-off from lo to hi (step) and take the first at which the
/// ADF test rejects a unit root at 5 %. The ADF runs on the first `max_samples` samples (0:
/// the whole recording, the default).
CutoffResult StationarityCutoff(const std::vector<double>& x, double rate_hz, double lo_hz = 50,
                                double hi_hz = 150, double step_hz = 10,
                                std::size_t max_samples = 0);

struct VibrationFitOptions {
  double model_rate_hz = 2000;  ///< 2 kHz in the thesis
  double band_lo_hz = 20;       ///< high-pass of the band limit
  int order = 0;                ///< 0: by the criterion
  int max_order = 30;
  OrderCriterion criterion = OrderCriterion::kAic;
  ResampleQuality resample = ResampleQuality::kMedium;
  int threads = 0;  ///< recordings preprocessed and fitted in parallel; 0: all cores
};
/// Preprocessing of one recording for modeling: resample to the model rate, band-limit.
std::vector<double> Preprocess(const Recording& r, const VibrationFitOptions& o);
/// The AR bank over the recordings' (speed, force) conditions: a regular grid when the
/// conditions form one, otherwise scattered cells with their Delaunay triangulation.
/// Every fit uses the same order (the criterion's choice over all recordings).
renderer::VibrationBank FitVibrationBank(const std::vector<Recording>& recordings,
                                         const VibrationFitOptions& o);

struct CvRow {
  double speed_mps = 0, force_N = 0;
  bool train = false;
  double es = 0;
  std::vector<double> measured_spectrum, synthesized_spectrum;  ///< WelchMagnitude of each
};
struct CvResult {
  std::vector<CvRow> rows;
  double mean_es_train = 0, mean_es_test = 0;
  int order = 0;
};
/// Ch. III.4 cross-validation: fit the bank on the recordings at the training speeds and
/// forces, synthesize every recording's condition with the renderer's interpolation and AR
/// synthesis (seeded), and report E_s per condition.
CvResult CrossValidate(const std::vector<Recording>& recordings,
                       const std::vector<double>& train_speeds_mps,
                       const std::vector<double>& train_forces_N, const VibrationFitOptions& o,
                       std::uint64_t seed = 1);

}  // namespace hapticlab::modeling
