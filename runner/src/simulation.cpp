// The simulated participant (participant.hpp): the simulated hand explores each side on the
// simulated rig (the sample's true pose, a virtual side's surface or a real side's ground
// truth), the simulated observer rates what it felt, and the phase's simulated observer
// answers adaptive trials; with the participant window a person rates instead.

#include <memory>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/sim/falcon_twin.hpp"
#include "hapticlab/sim/psychophysical_observer.hpp"
#include "hapticlab/sim/sim_device.hpp"
#include "participant.hpp"

namespace hapticlab::runner::internal {
namespace {

constexpr double kDropoutS = 0.05;  // an injected link dropout lasts 50 ms

class Simulated final : public Participant {
 public:
  Simulated(sim::SimRig& s, const Lab& lab, const RunOptions& opt, std::uint64_t seed)
      : s_(s),
        lab_(lab),
        p_(*lab.protocol),
        opt_(opt),
        observer_(lab.profiles.observer, DeriveSeed(seed, 0xABCDEF), p_.criteria) {}

  devices::VirtualClock* Clock() const override { return &s_.clock; }
  double PlaybackSpeed() const override { return opt_.ui ? opt_.ui_playback_speed : 1.0; }
  // A simulated participant without screens learns nothing from training.
  bool RendersTraining() const override { return opt_.ui != nullptr; }

  void DrawExploration(Rng& rng, int sides, std::vector<std::uint64_t>* render_seeds) override {
    strokes_.assign(static_cast<std::size_t>(sides), {});
    dropout_at_s_ = -1;
    for (std::size_t k = 0; k < strokes_.size(); ++k) {
      strokes_[k] = k == 0 ? sim::DrawStroke(rng) : sim::JitterStroke(strokes_[0], rng);
      if (render_seeds) render_seeds->push_back(rng.NextU64());
    }
  }

  bool DrawDropout(Rng& rng, double fault_rate, double duration_s) override {
    const bool drop = fault_rate > 0 && rng.Uniform() < fault_rate;
    dropout_at_s_ = drop ? 0.3 * duration_s : -1;
    return drop;
  }

  bool BeginSide(int k, const SideStart& side, Rng& rng) override {
    const renderer::RenderOptions& ro = *side.options;
    const renderer::MaterialModel& model = *side.model;
    double top_m, stiffness;
    truth_.reset();
    if (side.real) {
      const auto& profile = lab_.profiles.profiles.at(p_.FindMaterial(side.material)->profile);
      truth_ = std::make_unique<sim::TruthSample>(profile, rng.NextU64(), ro.vibration_rate_hz);
      top_m = truth_->top_m();
      stiffness = truth_->profile().stiffness_N_per_m;
    } else {
      top_m = model.contact.layer_thickness_m + (model.geometry->max_m() - model.geometry->min_m());
      stiffness = model.contact.texture.K + 0.5 * ro.device_max_stiffness_N_per_m;
    }
    const sim::Stroke stroke = static_cast<std::size_t>(k) < strokes_.size()
                                   ? strokes_[static_cast<std::size_t>(k)]
                                   : sim::Stroke{};
    s_.hand.Begin(stroke, s_.true_device_from_sample[static_cast<std::size_t>(side.sample)], top_m,
                  stiffness, truth_.get(), ro.force_rate_hz, ro.vibration_rate_hz);
    const double dropout_at_s = k == 0 ? dropout_at_s_ : -1;
    if (s_.generic) {
      s_.generic->Reset();
      if (dropout_at_s >= 0) s_.generic->InjectDropout(dropout_at_s, kDropoutS);
    }
    if (s_.twin) {
      s_.twin->BeginRun();
      s_.twin->InjectDropout(dropout_at_s, kDropoutS);
    }
    return dropout_at_s >= 0;
  }

  SideFelt EndSide() override {
    SideFelt f;
    f.hand_ticks = s_.hand.ticks();
    f.felt = s_.hand.Finish();
    truth_.reset();
    return f;
  }

  std::optional<std::vector<db::Rating>> Rate(const db::Trial& t, const TrialScreen& screen,
                                              const std::array<sim::Features, 2>& felt,
                                              Rng& rng) override {
    if (opt_.ui) return RateInWindow(*opt_.ui, screen, p_, ModeOf(opt_).rater.Name());
    if (opt_.on_felt) {
      FeltTrial ft{.plan_index = t.plan_index,
                   .phase = t.phase,
                   .material = t.material,
                   .comparison = t.comparison,
                   .method = t.method,
                   .repetition = t.repetition,
                   .distances = {},
                   .felt = felt};
      for (const auto& c : p_.criteria)
        ft.distances.push_back(observer_.Distance(c, felt[0], felt[1]));
      opt_.on_felt(ft);
    }
    std::vector<db::Rating> out;
    for (const auto& c : p_.criteria)
      out.push_back({c,
                     observer_.Rate(c, t.material, t.method, felt[0], felt[1], p_.scale_min,
                                    p_.scale_max, rng),
                     sim::Observer::ResponseTime(rng), db::kRaterSimulated});
    return out;
  }

  std::optional<AdaptiveAnswer> Answer(const protocols::AdaptiveSpec& spec, double x,
                                       int comparison, const TrialScreen& screen,
                                       Rng& rng) override {
    if (opt_.ui)
      return AnswerInWindow(*opt_.ui, screen, psychophysics::Intervals(spec.task), comparison);
    const auto a = sim::SimulatedAnswer(*spec.simulated_observer, spec.task, x, comparison, rng);
    return AdaptiveAnswer{.positive = a.positive,
                          .response = a.response,
                          .response_time_s = sim::Observer::ResponseTime(rng)};
  }

 private:
  sim::SimRig& s_;
  const Lab& lab_;
  const protocols::Protocol& p_;
  const RunOptions& opt_;
  const sim::Observer observer_;
  std::vector<sim::Stroke> strokes_;
  double dropout_at_s_ = -1;
  std::unique_ptr<sim::TruthSample> truth_;
};

}  // namespace

std::unique_ptr<Participant> MakeSimulatedParticipant(const Rig& rig, const Lab& lab,
                                                      const RunOptions& opt,
                                                      std::uint64_t participant_seed) {
  return std::make_unique<Simulated>(*rig.sim, lab, opt, participant_seed);
}

}  // namespace hapticlab::runner::internal
