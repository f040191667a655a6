#pragma once
/// @file Study protocols (TOML; format in docs/studies.md): what a study shows, in which
/// order, what participants rate, and which analyses run afterwards. Parsing reports every
/// problem at once with file, line and key; planning is deterministic from the protocol, the
/// study seed and the participant index.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hapticlab/core/phase_kind.hpp"
#include "hapticlab/protocols/adaptive.hpp"

namespace hapticlab::protocols {

/// A material of the study: a physical sample and its virtual model.
struct Material {
  std::string id;       ///< name used in plans, ratings and reports, e.g. "Denim"
  std::string sample;   ///< physical sample label the experimenter places
  std::string model;    ///< virtual model file (relative to the protocol), or "placeholder"
  std::string profile;  ///< simulated-lab ground truth profile (defaults to id)
  /// Report grouping of the aggregate tables, e.g. "inhomogeneous" (Tables 5.4/5.5); "" none.
  std::string group;
  int line = 0;
};

/// A rendering method: force algorithm plus vibration and hybrid-filter switches.
struct Method {
  std::string name;       ///< e.g. "hybrid", "FF", "LPC"
  std::string algorithm;  ///< wall | norm | fric1 | fric2 | none
  bool vibration = true;
  bool hybrid_filter = true;
  int line = 0;
};

/// The phase kinds (core/phase_kind.hpp); ToString gives a kind's name (kPhaseKindNames).
using PhaseKind = hapticlab::PhaseKind;
const char* ToString(PhaseKind k);

struct Phase {
  PhaseKind kind = PhaseKind::kMain;
  int repetitions = 1;
  double duration_s = 30;  ///< training: exploration time per sample [s]
  /// training: the method rendering the virtual samples (ch. V.2.1: each virtual sample in
  /// turn); default the last [[method]] (the full one in the dissertation's protocols)
  std::string method;
  bool same_pairs = true;  ///< reference: each material against itself (upper limit)
  int different_pairs =
      0;  ///< reference: distinct material pairs (lower limit), drawn by the study seed
  std::vector<std::pair<std::string, std::string>> explicit_pairs;  ///< or listed
  std::optional<AdaptiveSpec> adaptive;  ///< staircase / quest-plus phases
  int line = 0;
};

enum class Scheme { kFull, kBlocked, kLatinSquare };

struct Randomization {
  Scheme scheme = Scheme::kFull;
  std::string block_by = "method";  ///< blocked / latin-square: "method" or "material"
  bool no_immediate_repeat = true;  ///< no two consecutive rated trials share a material
  bool balance_sides = true;        ///< real on the left in half of the trials (±1)
};

struct Protocol {
  std::string file;  ///< path it was read from
  std::string text;  ///< the protocol file exactly (stored with the study)
  std::string name, description;
  /// `[study] title`: the study's name in figure titles and headings (default: `name`).
  std::string title;
  std::uint64_t seed = 1;  ///< study seed; participants derive theirs from it
  std::vector<std::string> criteria;
  double scale_min = 0, scale_max = 100;
  double stimulus_duration_s = 2.0;  ///< exploration time per stimulus in a rated trial [s]
  std::string profiles;              ///< simulated-lab profiles file (relative to the protocol)
  std::string
      observer;  ///< simulated observer's parameters (relative; empty: the profiles' [observer])
  std::vector<Material> materials;
  std::vector<Method> methods;
  std::vector<Phase> phases;
  Randomization randomization;
  int break_every_trials = 0;  ///< 0: no breaks
  double break_duration_s = 60;
  bool masking_noise = false;
  double masking_level_dB = 70;
  /// Participant codes must match this regular expression (`[study] participant_code`, RE2
  /// syntax, matched whole in linear time); the default allows 1-3 capital letters and 2-4 digits
  /// (P07, AB123).
  std::string participant_code = "^[A-Z]{1,3}[0-9]{2,4}$";
  /// `[consent] document, version`: the consent document participants sign and its version
  /// (a session with a person records the consent confirmed against them; empty: none given,
  /// which only a simulated session accepts). `consent_line`: the table's line (messages).
  std::string consent_document, consent_version;
  int consent_line = 0;
  /// `[analysis] tests`: keywords of the statistical analyses (rm-anova, tukey, lmm, ...).
  /// The stats module's registry decides which exist (stats::CheckAnalyses, run by `study
  /// validate`, `study run` and `analyze`); this module only reads them. `analyses_line`: the
  /// line of `tests` (messages).
  std::vector<std::string> analyses;
  int analyses_line = 0;
  /// `[analysis] lmm_formula`: the linear mixed model of the "lmm" analysis, fitted per
  /// criterion to the main phase's ratings (columns: score, participant, method, material,
  /// comparison, repetition).
  std::string lmm_formula = "score ~ method + (1 | participant) + (1 | material)";
  /// `[analysis] correction`: the sphericity correction (afex's names) whose p decides the
  /// significance of within-subject effects with more than one df: "GG" (default), "HF",
  /// "none" (docs/analysis.md, "One rule for significance").
  std::string correction = "GG";
  const Material* FindMaterial(const std::string& id) const;
  const Method* FindMethod(const std::string& name) const;
};

/// Sizes a protocol may have (docs/formats.md, "Bounds"): larger ones are refused while
/// parsing, before they are planned. A plan is built in O(n log^2 n) for n trials.
inline constexpr std::size_t kMaxMaterials = 1000;
inline constexpr std::size_t kMaxMethods = 100;
inline constexpr std::size_t kMaxPhases = 100;
inline constexpr std::size_t kMaxPlannedTrials = 20000;  ///< per participant, all phases

/// Longest participant-code pattern accepted.
inline constexpr std::size_t kMaxCodePatternBytes = 128;

/// True when `pattern` is usable as a participant code pattern (1..128 characters, a valid
/// RE2 regular expression: ECMAScript's common syntax without back-references or
/// look-arounds); else `why` says what is wrong.
bool ValidCodePattern(const std::string& pattern, std::string* why);
/// True when `code` is 1-32 letters, digits, '-' or '_' matching the protocol's
/// participant_code pattern and passes the database's rule (PseudonymousCodeProblem); when
/// only that rule refuses it, `why` says what it refuses. Builds no message.
bool ParticipantCodeAccepted(const Protocol& p, const std::string& code, std::string* why);
/// Refuses (InputError naming the protocol and --participant) a code ParticipantCodeAccepted
/// does not accept; the message gives an example the pattern accepts when it can build one.
void CheckParticipantCode(const Protocol& p, const std::string& code);

/// Reads and validates a protocol. Throws hapticlab::InputError listing every problem.
Protocol LoadProtocol(const std::string& path);
Protocol ParseProtocol(const std::string& text, const std::string& file);

/// One trial of a participant's plan.
struct PlannedTrial {
  int index = 0;  ///< position in the plan
  PhaseKind phase = PhaseKind::kMain;
  std::string material;
  std::string comparison;  ///< "virtual" (main), the other material (reference), "" (training)
  std::string method;      ///< main phase only
  int repetition = 0;
  std::string left, right;    ///< stimuli on the two squares: "real:<id>" or "virtual:<id>"
  bool rated = true;          ///< training trials are not rated
  bool break_before = false;  ///< a break precedes this trial
};

/// The participant's seed: derived from the study seed and the participant index.
std::uint64_t ParticipantSeed(const Protocol& p, int participant_index);

/// The exact trial list of participant `participant_index` (0-based). Same result on every
/// machine. @throws hapticlab::InputError when the constraints cannot be met (e.g. no
/// immediate repeat with too few materials in a block), naming the phase.
std::vector<PlannedTrial> Plan(const Protocol& p, int participant_index);

}  // namespace hapticlab::protocols
