// The declared field tables of adaptive [[phase]] tables (staircase, quest-plus; core/fields.hpp),
// read by adaptive.cpp and printed into docs/formats.md by ProtocolKeyTables().

#include "protocol_fields.hpp"

namespace hapticlab::protocols::internal {
namespace {

using fields::Field;
using fields::Type;
using psychophysics::Shape;
using psychophysics::StepType;
using psychophysics::Task;
template <class S>
using Fields = std::span<const Field<S>>;
constexpr std::string_view kShapes = "logistic|weibull|normal";  // psychophysics::Shape's order

}  // namespace

Fields<AdaptiveSpec> AdaptiveFields() {
  static constexpr Task kTasks[] = {Task::k2Afc, Task::k3Afc, Task::kYesNo};
  static const Field<AdaptiveSpec> kFields[] = {
      {.key = "kind",
       .type = Type::kCustom,
       .required = true,
       .doc = "the adaptive procedure",
       .expected = "staircase or quest-plus"},
      {.key = "material",
       .type = Type::kString,
       .ref = HL_FIELD_REF(AdaptiveSpec, material),
       .required = true,
       .doc = "the [[material]] rendered in every interval"},
      {.key = "method",
       .type = Type::kString,
       .ref = HL_FIELD_REF(AdaptiveSpec, method),
       .required = true,
       .doc = "the [[method]] rendering it"},
      {.key = "parameter",
       .type = Type::kString,
       .ref = HL_FIELD_REF(AdaptiveSpec, parameter),
       .required = true,
       .doc = "vibration.gain, geometry.amplitude_scale, contact.K, friction.mu_k or "
              "friction.mu_b_Ns_per_m"},
      {.key = "task",
       .type = Type::kChoice,
       .ref = +[](AdaptiveSpec& a, std::size_t i) { a.task = kTasks[i]; },
       .doc = "forced choice among 2 or 3 intervals, or yes/no",
       .choices = "2afc|3afc|yes-no",
       .chosen =
           +[](const AdaptiveSpec& a) {
             return static_cast<std::size_t>(a.task == Task::k3Afc    ? 1
                                             : a.task == Task::kYesNo ? 2
                                                                      : 0);
           }},
      {.key = "reference",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(AdaptiveSpec, reference),
       .unit = "the parameter's",
       .doc = "reference value; x = comparison - reference",
       .default_text = "required in m-AFC; yes-no: 0"},
      {.key = "false_alarm",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(AdaptiveSpec, false_alarm),
       .range = fields::ClosedOpen(0, 0.5),
       .doc = "yes-no only: the guess rate the fit assumes"},
      {.key = "fit",
       .type = Type::kChoice,
       .ref = +[](AdaptiveSpec& a, std::size_t i) { a.fit = static_cast<Shape>(i); },
       .doc = "psychometric function of the report's fit (and QUEST+'s model)",
       .choices = kShapes,
       .chosen = +[](const AdaptiveSpec& a) { return static_cast<std::size_t>(a.fit); }},
      {.key = "fit_lapse",
       .type = Type::kCustom,
       .doc = "the fit's lapse rate: free or fixed",
       .default_text = "\"free\"",
       .expected = "\"free\" or a rate in [0, 0.2)"},
      {.key = "jnd_performance",
       .type = Type::kCustom,
       .doc = "performance defining the JND",
       .default_text = "midway between guess rate and 1",
       .expected = "a probability in (guess rate, 1)"},
      {.key = "simulated_observer",
       .type = Type::kCustom,
       .doc = "the simulated observer's truth (--device sim)",
       .default_text = "none",
       .expected = "a table (below)"},
  };
  return kFields;
}

Fields<AdaptiveSpec> StaircaseFields() {
  static const Field<AdaptiveSpec> kFields[] = {
      {.key = "up",
       .type = Type::kInteger,
       .ref = HL_FIELD_REF(AdaptiveSpec, staircase.up),
       .range = {1, 5},
       .doc = "wrong answers in a row before the level goes up"},
      {.key = "down",
       .type = Type::kInteger,
       .ref = HL_FIELD_REF(AdaptiveSpec, staircase.down),
       .range = {1, 5},
       .doc = "right answers in a row before the level goes down"},
      {.key = "step_type",
       .type = Type::kChoice,
       .ref = +[](AdaptiveSpec& a,
                  std::size_t i) { a.staircase.step_type = static_cast<StepType>(i); },
       .doc = "level +- step, or level * / 10^step",
       .choices = "linear|log",
       .chosen =
           +[](const AdaptiveSpec& a) { return static_cast<std::size_t>(a.staircase.step_type); }},
      {.key = "steps",
       .type = Type::kCustom,
       .required = true,
       .doc = "step size after 0, 1, 2, ... reversals (the last one repeats)",
       .expected = "a number or an array of numbers > 0"},
      {.key = "start",
       .type = Type::kCustom,
       .required = true,
       .doc = "start level of each interleaved track",
       .expected = "a number or an array"},
      {.key = "min",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(AdaptiveSpec, staircase.min_level),
       .doc = "lowest level",
       .default_text = "the parameter's minimum (log: 0)"},
      {.key = "max",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(AdaptiveSpec, staircase.max_level),
       .doc = "highest level",
       .default_text = "none"},
      {.key = "reversals",
       .type = Type::kInteger,
       .ref = HL_FIELD_REF(AdaptiveSpec, staircase.max_reversals),
       .range = {1, 1000},
       .doc = "a track stops after this many reversals"},
      {.key = "max_trials",
       .type = Type::kInteger,
       .ref = HL_FIELD_REF(AdaptiveSpec, staircase.max_trials),
       .range = {1, 10000},
       .doc = "... or this many trials"},
      {.key = "discard_reversals",
       .type = Type::kInteger,
       .ref = HL_FIELD_REF(AdaptiveSpec, staircase.discard_reversals),
       .range = {0, 1000},
       .doc = "reversals left out of the estimate (fewer than reversals)"},
  };
  return kFields;
}

Fields<AdaptiveSpec> QuestPlusFields() {
  static const Field<AdaptiveSpec> kFields[] = {
      {.key = "stimuli",
       .type = Type::kCustom,
       .required = true,
       .doc = "the stimulus domain",
       .expected = "numbers, or { from, to, count = 2..1000, spacing = \"linear\"/\"log\" }"},
      {.key = "thresholds",
       .type = Type::kCustom,
       .required = true,
       .doc = "threshold grid",
       .expected = "as stimuli"},
      {.key = "slopes",
       .type = Type::kCustom,
       .required = true,
       .doc = "slope grid (> 0)",
       .expected = "as stimuli"},
      {.key = "lapses",
       .type = Type::kCustom,
       .doc = "lapse-rate grid",
       .default_text = "[0, 0.01, 0.02, 0.04]",
       .expected = "numbers in [0, 0.2)"},
      {.key = "trials",
       .type = Type::kInteger,
       .ref = HL_FIELD_REF(AdaptiveSpec, quest_trials),
       .range = {1, 10000},
       .doc = "trials to run"},
  };
  return kFields;
}

Fields<psychophysics::SimulatedObserverParams> ObserverFields() {
  using O = psychophysics::SimulatedObserverParams;
  static const Field<O> kFields[] = {
      {.key = "function",
       .type = Type::kChoice,
       .ref = +[](O& o, std::size_t i) { o.shape = static_cast<Shape>(i); },
       .doc = "the observer's psychometric function",
       .choices = kShapes,
       .default_text = "the phase's fit"},
      {.key = "threshold",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(O, threshold),
       .required = true,
       .doc = "true threshold (a stimulus difference)"},
      {.key = "slope",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(O, slope),
       .range = fields::Above(0),
       .required = true,
       .doc = "true slope"},
      {.key = "lapse",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(O, lapse),
       .range = fields::ClosedOpen(0, 0.2),
       .doc = "lapse rate"},
  };
  return kFields;
}

}  // namespace hapticlab::protocols::internal
