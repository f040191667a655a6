// hapticlab analyze: the protocol's analyses on a study database, as a report.

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/replication/bundle.hpp"
#include "hapticlab/replication/deviations.hpp"
#include "hapticlab/stats/report.hpp"

namespace hapticlab::cli {

void RegisterAnalyze(CLI::App& app) {
  struct O {
    std::string db, out, correction, plan;
    bool no_figures = false, json = false, include_simulated = false;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand(
      "analyze",
      "Run the analyses each study's protocol declares on its database and write a report:\n"
      "report.md, CSV tables (aggregates, rmANOVA, Tukey, grouping) and figures (SVG and PNG):\n"
      "bar charts with 95% within-subject CIs and Tukey asterisks, per-material bars with\n"
      "A/B/C letters against the real-real limits, box plots, a Q-Q plot of the ANOVA's\n"
      "residuals (docs/analysis.md). Staircase and QUEST+ phases:\n"
      "psychometric fits with bootstrap intervals, JND, Weber fraction and the fitted curve over\n"
      "the binned answers (docs/psychophysics.md). A damaged database (SQLite quick_check) or a\n"
      "score that is not a number on the protocol's scale is refused (exit 2).");
  cmd->add_option("--db", o->db, "Study database")->required();
  cmd->add_option("--out", o->out, "Report folder (created when missing)")->required();
  cmd->add_flag("--no-figures", o->no_figures, "Tables only");
  cmd->add_flag("--json", o->json, "Print the written files as JSON");
  cmd->add_flag(
      "--include-simulated", o->include_simulated,
      "Keep the simulated observer's ratings in a study that also holds ratings by participants\n"
      "(left out by default; the report says how many)");
  cmd->add_option("--correction", o->correction,
                  "Sphericity correction whose p decides the significance of within effects,\n"
                  "afex's names: GG (Greenhouse-Geisser), HF (Huynh-Feldt) or none; overrides\n"
                  "each protocol's [analysis] correction (default there: GG, as afex)")
      ->check(CLI::IsMember({"GG", "HF", "none"}));
  cmd->add_option("--plan", o->plan,
                  "Preregistered plan (study freeze) or imported site directory: the report\n"
                  "separates preregistered from exploratory analyses and lists every deviation\n"
                  "from the plan (docs/replication.md)");
  cmd->callback([o] {
    RunGuarded({{"db", "--db"}, {"out", "--out"}}, [&] {
      if (std::error_code ec;
          std::filesystem::exists(o->out, ec) && !std::filesystem::is_directory(o->out, ec))
        throw InputError(o->out, 0, "--out",
                         "exists and is not a folder: the report is written into a folder");
      stats::ReportOptions ro{.out_dir = o->out,
                              .figures = !o->no_figures,
                              .include_simulated = o->include_simulated,
                              .correction = o->correction};
      if (!o->plan.empty()) {  // verified before anything is written
        auto plan =
            std::make_shared<replication::Plan>(replication::OpenPlanForRun(o->plan, "").plan);
        const replication::AnalyzeSettings settings{o->correction, o->include_simulated};
        ro.study_section = [plan, settings](const db::Database& d, const db::Study& st) {
          return replication::DeviationsSection(*plan, d, st, settings);
        };
      }
      const auto r = stats::Analyze(o->db, ro);
      if (o->json) {
        fmt::print(
            "{}\n",
            JsonText({{"report", r.markdown}, {"files", r.files}, {"studies", r.studies}}, 2));
      } else {
        fmt::print("report: {} ({} files, studies: {})\n", r.markdown, r.files.size(),
                   fmt::join(r.studies, ", "));
      }
      return kExitOk;
    });
  });
}

}  // namespace hapticlab::cli
