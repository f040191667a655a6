#pragma once
// Who holds the stylus and who answers (private to runner): the one seam between the trial
// code and simulation. The trial code (trial.cpp, stimulus_side.cpp, adaptive_phase.cpp,
// session_queue.cpp) calls a Participant without knowing whether a simulated hand explores
// and a simulated observer rates (a simulated rig, simulation.cpp) or a person at the rig and
// the participant window do. Every draw from a trial's generator goes through here in the
// order the trial code calls, so a simulated session stays a pure function of its seeds.

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/devices/clock.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/psychophysics/simulated_observer.hpp"
#include "hapticlab/renderer/hybrid.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/sim/sim_lab.hpp"
#include "lab.hpp"

namespace hapticlab::runner::internal {

// What one side presents, as the hand needs it.
struct SideStart {
  int sample = 0;        // which sample pose of the rig (0 left, 1 right)
  bool real = false;     // a real sample: the hand touches its ground truth
  std::string material;  // the material's id
  const renderer::MaterialModel* model = nullptr;    // the side's model (a virtual side's height)
  const renderer::RenderOptions* options = nullptr;  // the side's render options (rates, limits)
};

// What the hand did in one side.
struct SideFelt {
  std::uint64_t hand_ticks = 0;  // ticks a simulated hand was stepped
  sim::Features felt;            // what it felt (zero for a person)
};

// An adaptive trial's answer.
struct AdaptiveAnswer {
  bool positive = false;  // correct (forced choice) or yes
  int response = 0;       // chosen interval (0-based), or 1 yes / 0 no
  double response_time_s = 0;
};

class Participant {
 public:
  virtual ~Participant() = default;

  // The engine's clock: a simulation's virtual clock; null: the real clock.
  virtual devices::VirtualClock* Clock() const = 0;
  // How many times faster than the wall clock stimuli and breaks play on screens.
  virtual double PlaybackSpeed() const = 0;
  // False when an unrated (training) side is not worth rendering: nobody learns from it.
  virtual bool RendersTraining() const = 0;

  // Draws from the trial's generator how its `sides` sides are explored (one exploration,
  // the others varied from it); with `render_seeds`, a render seed per side after its draw.
  virtual void DrawExploration(Rng& rng, int sides, std::vector<std::uint64_t>* render_seeds) = 0;
  // Draws whether the link drops out for 50 ms from 30 % into the first side of `duration_s`
  // (probability `fault_rate`; fault injection for tests). True: it will.
  virtual bool DrawDropout(Rng& rng, double fault_rate, double duration_s) = 0;
  // Side `k` of the trial starts (before the engine does); a real side's ground truth is
  // seeded from `rng`. True when a dropout is injected into this side.
  virtual bool BeginSide(int k, const SideStart& side, Rng& rng) = 0;
  // The side has ended (after the engine stopped).
  virtual SideFelt EndSide() = 0;

  // The ratings of planned trial `t` after its sides (felt: what each side's hand felt);
  // nullopt: the experimenter aborted.
  virtual std::optional<std::vector<db::Rating>> Rate(const db::Trial& t, const TrialScreen& screen,
                                                      const std::array<sim::Features, 2>& felt,
                                                      Rng& rng) = 0;
  // The answer to an adaptive trial of `spec` at level `x` whose comparison is interval
  // `comparison` (0-based; yes/no: 0); nullopt: the experimenter aborted.
  virtual std::optional<AdaptiveAnswer> Answer(const protocols::AdaptiveSpec& spec, double x,
                                               int comparison, const TrialScreen& screen,
                                               Rng& rng) = 0;
};

// The participant window: the person's ratings, clamped to the scale's step, with the
// response time from the rating screen's appearance (source: the session's Rater::Name), and
// an adaptive trial's answer; nullopt: the experimenter aborted.
std::optional<std::vector<db::Rating>> RateInWindow(SessionUi& ui, const TrialScreen& screen,
                                                    const protocols::Protocol& p,
                                                    const std::string& source);
std::optional<AdaptiveAnswer> AnswerInWindow(SessionUi& ui, const TrialScreen& screen,
                                             int intervals, int comparison);

// The simulated participant of a session on a simulated rig (simulation.cpp).
// Precondition: rig.sim is set.
std::unique_ptr<Participant> MakeSimulatedParticipant(const Rig& rig, const Lab& lab,
                                                      const RunOptions& opt,
                                                      std::uint64_t participant_seed);

// The participant of a session on `rig`: the simulation's hand and observer on a simulated
// rig (the participant window rating when there is one), else the person at the rig rating
// in the window. Precondition: a hardware rig has RunOptions::ui.
std::unique_ptr<Participant> MakeParticipant(const Rig& rig, const Lab& lab, const RunOptions& opt,
                                             std::uint64_t participant_seed);

// Checks before a session starts that its adaptive phases can run on `device`: a simulated
// back-end (hardware devices are refused); with a participant window the participant
// answers, without one the phase's simulated observer must exist.
// @throws InputError listing every problem
void CheckAdaptivePhases(const protocols::Protocol& p, const std::string& device, bool with_ui);

}  // namespace hapticlab::runner::internal
