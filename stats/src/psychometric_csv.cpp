#include "hapticlab/stats/psychometric_csv.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <map>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/psychometric_report.hpp"

namespace hapticlab::stats {
namespace {

using psychophysics::Shape;

// A count cell: a whole number >= 0 (a trial count may not exceed int).
int Count(const CsvTable& t, std::size_t row, std::size_t col, const char* what) {
  const double v = t.Number(row, col);
  if (!(v >= 0 && v <= std::numeric_limits<int>::max() && v == std::floor(v)))
    throw InputError(
        t.file, t.row_lines[row], t.header[col],
        fmt::format("expected a whole number of {} >= 0, got '{}'", what, t.rows[row][col]));
  return static_cast<int>(v);
}

}  // namespace

std::optional<PsychometricLink> ParsePsychometricLink(const std::string& text, std::string* why) {
  static const std::map<std::string, Shape> kShapes{
      {"logit", Shape::kLogistic}, {"probit", Shape::kNormal}, {"weibull", Shape::kWeibull}};
  const auto colon = text.find(':');
  const bool mafc = text.rfind("mafc-", 0) == 0;
  const std::string base =
      mafc ? text.substr(5, colon == std::string::npos ? colon : colon - 5) : text.substr(0, colon);
  const auto shape = kShapes.find(base);
  auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return std::nullopt;
  };
  if (shape == kShapes.end() || (!mafc && colon != std::string::npos))
    return fail(
        "expected logit, probit, weibull, mafc-logit:m, mafc-probit:m or mafc-weibull:m, "
        "got '" +
        text + "'");
  PsychometricLink link{.name = text, .shape = shape->second, .guess = 0};
  if (mafc) {
    const std::string m = colon == std::string::npos ? "" : text.substr(colon + 1);
    int alternatives = 0;
    std::size_t used = 0;
    try {
      alternatives = std::stoi(m, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (m.empty() || used != m.size() || alternatives < 2 || alternatives > 1000)
      return fail("'" + text + "': expected the number of alternatives m (2 to 1000) after ':'");
    link.guess = 1.0 / alternatives;
  }
  return link;
}

std::string PsychometricGroup::Name() const {
  std::string s;
  for (const auto& [col, val] : keys) s += (s.empty() ? "" : ", ") + col + "=" + val;
  return s.empty() ? "all" : s;
}

std::vector<PsychometricGroup> ReadPsychometricCsv(const std::string& path,
                                                   const PsychometricColumns& c,
                                                   bool positive_levels) {
  const CsvTable t = ReadCsv(path);
  const std::size_t level = t.Require(c.level), correct = t.Require(c.correct);
  const bool by_trials = !c.trials.empty();
  const std::size_t total = t.Require(by_trials ? c.trials : c.incorrect);
  std::vector<std::size_t> by;
  for (const auto& g : c.by) by.push_back(t.Require(g));
  std::vector<PsychometricGroup> groups;
  std::map<std::vector<std::string>, std::size_t> index;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    const int line = t.row_lines[r];
    const double x = t.Number(r, level);
    if (!std::isfinite(x))
      throw InputError(path, line, c.level,
                       "expected a finite stimulus level, got '" + t.rows[r][level] + "'");
    if (positive_levels && !(x > 0))
      throw InputError(
          path, line, c.level,
          "expected a level > 0: a Weibull link fits ln(level), got '" + t.rows[r][level] + "'");
    const int k = Count(t, r, correct, "correct trials");
    const int other = Count(t, r, total, by_trials ? "trials" : "incorrect trials");
    if (!by_trials && other > std::numeric_limits<int>::max() - k)
      throw InputError(path, line, c.incorrect, "correct + incorrect trials exceed 2^31 - 1");
    const int n = by_trials ? other : k + other;
    if (by_trials && n < 1)
      throw InputError(path, line, c.trials,
                       "expected at least 1 trial, got '" + t.rows[r][total] + "'");
    if (by_trials && k > n)
      throw InputError(path, line, c.correct,
                       fmt::format("{} correct of {} trials: expected at most the trials "
                                   "(column {})",
                                   k, n, c.trials));
    if (n < 1)
      throw InputError(path, line, c.correct, "a row with 0 correct and 0 incorrect trials");
    std::vector<std::string> key;
    for (const auto col : by) key.push_back(t.rows[r][col]);
    auto [it, fresh] = index.emplace(key, groups.size());
    if (fresh) {
      groups.emplace_back();
      for (std::size_t i = 0; i < by.size(); ++i) groups.back().keys.emplace_back(c.by[i], key[i]);
    }
    auto& d = groups[it->second].data;
    d.x.push_back(x);
    d.n.push_back(n);
    d.k.push_back(k);
  }
  if (groups.empty()) throw InputError(path, 0, c.level, "no data rows");
  return groups;
}

PsychometricSummary SummarizePsychometric(const PsychometricData& data,
                                          const PsychometricSummaryOptions& o) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  PsychometricSummary s;
  for (const int n : data.n) s.trials += n;
  s.fit = FitPsychometric(data, o.fit);
  s.stimulus_at.assign(o.performances.size(), nan);
  s.jnd = s.weber = nan;
  s.weber_ci = {nan, nan};
  s.boot.jnd = {nan, nan};
  s.boot.threshold = s.boot.slope = {nan, nan};
  s.boot.stimulus_at.assign(o.performances.size(), {nan, nan});
  if (!s.fit.usable) return s;
  const auto at = [&](double p) {
    const auto x = psychophysics::StimulusAt(o.fit.shape, s.fit.params, p);
    return x ? *x : nan;
  };
  for (std::size_t i = 0; i < o.performances.size(); ++i) s.stimulus_at[i] = at(o.performances[i]);
  s.jnd = at(o.jnd_performance);
  if (o.reference > 0) s.weber = s.jnd / o.reference;
  if (o.replicates < 2) return s;
  s.boot = BootstrapPsychometric(data, o.fit, s.fit, o.replicates, o.seed, o.level,
                                 o.jnd_performance, o.performances);
  if (o.reference > 0) s.weber_ci = {s.boot.jnd.lo / o.reference, s.boot.jnd.hi / o.reference};
  return s;
}

// Declared in psychometric_report.hpp; defined here, with no plotting or database code
// beside it, so that the lean hapticlab-stats (whose `psychometric` bins its data) links
// neither PLplot nor SQLite.
PsychometricData BinForPlot(const PsychometricData& pooled, int max_bins) {
  PsychometricData d = PoolByStimulus(pooled);  // not const: returned by move below
  if (static_cast<int>(d.x.size()) <= max_bins) return d;
  int total = 0;
  for (int n : d.n) total += n;
  PsychometricData out;
  double sx = 0;
  int n = 0, k = 0, bin = 0;
  int cum = 0;
  for (std::size_t i = 0; i < d.x.size(); ++i) {
    sx += d.x[i] * d.n[i];
    n += d.n[i];
    k += d.k[i];
    cum += d.n[i];
    // Close the bin when the running count passes its share of the trials.
    if (cum * max_bins >= (bin + 1) * total || i + 1 == d.x.size()) {
      out.x.push_back(sx / n);
      out.n.push_back(n);
      out.k.push_back(k);
      sx = 0, n = 0, k = 0;
      ++bin;
    }
  }
  return out;
}

}  // namespace hapticlab::stats
