#include "hapticlab/stats/report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <ostream>
#include <set>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/latency_histogram.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/timing.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/descriptive.hpp"
#include "hapticlab/stats/distributions.hpp"
#include "hapticlab/stats/lmm.hpp"
#include "hapticlab/stats/nonparametric.hpp"
#include "hapticlab/stats/plot.hpp"
#include "hapticlab/stats/psychometric_report.hpp"
#include "hapticlab/stats/shapiro.hpp"
#include "hapticlab/stats/tukey.hpp"

namespace hapticlab::stats {
namespace {

namespace fs = std::filesystem;

std::string P(double p) { return p < 0.001 ? "< 0.001" : fmt::format("{:.3f}", p); }
// "p < 0.001" or "p = 0.020", for sentences.
std::string PEq(double p) { return p < 0.001 ? "p < 0.001" : fmt::format("p = {:.3f}", p); }
std::string Stars(double p) { return p < 0.01 ? "**" : p < 0.05 ? "*" : ""; }
std::string Safe(const std::string& s) {
  std::string o;
  for (char c : s) o += std::isalnum(static_cast<unsigned char>(c)) || c == '-' ? c : '_';
  return o;
}

class Writer {
 public:
  explicit Writer(std::string dir) : dir_(std::move(dir)) {}
  std::ofstream Open(const std::string& name) {
    const std::string path = (fs::path(dir_) / name).string();
    files_.push_back(path);
    std::ofstream f(path);
    if (!f) throw std::runtime_error(path + ": cannot write");
    return f;
  }
  void Add(const std::vector<std::string>& f) { files_.insert(files_.end(), f.begin(), f.end()); }
  const std::string& dir() const { return dir_; }
  std::vector<std::string> files_;

 private:
  std::string dir_;
};

// Mean and 95 % CI half-width of participant means (the error bars of Figs. 5.7/5.8).
std::pair<double, double> MeanCi(const LongTable& t) {
  const auto per = t.Average({"participant"});
  if (per.rows() == 0) return {NAN, NAN};
  const auto d = Describe(per.y);
  return {d.mean, d.n > 1 ? d.ci95_hi - d.mean : NAN};
}

// Levels of `present` in the protocol's order (`order`), then any others (sorted).
std::vector<std::string> InProtocolOrder(const std::vector<std::string>& order, const std::vector<std::string>& present) {
  std::vector<std::string> out;
  for (const auto& x : order)
    if (std::find(present.begin(), present.end(), x) != present.end()) out.push_back(x);
  for (const auto& x : present)
    if (std::find(out.begin(), out.end(), x) == out.end()) out.push_back(x);
  return out;
}

// A requested analysis that cannot run says why, in the report (never dropped silently).
void NotRun(std::ostream& md, const std::string& test, const std::string& why) {
  md << "\n*`" << test << "` was requested but not run: " << why << "*\n";
}

// Aggregate tables in the layout of the dissertation's Tables 5.4/5.5: methods as rows in
// protocol order, materials as columns in protocol order, one table per material group.
void AggregateTables(std::ostream& md, std::ostream& agg, const protocols::Protocol& proto, const std::string& crit,
                     const LongTable& cm, const std::vector<std::string>& methods,
                     const std::vector<std::string>& materials, double upper) {
  std::vector<std::string> groups;  // in the order the protocol first names them
  std::map<std::string, std::vector<std::string>> by_group;
  for (const auto& ma : materials) {
    const auto* m = proto.FindMaterial(ma);
    const std::string g = m ? m->group : "";
    if (!by_group.count(g)) groups.push_back(g);
    by_group[g].push_back(ma);
  }
  md << "\nMean " << crit << " similarity (methods x materials, the layout of Tables 5.4/5.5)"
     << (std::isfinite(upper) ? "; in parentheses the ratio to the upper limit" : "") << ":\n";
  for (const auto& g : groups) {
    if (groups.size() > 1 || !g.empty()) md << "\n**" << (g.empty() ? "other" : g) << "**\n";
    md << "\n| method |";
    for (const auto& ma : by_group[g]) md << " " << ma << " |";
    md << "\n|---|";
    for (std::size_t i = 0; i < by_group[g].size(); ++i) md << "---|";
    md << "\n";
    for (const auto& me : methods) {
      md << "| " << me << " |";
      for (const auto& ma : by_group[g]) {
        const auto cell = cm.Where({{"material", ma}, {"method", me}});
        if (cell.rows() == 0) {
          md << " |";
          continue;
        }
        const auto ds = Describe(cell.y);
        const double ratio = std::isfinite(upper) ? ds.mean / upper : NAN;
        md << fmt::format(" {:.2f}{} |", ds.mean, std::isfinite(ratio) ? fmt::format(" ({:.2f})", ratio) : "");
        agg << fmt::format("{},{},{},{},{:.6f},{:.6f},{},{}\n", crit, g, ma, me, ds.mean, ds.sd, ds.n,
                           std::isfinite(ratio) ? fmt::format("{:.6f}", ratio) : "");
      }
      md << "\n";
    }
  }
}

// The rmANOVA table with Mauchly's test beside each effect, and every violated assumption
// said in words with the correction used.
void AnovaTable(std::ostream& md, std::ostream& csv, const RmAnovaResult& a) {
  md << "\nRepeated-measures ANOVA (" << a.subjects.size() << " participants"
     << (a.dropped_subjects.empty() ? "" : fmt::format(", {} dropped for missing cells", a.dropped_subjects.size()))
     << "):\n\n";
  // Every dropped participant named, with the cells it lacks.
  for (std::size_t i = 0; i < a.dropped_subjects.size(); ++i)
    md << "- dropped " << a.dropped_subjects[i] << ": " << a.dropped_reasons[i] << "\n";
  if (!a.dropped_subjects.empty()) md << "\n";
  md << "| factor | df | F | p | partial eta^2 | Mauchly W | p (Mauchly) | GG eps | p (GG) |\n"
        "|---|---|---|---|---|---|---|---|---|\n";
  std::vector<std::string> notes;
  for (const auto& e : a.effects) {
    const bool violated = e.mauchly_defined && e.df1 > 1 && e.mauchly_p < 0.05;
    const double p_used = violated ? e.p_gg : e.p;
    const std::string W = e.between_only || e.df1 <= 1 ? "-" : e.mauchly_defined ? fmt::format("{:.3f}", e.mauchly_W) : "n/a";
    const std::string p_w = e.between_only || e.df1 <= 1 ? "-" : e.mauchly_defined ? P(e.mauchly_p) + (violated ? " (violated)" : "") : "n/a";
    md << fmt::format("| {}{} | {:.0f}, {:.0f} | {} | {} | {:.3f} | {} | {} | {:.3f} | {} |\n", e.effect,
                      p_used < 0.05 ? "*" : "", e.df1, e.df2, e.F < 1e5 ? fmt::format("{:.3f}", e.F) : fmt::format("{:.3g}", e.F),
                      P(e.p), e.pes, W, p_w, e.gg_epsilon, P(e.p_gg));
    csv << fmt::format("{},{},{},{:.10g},{:.10g},{:.10g},{},{},{:.10g},{:.10g},{:.10g},{:.10g}\n", e.effect, e.df1,
                       e.df2, e.F, e.p, e.pes, std::isfinite(e.mauchly_W) ? fmt::format("{:.10g}", e.mauchly_W) : "",
                       std::isfinite(e.mauchly_p) ? fmt::format("{:.10g}", e.mauchly_p) : "", e.gg_epsilon, e.p_gg,
                       e.hf_epsilon, e.p_hf);
    if (violated)
      notes.push_back(fmt::format("**Sphericity violated** for {}: Mauchly's W = {:.3f}, {}. The Greenhouse-Geisser "
                                  "correction is used (epsilon = {:.3f}, corrected {}).",
                                  e.effect, e.mauchly_W, PEq(e.mauchly_p), e.gg_epsilon, PEq(e.p_gg)));
    else if (!e.between_only && e.df1 > 1 && !e.mauchly_defined)
      notes.push_back(fmt::format("Mauchly's test does not exist for {} (more levels than participants - 1); read "
                                  "the Greenhouse-Geisser corrected p.",
                                  e.effect));
  }
  md << "\nSignificant factors (p < 0.05; the Greenhouse-Geisser p where sphericity is violated) are marked by *. "
        "Mauchly's test is shown for factors with more than two levels (with two, sphericity holds trivially).\n";
  for (const auto& n : notes) md << "\n" << n << "\n";
}

}  // namespace

// The methods-section sentence on real-time timing over a study's trial sides (db/timing.hpp):
// achieved rates and lateness percentiles of the merged histograms of each loop.
std::string TimingMethodsSentence(const db::Database& d, std::int64_t study_id) {
  const auto rows = db::StudySideTimings(d, study_id);
  if (rows.empty()) return "No real-time timing was recorded for this study (recorded from schema v6 on).\n";
  std::size_t sides = 0, virt = 0, locked = 0, slack1 = 0, fifo = 0;
  std::string out;
  for (const auto& r : rows)
    if (r.loop == "force") {
      ++sides;
      virt += r.clock == "virtual";
      locked += r.memory_locked;
      slack1 += r.timer_slack_ns == 1;
      fifo += r.priority.rfind("SCHED_FIFO", 0) == 0;
    }
  if (virt == sides)
    return fmt::format("All {} trial sides ran on the simulated rig's virtual clock (stepped in time order, not "
                       "timed): there is no real-time timing to report.\n", sides);
  out = fmt::format("Real-time timing over {} trial sides on the real clock{}:", sides - virt,
                    virt ? fmt::format(" ({} more on a virtual clock are left out)", virt) : "");
  for (const char* loop : {"force", "vibration"}) {
    LatencySummary late;
    double rate = 0, lo = 1e300, hi = 0;
    std::int64_t ticks = 0, misses = 0, underruns = 0, overflows = 0;
    double tick_p99 = 0;
    bool any = false;
    for (const auto& r : rows) {
      if (r.loop != loop || r.clock != "real") continue;
      LatencySummary h;
      if (!h.ParseSparse(r.late_histogram, r.late_max_us * 1e-6))
        throw InputError(d.path(), 0, "side_timing.late_histogram", fmt::format("trial {}: malformed histogram", r.trial_id));
      late.Merge(h);
      any = true;
      rate = r.rate_hz;
      lo = std::min(lo, r.achieved_rate_hz);
      hi = std::max(hi, r.achieved_rate_hz);
      ticks += r.ticks;
      misses += r.deadline_misses;
      underruns += r.audio_underruns;
      overflows += r.recording_overflows;
      tick_p99 = std::max(tick_p99, r.tick_p99_us);
    }
    if (!any) continue;
    out += fmt::format(
        " the {} loop (requested {:.0f} Hz) achieved {:.1f}-{:.1f} Hz per side; its wake-up lateness over {} ticks was "
        "p50 {:.1f} us, p99 {:.1f} us, p99.9 {:.1f} us (max {:.1f} us), with {} deadline misses and a tick duration of "
        "at most {:.1f} us at the 99th percentile of any side",
        loop, rate, lo, hi, ticks, late.Quantile(0.5) * 1e6, late.Quantile(0.99) * 1e6, late.Quantile(0.999) * 1e6,
        late.max_s * 1e6, misses, tick_p99);
    out += std::string(loop) == "force" ? fmt::format(" ({} recording overflows);", overflows)
                                        : fmt::format(" ({} audio underruns).", underruns);
  }
  if (out.back() == ';') out.back() = '.';
  out += fmt::format(" Loop threads: timer slack 1 ns on {} of {} sides, SCHED_FIFO on {}, memory locked on {}.\n",
                     slack1, sides - virt, fifo, locked);
  return out;
}

LongTable RatingsFromDatabase(const std::string& db_path, bool include_simulated, RatingSources* sources) {
  RatingSources local;
  RatingSources& src = sources ? *sources : local;
  // quick_check first: a damaged record is refused, never analysed.
  const db::Database d = db::OpenForReading(db_path);
  LongTable t;
  t.source = db_path;
  t.y_name = "score";
  t.key_names = {"study", "participant", "phase", "material", "comparison", "method", "repetition", "criterion"};
  t.keys.assign(t.key_names.size(), {});
  for (const auto& st : d.Studies()) {
    // Scores are checked against the scale of the protocol the study ran.
    const auto proto = protocols::ParseProtocol(st.protocol_toml, db_path + " (protocol of " + st.name + ")");
    // A human study (any rating by a person) leaves the simulated observer's ratings out.
    bool human = false;
    for (const auto& p : d.Participants(st.id))
      for (const auto& se : d.Sessions(p.id))
        for (const auto& tr : d.Trials(se.id))
          for (const auto& r : d.Ratings(tr.id)) human = human || r.source != db::kRaterSimulated;
    for (const auto& p : d.Participants(st.id))
      for (const auto& se : d.Sessions(p.id))
        for (const auto& tr : d.Trials(se.id))
          for (const auto& r : d.Ratings(tr.id)) {
            if (r.score < proto.scale_min || r.score > proto.scale_max || r.response_time_s < 0)
              throw InputError(db_path, 0, "rating.score",
                               fmt::format("study '{}' trial {} criterion '{}': score {} (response time {} s) is "
                                           "outside the protocol's scale [{}, {}] or negative",
                                           st.name, tr.id, r.criterion, r.score, r.response_time_s, proto.scale_min,
                                           proto.scale_max));
            if (r.source == db::kRaterSimulated) {
              if (human && !include_simulated) {
                ++src.simulated_excluded[st.name];
                continue;
              }
              ++src.simulated_kept[st.name];
            } else {
              ++src.human[st.name];
            }
            const std::string row[] = {st.name, p.code, tr.phase, tr.material, tr.comparison, tr.method,
                                       std::to_string(tr.repetition), r.criterion};
            for (std::size_t c = 0; c < t.key_names.size(); ++c) t.keys[c].push_back(row[c]);
            t.y.push_back(r.score);
          }
  }
  return t;
}

ReportResult Analyze(const std::string& db_path, const ReportOptions& o) {
  RatingSources sources;
  const LongTable all = RatingsFromDatabase(db_path, o.include_simulated, &sources);
  if (all.rows() == 0) throw InputError(db_path, 0, "", "the database holds no ratings yet");
  fs::create_directories(o.out_dir);
  Writer w(o.out_dir);
  ReportResult res;
  db::Database d(db_path, {.create = false, .read_only = true});
  auto md = w.Open("report.md");
  md << "# HapticLab analysis report\n\nDatabase: `" << db_path << "`\n\n"
     << "Scores are similarity ratings on the protocol's scale. Repetitions are averaged per participant x cell "
        "before repeated-measures ANOVA (as afex does). Tukey comparisons of a within-subject factor use the pooled "
        "error of its effect (emmeans `model = \"univariate\"`). Error bars are 95 % confidence intervals of "
        "participant means. Outliers (1.5 IQR, Tukey's hinges) are counted, not removed.\n";
  for (const auto& st : d.Studies()) {
    const auto proto = protocols::ParseProtocol(st.protocol_toml, "(protocol of " + st.name + ")");
    const std::set<std::string> tests(proto.analyses.begin(), proto.analyses.end());
    const auto study = all.Where({{"study", st.name}});
    if (study.rows() == 0) continue;
    res.studies.push_back(st.name);
    const std::string sid = Safe(st.name);
    md << "\n## Study `" << st.name << "`\n\n" << proto.description << "\n\n"
       << "Participants: " << study.Levels("participant").size() << "; ratings: " << study.rows() << "\n";
    {
      // Where the ratings came from: a person's input device or the simulated observer.
      const auto count = [&](const std::map<std::string, std::size_t>& m) {
        const auto it = m.find(st.name);
        return it == m.end() ? std::size_t{0} : it->second;
      };
      const std::size_t human = count(sources.human), kept = count(sources.simulated_kept),
                        excluded = count(sources.simulated_excluded);
      if (excluded)
        md << "\n**Simulated ratings excluded:** " << excluded << " ratings of the simulated observer (sessions or "
           << "parts of sessions run without a person rating) are left out of this study's " << human
           << " ratings by participants; `hapticlab analyze --include-simulated` keeps them.\n";
      else if (kept && human)
        md << "\n**Simulated ratings included** (`--include-simulated`): " << kept << " ratings of the simulated "
           << "observer are analysed together with " << human << " ratings by participants.\n";
      else if (kept)
        md << "\nAll ratings come from the simulated observer (a simulated study).\n";
    }
    md << "\n" << TimingMethodsSentence(d, st.id);
    // Adaptive phases (staircase, QUEST+): psychometric fits, JND and Weber fraction.
    md << AdaptiveReport(db_path, st.name, st.protocol_toml, o.out_dir, o.figures, &w.files_);
    if (study.Where({{"phase", "main"}}).rows() + study.Where({{"phase", "reference"}}).rows() == 0) continue;
    const auto main = study.Where({{"phase", "main"}});
    const auto ref = study.Where({{"phase", "reference"}});
    std::vector<std::string> proto_methods, proto_materials;
    for (const auto& m : proto.methods) proto_methods.push_back(m.name);
    for (const auto& m : proto.materials) proto_materials.push_back(m.id);
    const auto methods = main.rows() ? InProtocolOrder(proto_methods, main.Levels("method")) : std::vector<std::string>{};
    const auto materials =
        main.rows() ? InProtocolOrder(proto_materials, main.Levels("material")) : std::vector<std::string>{};
    // Aggregated score tables for every criterion (Tables 4.1, 5.4, 5.5).
    std::ofstream agg;
    if (tests.count("aggregate")) {
      agg = w.Open(sid + "_aggregate.csv");
      agg << "criterion,group,material,method,mean,sd,n,ratio_to_upper\n";
    }
    for (const auto& crit : proto.criteria) {
      const auto cm = main.Where({{"criterion", crit}});
      md << "\n### " << crit << "\n";
      // Real-real limits from the reference phase.
      double upper = NAN, lower = NAN;
      LongTable same, diff;
      if (ref.rows()) {
        const auto rc = ref.Where({{"criterion", crit}});
        same = rc;
        same.keys.assign(rc.key_names.size(), {});
        same.y.clear();
        diff = same;
        for (std::size_t i = 0; i < rc.rows(); ++i) {
          auto& dst = rc.keys[rc.Key("material")][i] == rc.keys[rc.Key("comparison")][i] ? same : diff;
          for (std::size_t c = 0; c < rc.key_names.size(); ++c) dst.keys[c].push_back(rc.keys[c][i]);
          dst.y.push_back(rc.y[i]);
        }
        if (same.rows()) upper = Describe(same.y).mean;
        if (diff.rows()) lower = Describe(diff.y).mean;
        md << fmt::format("\nReal-real limits: upper {:.2f} (same material, n = {}), lower {:.2f} (different "
                          "materials, n = {}).\n",
                          upper, same.rows(), lower, diff.rows());
      }
      if (cm.rows() == 0) {
        md << "\nNo main-phase ratings of " << crit << " yet: the aggregate table, ANOVA, Tukey, grouping, "
           << "Kruskal-Wallis and Shapiro-Wilk analyses need them.\n";
        continue;
      }
      if (tests.count("aggregate")) AggregateTables(md, agg, proto, crit, cm, methods, materials, upper);
      // Repeated-measures ANOVA (Tables 5.2, 5.3); Tukey needs its error term.
      std::vector<std::string> within;
      if (methods.size() >= 2) within.push_back("method");
      if (materials.size() >= 2) within.push_back("material");
      const auto cells = cm.Average({"participant", "method", "material"});
      const std::size_t n_participants = cm.Levels("participant").size();
      std::optional<RmAnovaResult> anova;
      std::string anova_why;
      if (tests.count("rm-anova") || tests.count("tukey")) {
        if (within.empty())
          anova_why = "it needs a within factor with two or more levels (this study has one method and one material)";
        else if (n_participants < 2)
          anova_why = fmt::format("it needs two or more participants ({} so far)", n_participants);
        else
          try {
            anova = RmAnova(cm, "participant", within);
          } catch (const InputError& e) {
            anova_why = e.what();
          }
      }
      if (tests.count("rm-anova")) {
        if (anova) {
          auto csv = w.Open(fmt::format("{}_{}_rmanova.csv", sid, Safe(crit)));
          csv << "effect,df1,df2,F,p,pes,mauchly_W,mauchly_p,gg_epsilon,p_gg,hf_epsilon,p_hf\n";
          AnovaTable(md, csv, *anova);
        } else {
          NotRun(md, "rm-anova", anova_why);
        }
      }
      // Tukey on method + the bar chart of Figs. 5.7/5.8.
      if (tests.count("tukey")) {
        if (methods.size() < 2) {
          NotRun(md, "tukey", fmt::format("it compares methods and this study has {} method", methods.size()));
        } else if (!anova) {
          NotRun(md, "tukey", "it uses the repeated-measures ANOVA's error term, which could not be computed: " + anova_why);
        } else {
          const auto tk = TukeyWithin(*anova, "method", false);
          auto tcsv = w.Open(fmt::format("{}_{}_tukey.csv", sid, Safe(crit)));
          tcsv << "a,b,diff,lwr,upr,p_adj\n";
          md << "\nTukey HSD on method (univariate error of the method effect, df = " << tk.df << "):\n\n"
             << "| pair | diff | 95 % CI | p adj |\n|---|---|---|---|\n";
          BarChart bc;
          bc.title = fmt::format("{}: {} similarity", st.name, crit);
          bc.x_label = "rendering method";
          bc.y_label = crit + " similarity";
          bc.error_label = "95% CI";
          bc.groups = {""};
          for (const auto& me : methods) {
            const auto [m, ci] = MeanCi(cm.Where({{"method", me}}));
            bc.series.push_back({me, {m}, {ci}});
          }
          for (const auto& pr : tk.pairs) {
            md << fmt::format("| {} - {} | {:.2f} | [{:.2f}, {:.2f}] | {}{} |\n", pr.a, pr.b, pr.diff, pr.lwr, pr.upr,
                              P(pr.p_adj), Stars(pr.p_adj));
            tcsv << fmt::format("{},{},{:.10g},{:.10g},{:.10g},{:.10g}\n", pr.a, pr.b, pr.diff, pr.lwr, pr.upr, pr.p_adj);
            if (pr.p_adj < 0.05) {
              const auto ia = std::find(methods.begin(), methods.end(), pr.a) - methods.begin();
              const auto ib = std::find(methods.begin(), methods.end(), pr.b) - methods.begin();
              bc.marks.push_back({static_cast<int>(std::min(ia, ib)), static_cast<int>(std::max(ia, ib)), Stars(pr.p_adj)});
            }
          }
          if (o.figures) {
            const auto base = (fs::path(w.dir()) / fmt::format("{}_{}_methods", sid, Safe(crit))).string();
            w.Add(DrawBarChart(bc, base));
            md << "\n![" << crit << " by method](" << fs::path(base).filename().string() << ".png)\n"
               << "\n(* p < 0.05, ** p < 0.01, Tukey HSD.)\n";
          }
        }
      }
      // Linear mixed model of the protocol's [analysis] lmm_formula (every rating, no averaging).
      if (tests.count("lmm")) {
        md << "\nLinear mixed model `" << proto.lmm_formula
           << "` (REML, lme4's fit; Satterthwaite df, type 3 tests with sum-to-zero contrasts, as lmerTest / "
              "afex::mixed):\n\n";
        try {
          const auto m = FitLmm(cm, proto.lmm_formula);
          auto csv = w.Open(fmt::format("{}_{}_lmm.csv", sid, Safe(crit)));
          csv << "kind,name,estimate_or_F,se,num_df,den_df,t,p\n";
          md << "| term | df | F | p |\n|---|---|---|---|\n";
          for (const auto& t : m.anova) {
            md << fmt::format("| {}{} | {:.0f}, {:.2f} | {:.3f} | {} |\n", t.term, t.p < 0.05 ? "*" : "", t.num_df, t.den_df,
                              t.F, P(t.p));
            csv << fmt::format("F,{},{:.10g},,{:.0f},{:.10g},,{:.10g}\n", t.term, t.F, t.num_df, t.den_df, t.p);
          }
          for (const auto& c : m.fixed)
            csv << fmt::format("coefficient,{},{:.10g},{:.10g},1,{:.10g},{:.10g},{:.10g}\n", c.name, c.estimate, c.se, c.df,
                               c.t, c.p);
          md << "\n| random effect | SD |\n|---|---|\n";
          for (const auto& g : m.random)
            for (std::size_t i = 0; i < g.names.size(); ++i) md << fmt::format("| {} {} | {:.3f} |\n", g.group, g.names[i], g.sd[i]);
          md << fmt::format("| residual | {:.3f} |\n", m.sigma);
          if (m.singular) md << "\nBoundary (singular) fit: a variance is 0 or a correlation is +-1; simplify the random terms.\n";
          if (!m.converged) md << "\nThe optimizer did not converge; the numbers above are unreliable.\n";
        } catch (const InputError& e) {
          md << "Not fitted: " << e.what() << "\n";
        }
      }
      // Per-material bars by method (Figs. 4.8, 5.8).
      BarChart bm;
      bm.title = fmt::format("{}: {} similarity by material", st.name, crit);
      bm.x_label = "material";
      bm.y_label = crit + " similarity";
      bm.error_label = "95% CI";
      bm.groups = materials;
      for (const auto& me : methods) {
        BarSeries s{me, {}, {}};
        for (const auto& ma : materials) {
          const auto [m, ci] = MeanCi(cm.Where({{"material", ma}, {"method", me}}));
          s.mean.push_back(m);
          s.err.push_back(ci);
        }
        bm.series.push_back(s);
      }
      // Letters against the real-real limits (Fig. 4.5).
      if (tests.count("grouping")) {
        if (methods.size() != 1) {
          NotRun(md, "grouping",
                 fmt::format("it compares the materials of a single method against the real-real limits "
                             "(ch. IV.5.2), and this study has {} methods (see Tukey HSD for them)",
                             methods.size()));
        } else if (!same.rows() || !diff.rows()) {
          NotRun(md, "grouping",
                 "it needs the real-real limits: a reference phase with both same-material and "
                 "different-material pairs");
        } else {
          LongTable g = cm;
          for (std::size_t i = 0; i < same.rows(); ++i) {
            for (std::size_t c = 0; c < g.key_names.size(); ++c)
              g.keys[c].push_back(g.key_names[c] == "material" ? "upper limit" : same.keys[c][i]);
            g.y.push_back(same.y[i]);
          }
          for (std::size_t i = 0; i < diff.rows(); ++i) {
            for (std::size_t c = 0; c < g.key_names.size(); ++c)
              g.keys[c].push_back(g.key_names[c] == "material" ? "lower limit" : diff.keys[c][i]);
            g.y.push_back(diff.y[i]);
          }
          const auto kw = KruskalWallis(g, "material");
          const auto letters = GroupAgainstLimits(g, "material", "upper limit", "lower limit");
          md << fmt::format("\nKruskal-Wallis over materials and limits: H({:.0f}) = {:.2f}, p = {}. Dunn-Bonferroni "
                            "letters: A differs from the lower limit only, B from the upper only, C from neither, D "
                            "from both.\n\n| material | letter | p adj vs upper | p adj vs lower |\n|---|---|---|---|\n",
                            kw.df, kw.H, P(kw.p));
          auto lcsv = w.Open(fmt::format("{}_{}_grouping.csv", sid, Safe(crit)));
          lcsv << "material,letter,p_adj_vs_upper,p_adj_vs_lower\n";
          for (const auto& l : letters) {
            md << fmt::format("| {} | {} | {} | {} |\n", l.material, l.letter, P(l.p_adj_vs_upper), P(l.p_adj_vs_lower));
            lcsv << fmt::format("{},{},{:.10g},{:.10g}\n", l.material, l.letter, l.p_adj_vs_upper, l.p_adj_vs_lower);
            const auto it = std::find(bm.groups.begin(), bm.groups.end(), l.material);
            if (it != bm.groups.end()) {
              bm.group_marks.resize(bm.groups.size());
              bm.group_marks[static_cast<std::size_t>(it - bm.groups.begin())] = l.letter;
            }
          }
          bm.groups.push_back("lower limit");
          bm.groups.push_back("upper limit");
          for (auto& s : bm.series) {
            s.mean.push_back(lower);
            s.err.push_back(Describe(diff.y).se);
            s.mean.push_back(upper);
            s.err.push_back(Describe(same.y).se);
          }
          bm.error_label = "95% CI (limits: SE)";
        }
      }
      // Kruskal-Wallis on the cell means by method (or by material in a one-method study).
      if (tests.count("kruskal")) {
        const std::string by = methods.size() >= 2 ? "method" : "material";
        if (cells.Levels(by).size() < 2)
          NotRun(md, "kruskal", "it needs two or more methods or materials");
        else {
          const auto kw = KruskalWallis(cells, by);
          md << fmt::format("\nKruskal-Wallis on cell means by {}: H({:.0f}) = {:.2f}, {}.\n", by, kw.df, kw.H,
                            PEq(kw.p));
        }
      }
      if (o.figures) {
        const auto base = (fs::path(w.dir()) / fmt::format("{}_{}_materials", sid, Safe(crit))).string();
        w.Add(DrawBarChart(bm, base));
        md << "\n![" << crit << " by material](" << fs::path(base).filename().string() << ".png)\n";
        BoxPlot bp;
        bp.title = fmt::format("{}: {} ratings", st.name, crit);
        bp.x_label = "rendering method";
        bp.y_label = crit + " similarity";
        for (const auto& me : methods) {
          bp.groups.push_back(me);
          bp.samples.push_back(cm.Where({{"method", me}}).y);
        }
        const auto bbase = (fs::path(w.dir()) / fmt::format("{}_{}_box", sid, Safe(crit))).string();
        w.Add(DrawBoxPlot(bp, bbase));
        md << "\n![" << crit << " box plot](" << fs::path(bbase).filename().string() << ".png)\n";
      }
      // Normality (of the participant x cell means the ANOVA uses) and outliers per method.
      if (tests.count("shapiro")) {
        md << "\n| method | Shapiro-Wilk W (cell means) | p | normality | boxplot outliers (raw) |\n|---|---|---|---|---|\n";
        std::vector<std::string> flags;
        for (const auto& me : methods) {
          const auto c = cells.Where({{"method", me}});
          const auto raw = cm.Where({{"method", me}});
          std::string wcell = "n/a", pcell = "n/a", verdict = "not tested (fewer than 3 cell means or no spread)";
          if (c.rows() >= 3 && c.rows() <= 5000) {
            try {
              const auto s = ShapiroWilk(c.y);
              wcell = fmt::format("{:.4f}", s.W);
              pcell = P(s.p);
              verdict = s.p < 0.05 ? "**violated**" : "not rejected";
              if (s.p < 0.05)
                flags.push_back(fmt::format("**Normality violated** for method {}: Shapiro-Wilk W = {:.4f}, {} "
                                            "(< 0.05) on its {} cell means. The ANOVA's p-values may be off; the "
                                            "rank-based Kruskal-Wallis test (`kruskal`) does not assume normality.",
                                            me, s.W, PEq(s.p), c.rows()));
            } catch (const std::invalid_argument&) {
            }
          }
          md << fmt::format("| {} | {} | {} | {} | {} of {} |\n", me, wcell, pcell, verdict,
                            Outliers(raw.y, QuartileRule::kHinges).outliers.size(), raw.rows());
        }
        for (const auto& f : flags) md << "\n" << f << "\n";
      }
    }
    // Correlation of overall similarity with the criteria (Table 4.2), on trial ratings.
    if (tests.count("correlation")) {
      if (!std::count(proto.criteria.begin(), proto.criteria.end(), "overall") || proto.criteria.size() < 2) {
        md << "\n### Correlation of overall similarity (Table 4.2)\n";
        NotRun(md, "correlation", "it needs an `overall` criterion and at least one other criterion");
      } else {
        std::map<std::tuple<std::string, std::string, std::string, std::string, std::string>, std::map<std::string, double>> trials;
        for (std::size_t i = 0; i < main.rows(); ++i)
          trials[{main.keys[1][i], main.keys[3][i], main.keys[4][i], main.keys[5][i], main.keys[6][i]}][main.keys[7][i]] = main.y[i];
        std::map<std::string, std::vector<double>> col;
        for (const auto& [k, m] : trials) {
          if (m.size() != proto.criteria.size()) continue;
          double mn = 1e300, mx = -1e300, sum = 0;
          for (const auto& c : proto.criteria) {
            col[c].push_back(m.at(c));
            if (c == "overall") continue;
            mn = std::min(mn, m.at(c));
            mx = std::max(mx, m.at(c));
            sum += m.at(c);
          }
          col["min"].push_back(mn);
          col["max"].push_back(mx);
          col["mean"].push_back(sum / static_cast<double>(proto.criteria.size() - 1));
        }
        md << "\n### Correlation of overall similarity (Table 4.2)\n";
        if (col["overall"].size() >= 3) {
          md << "\n| with | Pearson r | p |\n|---|---|---|\n";
          for (const auto& [name, v] : col) {
            if (name == "overall") continue;
            const auto c = Pearson(col["overall"], v);
            md << fmt::format("| {} | {:.3f} | {} |\n", name, c.r, P(c.p));
          }
        } else {
          NotRun(md, "correlation",
                 fmt::format("it needs three or more main-phase trials rated on every criterion ({} so far)",
                             col["overall"].size()));
        }
      }
    }
  }
  md.close();
  res.markdown = (fs::path(o.out_dir) / "report.md").string();
  res.files = w.files_;
  return res;
}

}  // namespace hapticlab::stats
