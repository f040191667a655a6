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
#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/long_table.hpp"

namespace hapticlab::stats::report_internal {

namespace fs = std::filesystem;

/// "< 0.001" or "0.020", for tables.
std::string P(double p);
/// "p < 0.001" or "p = 0.020", for sentences.
std::string PEq(double p);
std::string Stars(double p);
/// A name safe in a file name (letters, digits, '-'; others become '_').
std::string Safe(const std::string& s);

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

/// Mean and 95 % CI half-width of participant means (the error bars of Figs. 5.7/5.8).
std::pair<double, double> MeanCi(const LongTable& t);
/// Levels of `present` in the protocol's order (`order`), then any others (sorted).
std::vector<std::string> InProtocolOrder(const std::vector<std::string>& order,
                                         const std::vector<std::string>& present);
/// A requested analysis that cannot run says why, in the report (never dropped silently).
void NotRun(std::ostream& md, const std::string& test, const std::string& why);
/// Aggregate tables in the layout of the dissertation's Tables 5.4/5.5.
void AggregateTables(std::ostream& md, std::ostream& agg, const protocols::Protocol& proto,
                     const std::string& crit, const LongTable& cm,
                     const std::vector<std::string>& methods,
                     const std::vector<std::string>& materials, double upper);
/// The rmANOVA table with Mauchly's test beside each effect.
void AnovaTable(std::ostream& md, std::ostream& csv, const RmAnovaResult& a);

}  // namespace hapticlab::stats::report_internal
