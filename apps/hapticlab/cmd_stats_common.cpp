// The options and the CSV loading every `stats` subcommand shares (cmd_stats_common.hpp).

#include "cmd_stats_common.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <boost/math/policies/error_handling.hpp>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include "cli_common.hpp"
#include "hapticlab/core/csv.hpp"
#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab::cli::stats_cmd {

void AddCommon(CLI::App* cmd, Common& c) {
  cmd->add_option("--csv", c.csv, "Long-format CSV (one row per observation)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--dv", c.dv, "Column of the response (numeric)")->required();
  cmd->add_option("--where", c.where,
                  "Keep rows with COL=VALUE (repeatable), e.g. --where criterion=roughness");
  cmd->add_option("--average-by", c.average_by,
                  "Average the response within each combination of these columns first, e.g.\n"
                  "subject,method,material to use cell means (repetitions averaged)");
  cmd->add_flag("--json", c.json, "Print results as JSON");
  cmd->add_flag(
      "--include-simulated", c.include_simulated,
      "A CSV with a 'source' column (hapticlab export): keep the simulated observer's rows\n"
      "although rows rated by participants are present (left out by default, with a note)");
}

stats::LongTable Load(const Common& c, std::vector<std::string> keys) {
  std::vector<std::pair<std::string, std::string>> cond;
  for (const auto& w : c.where) {
    const auto eq = w.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError(kCommandLine, 0, "--where", "expected COL=VALUE, got '" + w + "'");
    cond.emplace_back(w.substr(0, eq), w.substr(eq + 1));
    keys.push_back(cond.back().first);
  }
  const auto avg = stats::SplitList(c.average_by);
  keys.insert(keys.end(), avg.begin(), avg.end());
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  stats::RowFilter keep{.equal = cond, .not_equal = {}};
  // The project's exports carry each rating's source: when a person rated any row, the
  // simulated observer's rows are left out unless asked for (docs/analysis.md).
  {
    const CsvTable raw = ReadCsv(c.csv);
    if (const auto sc = raw.Find("source"); sc && !c.include_simulated) {
      std::size_t simulated = 0, human = 0;
      for (const auto& row : raw.rows)
        (row[*sc] == "simulated" ? simulated : human) += row[*sc].empty() ? 0 : 1;
      if (simulated && human) {
        keep.not_equal.emplace_back("source", "simulated");
        fmt::print(stderr,
                   "note: {}: {} rows rated by the simulated observer are left out ({} rated by "
                   "participants); "
                   "--include-simulated keeps them\n",
                   c.csv, simulated, human);
      }
    }
  }
  auto t = stats::ReadLongCsv(c.csv, c.dv, keys, c.allow_missing, keep);
  if (t.rows() == 0) throw InputError(c.csv, 0, "--where", "no rows left after filtering");
  if (!avg.empty()) t = t.Average(avg);
  return t;
}

namespace {

// The refusal of a non-finite statistic `what`: why, in words, and where.
[[noreturn]] void Refuse(const stats::LongTable& t, const std::string& what) {
  const std::string column = t.y_name.empty() ? std::string("response") : t.y_name;
  double lo = INFINITY, hi = -INFINITY;
  std::size_t extreme = 0;
  for (std::size_t r = 0; r < t.rows(); ++r) {
    if (std::isnan(t.y[r])) continue;
    lo = std::min(lo, t.y[r]);
    hi = std::max(hi, t.y[r]);
    if (std::abs(t.y[r]) > std::abs(t.y[extreme]) || std::isnan(t.y[extreme])) extreme = r;
  }
  const int line = extreme < t.lines.size() ? static_cast<int>(t.lines[extreme]) : 0;
  const double v = t.rows() ? t.y[extreme] : NAN;
  // The typical deviation from the median (median absolute deviation), to tell one value
  // that dwarfs the rest from a column on the wrong scale.
  std::vector<double> finite;
  for (double y : t.y)
    if (!std::isnan(y)) finite.push_back(y);
  std::vector<double> dev;
  double mad = 0;
  if (!finite.empty()) {
    std::nth_element(finite.begin(), finite.begin() + finite.size() / 2, finite.end());
    const double median = finite[finite.size() / 2];
    for (double y : finite) dev.push_back(std::abs(y - median));
    std::nth_element(dev.begin(), dev.begin() + dev.size() / 2, dev.end());
    mad = dev[dev.size() / 2];
  }
  const double big = std::max(std::abs(lo), std::abs(hi));
  std::string why;
  if (hi == lo)
    why = fmt::format("every value of {} is {:g}: the response does not vary, so {} is undefined",
                      column, lo, what);
  else if (big > 1e150 || hi - lo < 1e-150)
    why = fmt::format(
        "{} is not finite: the values of {} range from {:g} to {:g} (this row: {:g}), and their "
        "squares overflow or underflow double precision; rescale the column (e.g. to the rating "
        "scale) or correct the value",
        what, column, lo, hi, v);
  else if (mad > 0 && std::abs(v) / mad > 1e12)
    why = fmt::format(
        "{} is not finite: this row's {} ({:g}) is {:.0e} times the typical deviation of the "
        "others, beyond double precision's 16 digits (they vanish next to it); correct the value",
        what, column, v, std::abs(v) / mad);
  else
    why = fmt::format(
        "{} is not finite: the model fits the values of {} exactly (no residual variance), so "
        "the test is undefined",
        what, column);
  throw InputError(t.source, line, column, why);
}

}  // namespace

void RequireFinite(const stats::LongTable& t,
                   const std::vector<std::pair<std::string, double>>& values) {
  for (const auto& [name, v] : values)
    if (!std::isfinite(v))
      Refuse(t, name + (std::isnan(v) ? " (not a number)"
                        : v > 0       ? " (+infinity)"
                                      : " (-infinity)"));
}

void Fitted(const stats::LongTable& t, const std::function<void()>& fit) {
  // Boost.Math reports a non-finite argument or a failed series as these; its text names
  // library functions, not the data, so it never reaches the user as it is.
  try {
    fit();
  } catch (const std::domain_error&) {
    Refuse(t, "a distribution function's argument");
  } catch (const std::overflow_error&) {
    Refuse(t, "an intermediate result");
  } catch (const std::underflow_error&) {
    Refuse(t, "an intermediate result");
  } catch (const boost::math::evaluation_error&) {
    Refuse(t, "a series evaluation");
  } catch (const boost::math::rounding_error&) {
    Refuse(t, "a rounded value");
  }
}

}  // namespace hapticlab::cli::stats_cmd
