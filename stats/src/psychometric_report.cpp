#include "hapticlab/stats/psychometric_report.hpp"

#include <fmt/format.h>
#include <plplot/plplot.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/psychophysics/staircase.hpp"
#include "hapticlab/stats/psychometric_csv.hpp"

namespace hapticlab::stats {
namespace {

namespace fs = std::filesystem;
using psychophysics::Shape;

std::string Safe(const std::string& s) {
  std::string o;
  for (char c : s) o += std::isalnum(static_cast<unsigned char>(c)) || c == '-' ? c : '_';
  return o;
}

std::string Num(double v) { return std::isfinite(v) ? fmt::format("{:.4g}", v) : "n/a"; }
std::string Ci(const BootstrapInterval& i) {
  return std::isfinite(i.lo) && std::isfinite(i.hi) ? fmt::format("[{:.4g}, {:.4g}]", i.lo, i.hi)
                                                    : "n/a";
}

PsychometricData ToData(const std::vector<AdaptiveAnswer>& a) {
  PsychometricData d;
  for (const auto& x : a) {
    d.x.push_back(x.level);
    d.n.push_back(1);
    d.k.push_back(x.positive ? 1 : 0);
  }
  return PoolByStimulus(d);
}

struct FitRow {
  std::string who;
  int trials = 0;
  PsychometricFit fit;
  PsychometricBootstrap boot;
  double jnd = NAN;
  double staircase = NAN;  // mean of the reversal estimates of the tracks (staircase phases)
};

FitRow FitOne(const std::string& who, const std::vector<AdaptiveAnswer>& a,
              const protocols::AdaptiveSpec& spec, const PsychometricFitOptions& o, int replicates,
              std::uint64_t seed) {
  FitRow r;
  r.who = who;
  r.trials = static_cast<int>(a.size());
  // The same summary as `stats psychometric` (psychometric_csv.hpp).
  auto s = SummarizePsychometric(ToData(a), {.fit = o,
                                             .performances = {},
                                             .jnd_performance = spec.jnd_performance,
                                             .reference = 0,
                                             .replicates = replicates,
                                             .seed = seed,
                                             .level = 0.95});
  r.fit = std::move(s.fit);
  r.boot = std::move(s.boot);
  r.jnd = s.jnd;
  return r;
}

}  // namespace

std::vector<AdaptiveAnswer> AdaptiveAnswers(const std::string& db_path, const std::string& study,
                                            int phase_index) {
  db::Database d(db_path, {.create = false, .read_only = true});
  std::vector<AdaptiveAnswer> out;
  const auto st = d.FindStudy(study);
  if (!st) return out;
  const std::string tag = fmt::format("phase {}:", phase_index);
  for (const auto& p : d.Participants(st->id))
    for (const auto& se : d.Sessions(p.id))
      for (const auto& t : d.Trials(se.id)) {
        if (t.status != db::TrialStatus::kCompleted || t.comparison.rfind(tag, 0) != 0) continue;
        AdaptiveAnswer a{.participant = p.code, .track = t.repetition};
        bool has_level = false, has_correct = false;
        for (const auto& r : d.Ratings(t.id)) {
          if (r.criterion == "level") a.level = r.score, has_level = true;
          if (r.criterion == "correct") a.positive = r.score > 0.5, has_correct = true;
        }
        if (has_level && has_correct) out.push_back(a);
      }
  return out;
}

std::vector<std::string> DrawPsychometricPlot(const PsychometricPlot& p, const std::string& base) {
  HL_REQUIRE(!p.binned.x.empty(), "a psychometric plot needs data");
  const auto [lo_it, hi_it] = std::minmax_element(p.binned.x.begin(), p.binned.x.end());
  double x0 = *lo_it, x1 = *hi_it;
  if (std::isfinite(p.jnd)) x0 = std::min(x0, p.jnd), x1 = std::max(x1, p.jnd);
  const double pad = 0.05 * (x1 - x0 > 0 ? x1 - x0 : 1);
  x0 = p.shape == Shape::kWeibull ? std::max(x0 - pad, 0.0) : x0 - pad;
  x1 += pad;
  int nmax = 1;
  for (int n : p.binned.n) nmax = std::max(nmax, n);
  std::vector<std::string> files;
  for (const auto& [dev, ext] : {std::pair{"svgcairo", ".svg"}, std::pair{"pngcairo", ".png"}}) {
    const std::string file = base + ext;
    plsdev(dev);
    plsfnam(file.c_str());
    plspage(0, 0, 720, 480, 0, 0);
    plscolbg(255, 255, 255);
    plinit();
    plscol0(0, 255, 255, 255);
    plscol0(15, 0, 0, 0);
    plscol0(1, 0, 114, 178);
    plscol0(2, 213, 94, 0);
    pladv(0);
    plvpor(0.12, 0.95, 0.14, 0.9);
    plwind(x0, x1, 0, 1);
    plcol0(15);
    plschr(0, 0.8);
    plbox("bcnst", 0, 0, "bcnstv", 0, 0);
    pllab(p.x_label.c_str(), "proportion positive", p.title.c_str());
    // The fitted curve.
    std::vector<PLFLT> cx, cy;
    for (int i = 0; i <= 200; ++i) {
      const double x = x0 + (x1 - x0) * i / 200.0;
      cx.push_back(x);
      cy.push_back(psychophysics::Psi(p.shape, x, p.fit));
    }
    plcol0(1);
    plwidth(2);
    plline(static_cast<PLINT>(cx.size()), cx.data(), cy.data());
    // The JND: dashed lines to the curve.
    if (std::isfinite(p.jnd)) {
      plcol0(2);
      pllsty(2);
      PLFLT vx[2] = {p.jnd, p.jnd}, vy[2] = {0, p.jnd_performance};
      plline(2, vx, vy);
      PLFLT hx[2] = {x0, p.jnd}, hy[2] = {p.jnd_performance, p.jnd_performance};
      plline(2, hx, hy);
      pllsty(1);
    }
    // The binned data: circles with area proportional to the trial count.
    plcol0(15);
    plwidth(1);
    for (std::size_t i = 0; i < p.binned.x.size(); ++i) {
      PLFLT x = p.binned.x[i], y = static_cast<double>(p.binned.k[i]) / p.binned.n[i];
      plssym(0, 0.6 + 2.4 * std::sqrt(static_cast<double>(p.binned.n[i]) / nmax));
      plpoin(1, &x, &y, 4);
    }
    plend();
    files.push_back(file);
  }
  return files;
}

namespace {

// The CSV of every adaptive phase's fits, opened with its header at the first phase with data.
void OpenFitsCsv(std::ofstream& csv, const std::string& out_dir, const std::string& sid,
                 std::vector<std::string>* files) {
  const std::string path = (fs::path(out_dir) / (sid + "_psychometric.csv")).string();
  csv.open(path);
  if (!csv) throw std::runtime_error(path + ": cannot write");
  files->push_back(path);
  csv << "phase,participant,trials,function,threshold,threshold_lo,threshold_hi,slope,slope_lo,"
         "slope_hi,lapse,"
         "jnd,jnd_lo,jnd_hi,weber,weber_lo,weber_hi,staircase_estimate\n";
}

PsychometricFitOptions FitOptionsOf(const protocols::AdaptiveSpec& a) {
  PsychometricFitOptions o;
  o.shape = a.fit;
  o.guess = psychophysics::GuessRate(a.task, a.false_alarm);
  o.lapse_free = a.fit_lapse_free;
  o.lapse = a.fit_lapse;
  return o;
}

// The phase's heading, what was fitted, and the table's header.
std::string PhaseHeader(std::size_t pi, const protocols::Phase& ph, const PsychometricFitOptions& o,
                        int replicates) {
  const auto& a = *ph.adaptive;
  const bool weber = a.reference > 0;
  const bool staircase = ph.kind == protocols::PhaseKind::kStaircase;
  std::ostringstream md;
  md << fmt::format("\n### Phase {}: {} of `{}` ({} {}, {})\n\n", pi,
                    psychophysics::ToString(a.task), a.parameter, a.material, a.method,
                    protocols::ToString(ph.kind));
  md << fmt::format(
      "Stimulus x = comparison - reference ({} = {}). Fit: {} by maximum likelihood, guess rate "
      "{:.3g} (task), "
      "lapse {}; 95 % parametric-bootstrap intervals ({} replicates). JND = x at {:.1f} % "
      "positive{}.\n\n",
      a.parameter, a.reference, psychophysics::ToString(a.fit), o.guess,
      o.lapse_free ? fmt::format("free in [0, {}]", o.max_lapse)
                   : fmt::format("fixed at {}", o.lapse),
      replicates, 100 * a.jnd_performance, weber ? "; Weber fraction = JND / reference" : "");
  md << "| participant | trials | threshold [95 % CI] | slope [95 % CI] | lapse | JND [95 % CI] |"
     << (weber ? " Weber fraction [95 % CI] |" : "")
     << (staircase ? " staircase (mean of reversals) |" : "") << "\n|---|---|---|---|---|---|"
     << (weber ? "---|" : "") << (staircase ? "---|" : "") << "\n";
  return md.str();
}

// Staircase estimate: the tracks' reversal means, replayed from the record (NaN when none,
// or when the record does not follow this protocol's rules).
double StaircaseEstimate(const psychophysics::StaircaseConfig& spec,
                         const std::vector<AdaptiveAnswer>& v) {
  std::vector<psychophysics::StaircaseTrial> h;
  for (const auto& x : v) h.push_back({x.track, x.level, x.positive});
  try {
    double sum = 0;
    int n = 0;
    for (const auto& t : psychophysics::ReplayStaircase(spec, h)) {
      const double e = psychophysics::TrackEstimate(spec, t);
      if (std::isfinite(e)) sum += e, ++n;
    }
    return n ? sum / n : NAN;
  } catch (const InputError&) {
    return NAN;
  }
}

// One fit per participant, then (with more than one) the pooled fit; each with its own
// bootstrap seed derived from the phase's.
std::vector<FitRow> FitPhase(std::size_t pi, const protocols::Phase& ph,
                             const PsychometricFitOptions& o, int replicates,
                             const std::vector<AdaptiveAnswer>& answers,
                             const std::map<std::string, std::vector<AdaptiveAnswer>>& by) {
  const auto& a = *ph.adaptive;
  std::vector<FitRow> rows;
  std::uint64_t seed = DeriveSeed(0x5EED, pi);
  for (const auto& [who, v] : by) {
    rows.push_back(FitOne(who, v, a, o, replicates, seed = DeriveSeed(seed, 1)));
    if (ph.kind == protocols::PhaseKind::kStaircase)
      rows.back().staircase = StaircaseEstimate(a.staircase, v);
  }
  if (by.size() > 1)
    rows.push_back(FitOne("all (pooled)", answers, a, o, replicates, DeriveSeed(seed, 2)));
  return rows;
}

// One fit's row of the phase's table and of the CSV.
void WriteFitRow(std::size_t pi, const protocols::Phase& ph, const FitRow& r,
                 std::ostringstream& md, std::ofstream& csv) {
  const auto& a = *ph.adaptive;
  const bool weber = a.reference > 0;
  const auto& f = r.fit;
  const BootstrapInterval w{r.boot.jnd.lo / a.reference, r.boot.jnd.hi / a.reference};
  if (!f.usable) {
    md << fmt::format("| {} | {} | fit not usable: {} |\n", r.who, r.trials, f.message);
    return;
  }
  md << fmt::format("| {} | {} | {} {} | {} {} | {} | {} {} |", r.who, r.trials,
                    Num(f.params.threshold), Ci(r.boot.threshold), Num(f.params.slope),
                    Ci(r.boot.slope), Num(f.params.lapse), Num(r.jnd), Ci(r.boot.jnd));
  if (weber) md << fmt::format(" {} {} |", Num(r.jnd / a.reference), Ci(w));
  if (ph.kind == protocols::PhaseKind::kStaircase) md << " " << Num(r.staircase) << " |";
  md << "\n";
  csv << fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", pi, r.who, r.trials,
                     psychophysics::ToString(a.fit), f.params.threshold, r.boot.threshold.lo,
                     r.boot.threshold.hi, f.params.slope, r.boot.slope.lo, r.boot.slope.hi,
                     f.params.lapse, r.jnd, r.boot.jnd.lo, r.boot.jnd.hi,
                     weber ? r.jnd / a.reference : NAN, weber ? w.lo : NAN, weber ? w.hi : NAN,
                     r.staircase);
}

// The simulated observer's truth, when the protocol names one.
std::string ObserverNote(const protocols::AdaptiveSpec& a, const PsychometricFitOptions& o) {
  if (!a.simulated_observer) return "";
  const auto& so = *a.simulated_observer;
  const psychophysics::PsychometricParams truth{so.threshold, so.slope, o.guess, so.lapse};
  const auto true_jnd = psychophysics::Psi(so.shape, 0, truth) < a.jnd_performance
                            ? psychophysics::StimulusAt(so.shape, truth, a.jnd_performance)
                            : std::nullopt;
  return fmt::format(
      "\nSessions run with `--device sim` and no `--ui` answered from the simulated observer: "
      "{} threshold "
      "{}, slope {}, lapse "
      "{}; its true JND is {}{}.\n",
      psychophysics::ToString(so.shape), so.threshold, so.slope, so.lapse,
      true_jnd ? Num(*true_jnd) : "n/a",
      true_jnd && a.reference > 0
          ? fmt::format(" (Weber fraction {})", Num(*true_jnd / a.reference))
          : "");
}

// The figure: the pooled fit over the binned answers of everyone; returns its Markdown.
std::string PhaseFigure(std::size_t pi, const protocols::AdaptiveSpec& a, const FitRow& pooled,
                        const std::vector<AdaptiveAnswer>& answers, const std::string& who,
                        const std::string& base, std::vector<std::string>* files) {
  PsychometricPlot plot;
  plot.title =
      fmt::format("{}: {} {} ({})", a.material, a.parameter, psychophysics::ToString(a.task), who);
  plot.x_label = fmt::format("{} difference from {}", a.parameter, a.reference);
  plot.binned = BinForPlot(ToData(answers));
  plot.shape = a.fit;
  plot.fit = pooled.fit.params;
  plot.jnd = pooled.jnd;
  plot.jnd_performance = a.jnd_performance;
  const auto f = DrawPsychometricPlot(plot, base);
  files->insert(files->end(), f.begin(), f.end());
  return fmt::format("\n![psychometric function, phase {}]({}.png)\n\n", pi,
                     fs::path(base).filename().string()) +
         "The curve is the pooled fit; circles are the answers binned by x (area "
         "proportional to the "
         "trials in the bin); the dashed lines mark the JND.\n";
}

}  // namespace

std::string AdaptiveReport(const std::string& db_path, const std::string& study,
                           const std::string& protocol_toml, const std::string& out_dir,
                           bool figures, std::vector<std::string>* files, int replicates) {
  const auto proto = protocols::ParseProtocol(protocol_toml, "(protocol of " + study + ")");
  std::ostringstream md;
  std::ofstream csv;
  const std::string sid = Safe(study);
  for (std::size_t pi = 0; pi < proto.phases.size(); ++pi) {
    const auto& ph = proto.phases[pi];
    if (!ph.adaptive) continue;
    const auto& a = *ph.adaptive;
    const auto answers = AdaptiveAnswers(db_path, study, static_cast<int>(pi));
    if (answers.empty()) continue;
    if (!csv.is_open()) OpenFitsCsv(csv, out_dir, sid, files);
    const PsychometricFitOptions o = FitOptionsOf(a);
    md << PhaseHeader(pi, ph, o, replicates);
    std::map<std::string, std::vector<AdaptiveAnswer>> by;
    for (const auto& x : answers) by[x.participant].push_back(x);
    const std::vector<FitRow> rows = FitPhase(pi, ph, o, replicates, answers, by);
    for (const auto& r : rows) WriteFitRow(pi, ph, r, md, csv);
    md << ObserverNote(a, o);
    if (figures && rows.back().fit.usable) {
      const std::string base =
          (fs::path(out_dir) / fmt::format("{}_phase{}_psychometric", sid, pi)).string();
      md << PhaseFigure(pi, a, rows.back(), answers,
                        by.size() > 1 ? "all participants" : by.begin()->first, base, files);
    }
  }
  return md.str();
}

}  // namespace hapticlab::stats
