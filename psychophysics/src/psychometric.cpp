#include "hapticlab/psychophysics/psychometric.hpp"

#include <cmath>
#include <limits>
#include <numbers>

namespace hapticlab::psychophysics {

const char* ToString(Shape s) {
  switch (s) {
    case Shape::kLogistic:
      return "logistic";
    case Shape::kWeibull:
      return "weibull";
    case Shape::kNormal:
      return "normal";
  }
  return "?";
}

std::optional<Shape> ParseShape(const std::string& s) {
  if (s == "logistic") return Shape::kLogistic;
  if (s == "weibull") return Shape::kWeibull;
  if (s == "normal") return Shape::kNormal;
  return std::nullopt;
}

const char* ToString(Task t) {
  switch (t) {
    case Task::kYesNo:
      return "yes-no";
    case Task::k2Afc:
      return "2afc";
    case Task::k3Afc:
      return "3afc";
  }
  return "?";
}

std::optional<Task> ParseTask(const std::string& s) {
  if (s == "yes-no") return Task::kYesNo;
  if (s == "2afc") return Task::k2Afc;
  if (s == "3afc") return Task::k3Afc;
  return std::nullopt;
}

int Intervals(Task t) { return t == Task::kYesNo ? 1 : (t == Task::k2Afc ? 2 : 3); }

double GuessRate(Task t, double yes_no_false_alarm) {
  return t == Task::kYesNo ? yes_no_false_alarm : 1.0 / Intervals(t);
}

double Predictor(Shape s, double x) {
  if (s != Shape::kWeibull) return x;
  return x > 0 ? std::log(x) : -std::numeric_limits<double>::infinity();
}

double CoreOfEta(Shape s, double eta) {
  switch (s) {
    case Shape::kLogistic:
      return 1.0 / (1.0 + std::exp(-eta));
    case Shape::kNormal:
      return 0.5 * std::erfc(-eta / std::numbers::sqrt2);
    case Shape::kWeibull:
      return -std::expm1(-std::exp(eta));
  }
  return 0;
}

double CoreDensityOfEta(Shape s, double eta) {
  switch (s) {
    case Shape::kLogistic: {
      const double F = 1.0 / (1.0 + std::exp(-eta));
      return F * (1 - F);
    }
    case Shape::kNormal:
      return std::exp(-0.5 * eta * eta) / std::sqrt(2 * std::numbers::pi);
    case Shape::kWeibull: {
      if (!std::isfinite(eta)) return 0;
      const double e = std::exp(eta);
      return e * std::exp(-e);
    }
  }
  return 0;
}

double EtaOfCore(Shape s, double F) {
  switch (s) {
    case Shape::kLogistic:
      return std::log(F / (1 - F));
    case Shape::kWeibull:
      return std::log(-std::log1p(-F));
    case Shape::kNormal: {
      // Newton on Phi(eta) = F from a logistic start; Phi is smooth and monotone.
      double eta = std::log(F / (1 - F)) / 1.702;  // logistic approximation of Phi
      for (int i = 0; i < 60; ++i) {
        const double d = (CoreOfEta(s, eta) - F) / CoreDensityOfEta(s, eta);
        eta -= d;
        if (std::abs(d) < 1e-15 * (1 + std::abs(eta))) break;
      }
      return eta;
    }
  }
  return 0;
}

double Core(Shape s, double x, double threshold, double slope) {
  const double eta = slope * (Predictor(s, x) - Predictor(s, threshold));
  if (std::isnan(eta)) return 0;  // Weibull at x <= 0 with slope 0
  return CoreOfEta(s, eta);
}

double Psi(Shape s, double x, const PsychometricParams& p) {
  return p.guess + (1 - p.guess - p.lapse) * Core(s, x, p.threshold, p.slope);
}

std::optional<double> StimulusAt(Shape s, const PsychometricParams& params, double p) {
  const double F = (p - params.guess) / (1 - params.guess - params.lapse);
  if (!(F > 0 && F < 1) || params.slope == 0) return std::nullopt;
  const double g = Predictor(s, params.threshold) + EtaOfCore(s, F) / params.slope;
  return s == Shape::kWeibull ? std::exp(g) : g;
}

}  // namespace hapticlab::psychophysics
