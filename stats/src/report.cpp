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
#include "hapticlab/stats/within_ci.hpp"
#include "report_internal.hpp"

namespace hapticlab::stats {

using namespace report_internal;

ReportResult Analyze(const std::string& db_path, const ReportOptions& o) {
  RatingSources sources;
  const LongTable all = RatingsFromDatabase(db_path, o.include_simulated, &sources);
  if (all.rows() == 0) throw InputError(db_path, 0, "", "the database holds no ratings yet");
  fs::create_directories(o.out_dir);
  Writer w(o.out_dir);
  ReportResult res;
  db::Database d(db_path, {.create = false, .read_only = true});
  auto md = w.Open("report.md");
  // The database by its file name: a folder would carry a user or host name into the report.
  md << "# HapticLab analysis report\n\nDatabase: `" << fs::path(db_path).filename().string()
     << "`\n\n"
     << "Scores are similarity ratings on the protocol's scale. Repetitions are averaged per "
        "participant x cell "
        "before repeated-measures ANOVA (as afex does). Tukey comparisons of a within-subject "
        "factor use the pooled "
        "error of its effect (emmeans `model = \"univariate\"`). Error bars beside these "
        "within-subject tests are 95 % within-subject confidence intervals (Cousineau 2005 with "
        "Morey's 2008 correction, as afex_plot and Rmisc::summarySEwithin). Outliers (1.5 IQR, "
        "Tukey's hinges) are counted, not removed.\n";
  for (const auto& st : d.Studies()) {
    const auto proto = protocols::ParseProtocol(st.protocol_toml, "(protocol of " + st.name + ")");
    const std::set<std::string> tests(proto.analyses.begin(), proto.analyses.end());
    const Correction correction =
        o.correction.empty() ? ParseCorrection(proto.correction, st.name, "analysis.correction")
                             : ParseCorrection(o.correction, "<command line>", "--correction");
    const auto study = all.Where({{"study", st.name}});
    if (study.rows() == 0) continue;
    res.studies.push_back(st.name);
    const std::string sid = Safe(st.name);
    md << "\n## Study `" << st.name << "`\n\n"
       << proto.description << "\n\n"
       << "Participants: " << study.Levels("participant").size() << "; ratings: " << study.rows()
       << "\n";
    {
      // Where the ratings came from: a person's input device or the simulated observer.
      const auto count = [&](const std::map<std::string, std::size_t>& m) {
        const auto it = m.find(st.name);
        return it == m.end() ? std::size_t{0} : it->second;
      };
      const std::size_t human = count(sources.human), kept = count(sources.simulated_kept),
                        excluded = count(sources.simulated_excluded);
      if (excluded)
        md << "\n**Simulated ratings excluded:** " << excluded
           << " ratings of the simulated observer (sessions or "
           << "parts of sessions run without a person rating) are left out of this study's "
           << human
           << " ratings by participants; `hapticlab analyze --include-simulated` keeps them.\n";
      else if (kept && human)
        md << "\n**Simulated ratings included** (`--include-simulated`): " << kept
           << " ratings of the simulated "
           << "observer are analysed together with " << human << " ratings by participants.\n";
      else if (kept)
        md << "\nAll ratings come from the simulated observer (a simulated study).\n";
    }
    md << "\n" << TimingMethodsSentence(d, st.id);
    if (o.study_section) md << o.study_section(d, st);  // analyze --plan: deviations
    // Adaptive phases (staircase, QUEST+): psychometric fits, JND and Weber fraction.
    md << AdaptiveReport(db_path, st.name, st.protocol_toml, o.out_dir, o.figures, &w.files_);
    md << MultiSiteSection(d, st.id, proto, study, w, o.figures);  // docs/replication.md
    if (study.Where({{"phase", "main"}}).rows() + study.Where({{"phase", "reference"}}).rows() == 0)
      continue;
    const auto main = study.Where({{"phase", "main"}});
    const auto ref = study.Where({{"phase", "reference"}});
    std::vector<std::string> proto_methods, proto_materials;
    for (const auto& m : proto.methods) proto_methods.push_back(m.name);
    for (const auto& m : proto.materials) proto_materials.push_back(m.id);
    const auto methods = main.rows() ? InProtocolOrder(proto_methods, main.Levels("method"))
                                     : std::vector<std::string>{};
    const auto materials = main.rows() ? InProtocolOrder(proto_materials, main.Levels("material"))
                                       : std::vector<std::string>{};
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
          auto& dst =
              rc.keys[rc.Key("material")][i] == rc.keys[rc.Key("comparison")][i] ? same : diff;
          for (std::size_t c = 0; c < rc.key_names.size(); ++c)
            dst.keys[c].push_back(rc.keys[c][i]);
          dst.y.push_back(rc.y[i]);
        }
        if (same.rows()) upper = Describe(same.y).mean;
        if (diff.rows()) lower = Describe(diff.y).mean;
        md << fmt::format(
            "\nReal-real limits: upper {:.2f} (same material, n = {}), lower {:.2f} (different "
            "materials, n = {}).\n",
            upper, same.rows(), lower, diff.rows());
      }
      if (cm.rows() == 0) {
        md << "\nNo main-phase ratings of " << crit
           << " yet: the aggregate table, ANOVA, Tukey, grouping, "
           << "Kruskal-Wallis and Shapiro-Wilk analyses need them.\n";
        continue;
      }
      if (tests.count("aggregate"))
        AggregateTables(md, agg, proto, crit, cm, methods, materials, upper);
      // Repeated-measures ANOVA (Tables 5.2, 5.3); Tukey needs its error term.
      std::vector<std::string> within;
      if (methods.size() >= 2) within.push_back("method");
      if (materials.size() >= 2) within.push_back("material");
      const auto cells = cm.Average({"participant", "method", "material"});
      const std::size_t n_participants = cm.Levels("participant").size();
      std::optional<RmAnovaResult> anova;
      std::string anova_why;
      if (tests.count("rm-anova") || tests.count("tukey") || tests.count("shapiro")) {
        if (within.empty())
          anova_why =
              "it needs a within factor with two or more levels (this study has one method and one "
              "material)";
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
          csv << "effect,df1,df2,F,p,pes,mauchly_W,mauchly_p,gg_epsilon,p_gg,hf_epsilon,p_hf,"
                 "correction,p_used\n";
          AnovaTable(md, csv, *anova, correction);
        } else {
          NotRun(md, "rm-anova", anova_why);
        }
      }
      // Tukey on method + the bar chart of Figs. 5.7/5.8.
      if (tests.count("tukey")) {
        if (methods.size() < 2) {
          NotRun(md, "tukey",
                 fmt::format("it compares methods and this study has {} method", methods.size()));
        } else if (!anova) {
          NotRun(md, "tukey",
                 "it uses the repeated-measures ANOVA's error term, which could not be computed: " +
                     anova_why);
        } else {
          const auto tk = TukeyWithin(*anova, "method", false);
          auto tcsv = w.Open(fmt::format("{}_{}_tukey.csv", sid, Safe(crit)));
          tcsv << "a,b,diff,lwr,upr,p_adj\n";
          md << "\nTukey HSD on method (univariate error of the method effect, df = " << tk.df
             << "):\n\n"
             << "| pair | diff | 95 % CI | p adj |\n|---|---|---|---|\n";
          BarChart bc;
          bc.title = fmt::format("{}: {} similarity", proto.title, crit);
          bc.x_label = "rendering method";
          bc.y_label = crit + " similarity";
          bc.error_label = kWithinCiLabel;
          bc.groups = {""};
          const auto ci = WithinSubjectCi(cm, "participant", {"method"});
          for (const auto& me : methods)
            for (const auto& c : ci)
              if (c.cell[0] == me) bc.series.push_back({me, {c.mean}, {c.half_width}});
          for (const auto& pr : tk.pairs) {
            md << fmt::format("| {} - {} | {:.2f} | [{:.2f}, {:.2f}] | {}{} |\n", pr.a, pr.b,
                              pr.diff, pr.lwr, pr.upr, P(pr.p_adj), Stars(pr.p_adj));
            tcsv << fmt::format("{},{},{:.10g},{:.10g},{:.10g},{:.10g}\n", pr.a, pr.b, pr.diff,
                                pr.lwr, pr.upr, pr.p_adj);
            if (pr.p_adj < 0.05) {
              const auto ia = std::find(methods.begin(), methods.end(), pr.a) - methods.begin();
              const auto ib = std::find(methods.begin(), methods.end(), pr.b) - methods.begin();
              bc.marks.push_back({static_cast<int>(std::min(ia, ib)),
                                  static_cast<int>(std::max(ia, ib)), Stars(pr.p_adj)});
            }
          }
          if (o.figures) {
            const auto base =
                (fs::path(w.dir()) / fmt::format("{}_{}_methods", sid, Safe(crit))).string();
            w.Add(DrawBarChart(bc, base));
            md << "\n![" << crit << " by method](" << fs::path(base).filename().string()
               << ".png)\n"
               << "\n(Error bars: " << kWithinCiLabel << " of the participants' method means; "
               << "* p < 0.05, ** p < 0.01, Tukey HSD.)\n";
          }
        }
      }
      // Linear mixed model of the protocol's [analysis] lmm_formula (every rating, no averaging).
      if (tests.count("lmm")) {
        md << "\nLinear mixed model `" << proto.lmm_formula
           << "` (REML, lme4's fit; Satterthwaite df, type 3 tests with sum-to-zero contrasts, as "
              "lmerTest / "
              "afex::mixed):\n\n";
        try {
          const auto m = FitLmm(cm, proto.lmm_formula);
          auto csv = w.Open(fmt::format("{}_{}_lmm.csv", sid, Safe(crit)));
          csv << "kind,name,estimate_or_F,se,num_df,den_df,t,p\n";
          md << "| term | df | F | p |\n|---|---|---|---|\n";
          for (const auto& t : m.anova) {
            md << fmt::format("| {}{} | {:.0f}, {:.2f} | {:.3f} | {} |\n", t.term,
                              t.p < 0.05 ? "*" : "", t.num_df, t.den_df, t.F, P(t.p));
            csv << fmt::format("F,{},{:.10g},,{:.0f},{:.10g},,{:.10g}\n", t.term, t.F, t.num_df,
                               t.den_df, t.p);
          }
          for (const auto& c : m.fixed)
            csv << fmt::format("coefficient,{},{:.10g},{:.10g},1,{:.10g},{:.10g},{:.10g}\n", c.name,
                               c.estimate, c.se, c.df, c.t, c.p);
          md << "\n| random effect | SD |\n|---|---|\n";
          for (const auto& g : m.random)
            for (std::size_t i = 0; i < g.names.size(); ++i)
              md << fmt::format("| {} {} | {:.3f} |\n", g.group, g.names[i], g.sd[i]);
          md << fmt::format("| residual | {:.3f} |\n", m.sigma);
          if (m.singular)
            md << "\nBoundary (singular) fit: a variance is 0 or a correlation is +-1; simplify "
                  "the random terms.\n";
          if (!m.converged)
            md << "\nThe optimizer did not converge; the numbers above are unreliable.\n";
        } catch (const InputError& e) {
          md << "Not fitted: " << e.what() << "\n";
        }
      }
      // Per-material bars by method (Figs. 4.8, 5.8).
      BarChart bm;
      bm.title = fmt::format("{}: {} similarity by material", proto.title, crit);
      bm.x_label = "material";
      bm.y_label = crit + " similarity";
      bm.groups = materials;
      MaterialSeries(bm, cm, methods, materials);
      // Letters against the real-real limits (Fig. 4.5).
      if (tests.count("grouping")) {
        if (methods.size() != 1) {
          NotRun(md, "grouping",
                 fmt::format(
                     "it compares the materials of a single method against the real-real limits "
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
          md << fmt::format(
              "\nKruskal-Wallis over materials and limits: H({:.0f}) = {:.2f}, p = {}. "
              "Dunn-Bonferroni "
              "letters: A differs from the lower limit only, B from the upper only, C from "
              "neither, D "
              "from both.\n\n| material | letter | p adj vs upper | p adj vs lower "
              "|\n|---|---|---|---|\n",
              kw.df, kw.H, P(kw.p));
          auto lcsv = w.Open(fmt::format("{}_{}_grouping.csv", sid, Safe(crit)));
          lcsv << "material,letter,p_adj_vs_upper,p_adj_vs_lower\n";
          for (const auto& l : letters) {
            md << fmt::format("| {} | {} | {} | {} |\n", l.material, l.letter, P(l.p_adj_vs_upper),
                              P(l.p_adj_vs_lower));
            lcsv << fmt::format("{},{},{:.10g},{:.10g}\n", l.material, l.letter, l.p_adj_vs_upper,
                                l.p_adj_vs_lower);
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
          bm.error_label += "; limits: SE";
        }
      }
      // Kruskal-Wallis on the cell means by method (or by material in a one-method study).
      if (tests.count("kruskal")) {
        const std::string by = methods.size() >= 2 ? "method" : "material";
        if (cells.Levels(by).size() < 2)
          NotRun(md, "kruskal", "it needs two or more methods or materials");
        else {
          const auto kw = KruskalWallis(cells, by);
          md << fmt::format("\nKruskal-Wallis on cell means by {}: H({:.0f}) = {:.2f}, {}.\n", by,
                            kw.df, kw.H, PEq(kw.p));
        }
      }
      if (o.figures) {
        const auto base =
            (fs::path(w.dir()) / fmt::format("{}_{}_materials", sid, Safe(crit))).string();
        w.Add(DrawBarChart(bm, base));
        md << "\n![" << crit << " by material](" << fs::path(base).filename().string()
           << ".png)\n\n(Error bars: " << bm.error_label << ".)\n";
        BoxPlot bp;
        bp.title = fmt::format("{}: {} ratings", proto.title, crit);
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
      // Normality of the ANOVA's residuals (afex's residuals()), and outliers per method.
      if (tests.count("shapiro")) {
        if (anova)
          ResidualNormality(md, w, fmt::format("{}_{}", sid, Safe(crit)), *anova, correction,
                            o.figures, fmt::format("{}: {} residuals", proto.title, crit));
        else
          NotRun(md, "shapiro", "it tests the repeated-measures ANOVA's residuals: " + anova_why);
        md << "\n| method | boxplot outliers (raw ratings, 1.5 IQR) |\n|---|---|\n";
        for (const auto& me : methods) {
          const auto raw = cm.Where({{"method", me}});
          md << fmt::format("| {} | {} of {} |\n", me,
                            Outliers(raw.y, QuartileRule::kHinges).outliers.size(), raw.rows());
        }
      }
    }
    // Correlation of overall similarity with the criteria (Table 4.2), on trial ratings.
    if (tests.count("correlation")) {
      if (!std::count(proto.criteria.begin(), proto.criteria.end(), "overall") ||
          proto.criteria.size() < 2) {
        md << "\n### Correlation of overall similarity (Table 4.2)\n";
        NotRun(md, "correlation",
               "it needs an `overall` criterion and at least one other criterion");
      } else {
        std::map<std::tuple<std::string, std::string, std::string, std::string, std::string>,
                 std::map<std::string, double>>
            trials;
        for (std::size_t i = 0; i < main.rows(); ++i)
          trials[{main.keys[1][i], main.keys[3][i], main.keys[4][i], main.keys[5][i],
                  main.keys[6][i]}][main.keys[7][i]] = main.y[i];
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
          NotRun(
              md, "correlation",
              fmt::format(
                  "it needs three or more main-phase trials rated on every criterion ({} so far)",
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
