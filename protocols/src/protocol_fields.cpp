// The protocol file's declared field tables (core/fields.hpp) and the key tables of
// docs/formats.md printed from them. A key is declared here once: its type, unit, range and
// meaning; protocol.cpp and adaptive.cpp read through these tables.

#include "protocol_fields.hpp"

#include <string>

#include "hapticlab/protocols/protocol_keys.hpp"

namespace hapticlab::protocols {
namespace internal {
namespace {

using fields::Field;
using fields::Type;

template <class S>
using Fields = std::span<const Field<S>>;

}  // namespace

Fields<Protocol> TopLevelFields() {
  static const Field<Protocol> kFields[] = {
      {.key = "study"},         {.key = "material"},      {.key = "method"},
      {.key = "phase"},         {.key = "randomization"}, {.key = "breaks"},
      {.key = "masking_noise"}, {.key = "consent"},       {.key = "analysis"}};
  return kFields;
}

Fields<Protocol> StudyFields() {
  static const Field<Protocol> kFields[] = {
      {.key = "name",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Protocol, name),
       .required = true,
       .doc = "the study's name (database, exports, reports)"},
      {.key = "title",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Protocol, title),
       .doc = "the name in figure titles and headings",
       .default_text = "the name"},
      {.key = "description",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Protocol, description),
       .doc = "free text"},
      {.key = "seed",
       .type = Type::kInteger,
       .ref = HL_FIELD_REF(Protocol, seed),
       .range = {.lo = 0},
       .required = true,
       .doc = "study seed; each participant's seed derives from it"},
      {.key = "criteria",
       .type = Type::kStrings,
       .ref = HL_FIELD_REF(Protocol, criteria),
       .required = true,
       .doc = "what each rated trial asks, at least one"},
      {.key = "scale",
       .type = Type::kCustom,
       .doc = "the rating scale's ends",
       .default_text = "[0, 100]",
       .expected = "[min, max], finite, min < max"},
      {.key = "stimulus_duration_s",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(Protocol, stimulus_duration_s),
       .range = fields::OpenClosed(0, 600),
       .unit = "s",
       .doc = "exploration time per stimulus in a rated trial"},
      {.key = "profiles",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Protocol, profiles),
       .doc = "simulated-lab profiles file, relative to the protocol"},
      {.key = "observer",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Protocol, observer),
       .doc = "simulated observer's file (empty: the profiles' [observer])"},
      {.key = "participant_code",
       .type = Type::kCustom,
       .doc = "pattern every participant code matches whole",
       .default_text = "\"^[A-Z]{1,3}[0-9]{2,4}$\"",
       .expected = "an RE2 regular expression of 1..128 characters"},
  };
  return kFields;
}

Material MaterialDefaults() {
  Material m;
  m.model = "placeholder";
  return m;
}

Fields<Material> MaterialFields() {
  static const Field<Material> kFields[] = {
      {.key = "id",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Material, id),
       .required = true,
       .doc = "the material's name in plans, ratings and reports (unique)"},
      {.key = "sample",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Material, sample),
       .doc = "label of the physical sample the experimenter places",
       .default_text = "the id"},
      {.key = "model",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Material, model),
       .doc = "material model file, relative to the protocol, or \"placeholder\""},
      {.key = "profile",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Material, profile),
       .doc = "simulated-lab profile of the sample",
       .default_text = "the id"},
      {.key = "group",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Material, group),
       .doc = "report grouping of the aggregate tables (\"\": none)"},
  };
  return kFields;
}

Fields<Method> MethodFields() {
  static constexpr std::string_view kAlgorithms = "wall|norm|fric1|fric2|none";
  static const Field<Method> kFields[] = {
      {.key = "name",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Method, name),
       .required = true,
       .doc = "the method's name in plans and reports (unique)"},
      {.key = "algorithm",
       .type = Type::kChoice,
       .ref =
           +[](Method& m, std::size_t i) {
             m.algorithm = std::string(fields::SplitChoices(kAlgorithms)[i]);
           },
       .required = true,
       .doc = "force rendering algorithm",
       .choices = kAlgorithms},
      {.key = "vibration",
       .type = Type::kBool,
       .ref = HL_FIELD_REF(Method, vibration),
       .doc = "play the vibration model"},
      {.key = "hybrid_filter",
       .type = Type::kBool,
       .ref = HL_FIELD_REF(Method, hybrid_filter),
       .doc = "split force and vibration at the model's cutoff"},
  };
  return kFields;
}

Fields<Phase> PhaseFields() {
  static const Field<Phase> kFields[] = {
      {.key = "kind",
       .type = Type::kChoice,
       .ref = +[](Phase& p, std::size_t i) { p.kind = static_cast<PhaseKind>(i); },
       .required = true,
       .doc = "staircase and quest-plus phases have keys of their own (below)",
       .choices = kPhaseKinds},
      {.key = "repetitions",
       .type = Type::kInteger,
       .ref = HL_FIELD_REF(Phase, repetitions),
       .range = {1, 100},
       .doc = "times each trial of the phase is repeated"},
      {.key = "duration_s",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(Phase, duration_s),
       .range = fields::OpenClosed(0, 3600),
       .unit = "s",
       .doc = "training: exploration time per sample"},
      {.key = "method",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Phase, method),
       .doc = "training only: the [[method]] rendering the virtual samples",
       .default_text = "the last [[method]]"},
      {.key = "same_pairs",
       .type = Type::kBool,
       .ref = HL_FIELD_REF(Phase, same_pairs),
       .doc = "reference: each material against itself"},
      {.key = "different_pairs",
       .type = Type::kCustom,
       .doc = "reference: distinct material pairs, drawn by the study seed or listed",
       .default_text = "0",
       .expected = "a count 0..n(n-1)/2, or a list of [\"A\", \"B\"] pairs"},
  };
  return kFields;
}

Fields<Randomization> RandomizationFields() {
  static constexpr std::string_view kSchemes = "full|blocked|latin-square";
  static constexpr std::string_view kBlockBy = "method|material";
  static const Field<Randomization> kFields[] = {
      {.key = "scheme",
       .type = Type::kChoice,
       .ref = +[](Randomization& r, std::size_t i) { r.scheme = static_cast<Scheme>(i); },
       .doc = "order of the main phase's trials",
       .choices = kSchemes,
       .chosen = +[](const Randomization& r) { return static_cast<std::size_t>(r.scheme); }},
      {.key = "block_by",
       .type = Type::kChoice,
       .ref = +[](Randomization& r,
                  std::size_t i) { r.block_by = std::string(fields::SplitChoices(kBlockBy)[i]); },
       .doc = "blocked / latin-square: what a block holds constant",
       .choices = kBlockBy,
       .chosen = +[](const Randomization& r) { return std::size_t{r.block_by != "method"}; }},
      {.key = "no_immediate_repeat",
       .type = Type::kBool,
       .ref = HL_FIELD_REF(Randomization, no_immediate_repeat),
       .doc = "no two consecutive rated trials share a material"},
      {.key = "balance_sides",
       .type = Type::kBool,
       .ref = HL_FIELD_REF(Randomization, balance_sides),
       .doc = "the real sample on the left in half of the trials"},
  };
  return kFields;
}

Fields<Protocol> BreakFields() {
  static const Field<Protocol> kFields[] = {
      {.key = "every_trials",
       .type = Type::kInteger,
       .ref = HL_FIELD_REF(Protocol, break_every_trials),
       .range = {0, 10000},
       .doc = "a break after this many trials (0: no breaks)"},
      {.key = "duration_s",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(Protocol, break_duration_s),
       .range = {0, 3600},
       .unit = "s",
       .doc = "length of each break"},
  };
  return kFields;
}

Fields<Protocol> MaskingFields() {
  static const Field<Protocol> kFields[] = {
      {.key = "enabled",
       .type = Type::kBool,
       .ref = HL_FIELD_REF(Protocol, masking_noise),
       .doc = "play masking noise during stimuli",
       .default_text = "true (the table is given)"},
      // Headphone noise above 100 dB harms hearing within minutes.
      {.key = "level_dB",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(Protocol, masking_level_dB),
       .range = {0, 100},
       .unit = "dB",
       .doc = "noise level"},
  };
  return kFields;
}

Fields<Protocol> ConsentFields() {
  static const Field<Protocol> kFields[] = {
      {.key = "document",
       .type = Type::kCustom,
       .required = true,
       .doc = "the consent document's name or title (not a path)",
       .expected = "one line of 1..256 characters"},
      {.key = "version",
       .type = Type::kCustom,
       .required = true,
       .doc = "its version",
       .expected = "one line of 1..64 characters"},
  };
  return kFields;
}

Fields<Protocol> AnalysisFields() {
  static const Field<Protocol> kFields[] = {
      {.key = "tests",
       .type = Type::kStrings,
       .ref = HL_FIELD_REF(Protocol, analyses),
       .doc = "analyses the report runs (docs/analysis.md)",
       .default_text = "all but lmm"},
      {.key = "lmm_formula",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Protocol, lmm_formula),
       .doc = "the lmm analysis's lme4 formula"},
      {.key = "correction",
       .type = Type::kString,
       .ref = HL_FIELD_REF(Protocol, correction),
       .doc = "sphericity correction: \"GG\", \"HF\" or \"none\""},
  };
  return kFields;
}

}  // namespace internal

std::string ProtocolKeyTables() {
  using namespace internal;
  std::string s;
  auto section = [&s](const char* title, const std::string& table) {
    s += std::string("**") + title + "**\n\n" + table + "\n";
  };
  section("[study]", fields::FieldsMarkdown(StudyFields()));
  section("[[material]]", fields::FieldsMarkdown(MaterialFields(), MaterialDefaults()));
  section("[[method]]", fields::FieldsMarkdown(MethodFields()));
  section("[[phase]] (training, reference, main)", fields::FieldsMarkdown(PhaseFields()));
  section("[[phase]] (staircase, quest-plus): both kinds",
          fields::FieldsMarkdown(AdaptiveFields()));
  section("[[phase]] kind = \"staircase\"", fields::FieldsMarkdown(StaircaseFields()));
  section("[[phase]] kind = \"quest-plus\"", fields::FieldsMarkdown(QuestPlusFields()));
  section("[phase.simulated_observer]", fields::FieldsMarkdown(ObserverFields()));
  section("[randomization]", fields::FieldsMarkdown(RandomizationFields()));
  section("[breaks]", fields::FieldsMarkdown(BreakFields()));
  section("[masking_noise]", fields::FieldsMarkdown(MaskingFields()));
  section("[consent] (both keys when the table is given)", fields::FieldsMarkdown(ConsentFields()));
  section("[analysis]", fields::FieldsMarkdown(AnalysisFields()));
  s.pop_back();  // one newline at the end
  return s;
}

}  // namespace hapticlab::protocols
