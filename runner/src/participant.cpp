// The person at the rig (participant.hpp): explores with their own hand and answers in the
// participant window; and the choice, once per session, between the person and the
// simulation.

#include "participant.hpp"

#include <fmt/format.h>

#include <chrono>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"

namespace hapticlab::runner::internal {
namespace {

double SecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

class Person final : public Participant {
 public:
  Person(const protocols::Protocol& p, const RunOptions& opt) : p_(p), opt_(opt) {}
  devices::VirtualClock* Clock() const override { return nullptr; }
  double PlaybackSpeed() const override { return 1.0; }
  bool RendersTraining() const override { return true; }
  void DrawExploration(Rng& rng, int sides, std::vector<std::uint64_t>* render_seeds) override {
    if (render_seeds)
      for (int k = 0; k < sides; ++k) render_seeds->push_back(rng.NextU64());
  }
  bool DrawDropout(Rng&, double, double) override { return false; }
  bool BeginSide(int, const SideStart&, Rng&) override { return false; }
  SideFelt EndSide() override { return {}; }
  std::optional<std::vector<db::Rating>> Rate(const db::Trial&, const TrialScreen& screen,
                                              const std::array<sim::Features, 2>&, Rng&) override {
    return RateInWindow(*opt_.ui, screen, p_, ModeOf(opt_).rater.Name());
  }
  std::optional<AdaptiveAnswer> Answer(const protocols::AdaptiveSpec& spec, double, int comparison,
                                       const TrialScreen& screen, Rng&) override {
    return AnswerInWindow(*opt_.ui, screen, psychophysics::Intervals(spec.task), comparison);
  }

 private:
  const protocols::Protocol& p_;
  const RunOptions& opt_;
};

}  // namespace

std::optional<std::vector<db::Rating>> RateInWindow(SessionUi& ui, const TrialScreen& screen,
                                                    const protocols::Protocol& p,
                                                    const std::string& source) {
  const auto shown = std::chrono::steady_clock::now();
  const auto r = ui.Rate(screen);
  if (!r || r->size() != p.criteria.size()) return std::nullopt;
  const double rt = SecondsSince(shown);
  std::vector<db::Rating> out;
  for (std::size_t i = 0; i < p.criteria.size(); ++i)
    out.push_back({p.criteria[i], ScaleValue((*r)[i], p.scale_min, p.scale_max), rt, source});
  return out;
}

std::optional<AdaptiveAnswer> AnswerInWindow(SessionUi& ui, const TrialScreen& screen,
                                             int intervals, int comparison) {
  const auto asked = std::chrono::steady_clock::now();
  const auto choice = ui.Choose(screen);
  if (!choice || *choice < 0 || *choice >= static_cast<int>(screen.answers.size()))
    return std::nullopt;
  AdaptiveAnswer a;
  a.response_time_s = SecondsSince(asked);
  a.positive = intervals == 1 ? *choice == 0 : *choice == comparison;
  a.response = intervals == 1 ? (*choice == 0 ? 1 : 0) : *choice;
  return a;
}

std::unique_ptr<Participant> MakeParticipant(const Rig& rig, const Lab& lab, const RunOptions& opt,
                                             std::uint64_t participant_seed) {
  if (rig.sim) return MakeSimulatedParticipant(rig, lab, opt, participant_seed);
  HL_REQUIRE(opt.ui != nullptr,
             "a hardware session needs RunOptions::ui (the participant window gives the ratings)");
  return std::make_unique<Person>(*lab.protocol, opt);
}

void CheckAdaptivePhases(const protocols::Protocol& p, const std::string& device, bool with_ui) {
  Diagnostics d;
  for (std::size_t i = 0; i < p.phases.size(); ++i) {
    const auto& ph = p.phases[i];
    if (!ph.adaptive) continue;
    if (!IsSimulatedBackend(device))
      d.Add(
          p.file, ph.line, fmt::format("phase[{}].kind", i),
          "adaptive phases run on a simulated device (" + SimulatedBackendList() +
              ") in this build "
              "(on a hardware device the participant's answers are not wired up and checked yet)");
    else if (!ph.adaptive->simulated_observer && !with_ui)
      d.Add(p.file, ph.line, fmt::format("phase[{}].simulated_observer", i),
            "missing; a simulated rig without the participant window needs the observer's true "
            "psychometric function "
            "on the varied parameter");
  }
  d.ThrowIfAny();
}

}  // namespace hapticlab::runner::internal
