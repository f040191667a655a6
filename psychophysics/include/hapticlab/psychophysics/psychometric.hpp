#pragma once
/// @file Psychometric functions and forced-choice tasks (shared by the adaptive procedures,
/// the simulated observer and the fits in stats).
///
/// psi(x) = gamma + (1 - gamma - lambda) F(x; alpha, beta)      [Wichmann & Hill 2001,
/// doi:10.3758/BF03194544; Kingdom & Prins 2016, "Psychophysics", ch. 4]
///   logistic:          F = 1 / (1 + exp(-beta (x - alpha)))          F(alpha) = 0.5
///   cumulative normal: F = Phi(beta (x - alpha))  (beta = 1 / sigma)  F(alpha) = 0.5
///   Weibull (x > 0):   F = 1 - exp(-(x / alpha)^beta)                F(alpha) = 1 - 1/e
/// gamma is the guess rate (1/m in an m-alternative forced choice, the false-alarm rate in
/// yes/no), lambda the lapse rate. Every function is F(eta) of a linear predictor
/// eta = a + b g(x), g(x) = x (logistic, normal) or ln x (Weibull), with b = beta and
/// a = -beta alpha (or -beta ln alpha): the form R's glm fits (tests/data/psychometric/).
/// x is in the unit of the varied parameter (docs/psychophysics.md).

#include <optional>
#include <string>

namespace hapticlab::psychophysics {

enum class Shape { kLogistic, kWeibull, kNormal };
const char* ToString(Shape s);
/// "logistic", "weibull" or "normal"; nullopt otherwise.
std::optional<Shape> ParseShape(const std::string& s);

/// The task a trial asks: which of m intervals holds the comparison (m = 2, 3), or yes/no.
enum class Task { kYesNo, k2Afc, k3Afc };
const char* ToString(Task t);
/// "yes-no", "2afc" or "3afc"; nullopt otherwise.
std::optional<Task> ParseTask(const std::string& s);
/// Number of stimulus intervals a trial presents (1, 2, 3).
int Intervals(Task t);
/// Guess rate of an m-AFC task (1/m); for yes/no the given false-alarm rate.
double GuessRate(Task t, double yes_no_false_alarm = 0);

/// Parameters of psi. alpha and x share the varied parameter's unit; beta is per that unit
/// (logistic, normal) or dimensionless (Weibull).
struct PsychometricParams {
  double threshold = 1;  ///< alpha
  double slope = 1;      ///< beta, > 0 for an increasing function
  double guess = 0;      ///< gamma (dimensionless), 0 <= gamma < 1
  double lapse = 0;      ///< lambda (dimensionless), 0 <= lambda < 1 - gamma
};

/// The predictor transform g(x): x, or ln x for the Weibull (-inf for x <= 0).
double Predictor(Shape s, double x);
/// F(eta), the core as a function of the linear predictor.
double CoreOfEta(Shape s, double eta);
/// dF/d eta.
double CoreDensityOfEta(Shape s, double eta);
/// The inverse of CoreOfEta, for 0 < F < 1.
double EtaOfCore(Shape s, double F);
/// F(x; alpha, beta).
double Core(Shape s, double x, double threshold, double slope);
/// psi(x).
double Psi(Shape s, double x, const PsychometricParams& p);
/// The stimulus at which psi(x) = p (nullopt when p is outside (gamma, 1 - lambda) or slope
/// is 0), e.g. the 75 %-correct point of a 2AFC fit.
std::optional<double> StimulusAt(Shape s, const PsychometricParams& params, double p);

}  // namespace hapticlab::psychophysics
