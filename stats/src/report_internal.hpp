#pragma once
// Helpers shared by the report's files (stats/src/report*.cpp): number formats, the output
// directory writer, the aggregate and ANOVA tables. Not installed.

#include <filesystem>
#include <fstream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/stats/analysis.hpp"
#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/long_table.hpp"
#include "hapticlab/stats/plot.hpp"

namespace hapticlab::db {
class Database;
}

namespace hapticlab::stats::report_internal {

namespace fs = std::filesystem;

/// "< 0.001" or "0.020", for tables.
std::string P(double p);
/// "p < 0.001" or "p = 0.020", for sentences.
std::string PEq(double p);
std::string Stars(double p);
/// A name safe in a file name (letters, digits, '-'; others become '_').
std::string Safe(const std::string& s);

/// The report's output folder (hapticlab/stats/analysis.hpp).
using Writer = ReportWriter;

/// Mean and 95 % CI half-width of participant means (the error bars of Figs. 5.7/5.8).
std::pair<double, double> MeanCi(const LongTable& t);
/// Levels of `present` in the protocol's order (`order`), then any others (sorted).
std::vector<std::string> InProtocolOrder(const std::vector<std::string>& order,
                                         const std::vector<std::string>& present);
/// Aggregate tables in the layout of the dissertation's Tables 5.4/5.5.
void AggregateTables(std::ostream& md, std::ostream& agg, const protocols::Protocol& proto,
                     const std::string& crit, const LongTable& cm,
                     const std::vector<std::string>& methods,
                     const std::vector<std::string>& materials, double upper);
/// The rmANOVA table with Mauchly's test beside each effect. Stars, the df and p columns and
/// every sentence follow one rule: an effect is significant when the p of `correction` (the
/// corrected p of a within effect, the plain p of a between one) is below 0.05.
void AnovaTable(std::ostream& md, std::ostream& csv, const RmAnovaResult& a,
                Correction correction = Correction::kGG);
/// What the error bars beside within-subject tests show (figures and captions).
inline constexpr const char* kWithinCiLabel = "95% within-subject CI (Cousineau-Morey)";
/// The per-material bars of each method (Figs. 4.8, 5.8) with within-subject CIs over the
/// method x material cells (WithinSubjectCi); between-subject CIs of participant means where
/// the cells do not vary within participants. Sets chart.series and chart.error_label.
void MaterialSeries(BarChart& chart, const LongTable& cm, const std::vector<std::string>& methods,
                    const std::vector<std::string>& materials);
/// A departure from normality matters to a conclusion whose p lies in [kStakeLow, kStakeHigh).
inline constexpr double kStakeLow = 0.01, kStakeHigh = 0.10;
/// A conclusion a model's normality check may put at stake: an effect and the p it is judged by.
struct Conclusion {
  std::string effect;
  double p = 1;
};
/// Shapiro-Wilk on a model's residuals (`what`: "the ANOVA's residuals (as ..."; the count
/// and ")" follow), a Q-Q figure (`<base_name>_qq.svg/.png/.pdf`), and advice (`advice`: what
/// to confirm the conclusion with) only where a conclusion's p is in the stake band.
void ResidualNormality(std::ostream& md, Writer& w, const std::string& base_name,
                       const std::vector<double>& residuals, const std::string& what,
                       const std::vector<Conclusion>& conclusions, const std::string& advice,
                       bool figures, const std::string& title);
/// The same on the rmANOVA's residuals (AnovaResiduals), its effects judged by `correction`.
void ResidualNormality(std::ostream& md, Writer& w, const std::string& base_name,
                       const RmAnovaResult& a, Correction correction, bool figures,
                       const std::string& title);

/// The "Sites" section of a study (multisite_report.cpp): "" unless its sessions come from two
/// or more sites.
std::string MultiSiteSection(const db::Database& d, std::int64_t study_id,
                             const protocols::Protocol& proto, const LongTable& study, Writer& w,
                             bool figures);

}  // namespace hapticlab::stats::report_internal
