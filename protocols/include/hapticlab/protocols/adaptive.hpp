#pragma once
/// @file Adaptive phases of a protocol (`kind = "staircase"` or `"quest-plus"`;
/// docs/psychophysics.md): one rendering parameter of one material under one method is varied
/// in a 2AFC, 3AFC or yes/no task. The stimulus variable x of every procedure, fit and report
/// is the comparison's parameter value minus the reference value (`reference`, default 0 in
/// yes/no), in the parameter's unit.

#include <optional>
#include <string>
#include <vector>

#include "hapticlab/psychophysics/psychometric.hpp"
#include "hapticlab/psychophysics/quest_plus.hpp"
#include "hapticlab/psychophysics/simulated_observer.hpp"
#include "hapticlab/psychophysics/staircase.hpp"

namespace hapticlab::protocols {

/// Parameters an adaptive phase may vary, with their unit (as in renderer/material.hpp):
/// vibration.gain (multiplies every AR cell's excitation gain; dimensionless, >= 0),
/// geometry.amplitude_scale (multiplies the height map; dimensionless, >= 0),
/// contact.K (texture-layer Hunt-Crossley stiffness [N/m^n], > 0),
/// friction.mu_k (Coulomb coefficient, dimensionless, >= 0),
/// friction.mu_b_Ns_per_m (viscous coefficient [N s/m], >= 0).
const std::vector<std::string>& AdaptiveParameters();
/// Smallest value a parameter may take (0, or just above 0 for contact.K).
double AdaptiveParameterMin(const std::string& parameter);

struct AdaptiveSpec {
  std::string material;   ///< material id rendered in every interval
  std::string method;     ///< rendering method name
  std::string parameter;  ///< one of AdaptiveParameters()
  psychophysics::Task task = psychophysics::Task::k2Afc;
  double reference = 1;    ///< reference parameter value; x = comparison - reference
  double false_alarm = 0;  ///< yes/no: guess rate used by the fit (dimensionless)
  /// The psychometric function fitted in the report (and QUEST+'s model).
  psychophysics::Shape fit = psychophysics::Shape::kWeibull;
  bool fit_lapse_free = true;  ///< else fixed at fit_lapse
  double fit_lapse = 0;
  /// Performance that defines the JND in the report (default: midway between the guess rate
  /// and 1, i.e. 75 % in 2AFC).
  double jnd_performance = 0.75;
  psychophysics::StaircaseConfig staircase;  ///< kind = "staircase"
  psychophysics::QuestPlusConfig quest;      ///< kind = "quest-plus"
  int quest_trials = 60;                     ///< kind = "quest-plus": trials to run
  /// The simulated observer's truth (`[phase.simulated_observer]`), used with --device sim.
  std::optional<psychophysics::SimulatedObserverParams> simulated_observer;
};

}  // namespace hapticlab::protocols
