#include "hapticlab/stats/power.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/plot.hpp"

namespace hapticlab::stats {

using nlohmann::json;

std::vector<PowerTally> AnalyseOnce(const LongTable& data, double alpha) {
  std::vector<std::string> criteria;
  const auto& ccol = data.keys[data.Key("criterion")];
  for (const auto& c : ccol)
    if (std::find(criteria.begin(), criteria.end(), c) == criteria.end()) criteria.push_back(c);
  std::vector<PowerTally> out;
  for (const auto& crit : criteria) {
    const LongTable cm = data.Where({{"criterion", crit}});
    std::vector<std::string> within;
    for (const auto& k : cm.key_names)
      if (k != "participant" && k != "criterion" && cm.Levels(k).size() >= 2) within.push_back(k);
    if (within.empty()) continue;
    const auto a = RmAnova(cm, "participant", within);
    for (const auto& e : a.effects)
      out.push_back({.criterion = crit,
                     .effect = e.effect,
                     .hits = e.p < alpha ? 1 : 0,
                     .runs = 1,
                     .sum_pes = std::isfinite(e.pes) ? e.pes : 0});
  }
  return out;
}

PowerResult SimulatePower(const std::string& protocol, const StudyGenerator& generate,
                          const PowerOptions& o) {
  if (o.shards < 1 || o.shard < 0 || o.shard >= o.shards)
    throw InputError("<command line>", 0, "shard", "expected i/N with 0 <= i < N");
  PowerResult r{.protocol = protocol,
                .simulations = o.simulations,
                .seed = o.seed,
                .shard = o.shard,
                .shards = o.shards,
                .rows = {}};
  std::vector<long> mine;  // simulation indices of this shard
  for (long s = o.shard; s < o.simulations; s += o.shards) mine.push_back(s);
  const long total = static_cast<long>(mine.size() * o.participants.size());
  long done = 0;
  for (const int n : o.participants) {
    std::vector<std::vector<PowerTally>> per(mine.size());
    std::atomic<std::size_t> next{0};
    std::atomic<long> finished{0};
    std::exception_ptr error;
    std::mutex error_mutex;
    // Simulation i of this shard; an error stops every worker and is rethrown below.
    auto simulate = [&](std::size_t i) {
      try {
        Rng rng(DeriveSeed(DeriveSeed(o.seed, static_cast<std::uint64_t>(n)),
                           static_cast<std::uint64_t>(mine[i])));
        per[i] = AnalyseOnce(generate(n, rng), o.alpha);
      } catch (...) {
        const std::lock_guard lock(error_mutex);
        if (!error) error = std::current_exception();
        next = mine.size();
      }
      ++finished;
    };
    auto work = [&] {
      for (std::size_t i; (i = next.fetch_add(1)) < mine.size();) simulate(i);
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < std::max(o.threads, 1); ++t) pool.emplace_back(work);
    // The calling thread works too and reports progress between its simulations.
    for (std::size_t i; (i = next.fetch_add(1)) < mine.size();) {
      simulate(i);
      if (o.progress) o.progress(done + finished.load(), total);
    }
    for (auto& t : pool) t.join();
    if (error) std::rethrow_exception(error);
    done += static_cast<long>(mine.size());
    if (o.progress) o.progress(done, total);
    // Reduce in simulation order: the same sums whatever the thread count.
    PowerRow row{.participants = n, .effects = {}};
    for (const auto& sim : per)
      for (const auto& t : sim) {
        if (!o.effects.empty() &&
            std::find(o.effects.begin(), o.effects.end(), t.effect) == o.effects.end())
          continue;
        auto it = std::find_if(row.effects.begin(), row.effects.end(), [&](const PowerTally& x) {
          return x.criterion == t.criterion && x.effect == t.effect;
        });
        if (it == row.effects.end()) {
          row.effects.push_back(t);
        } else {
          it->hits += t.hits;
          it->runs += t.runs;
          it->sum_pes += t.sum_pes;
        }
      }
    r.rows.push_back(std::move(row));
  }
  return r;
}

void WilsonInterval(long hits, long n, double* low, double* high) {
  if (n <= 0) {
    *low = 0;
    *high = 1;
    return;
  }
  constexpr double kZ = 1.959963984540054;  // 97.5 % normal quantile
  const double nn = static_cast<double>(n), p = static_cast<double>(hits) / nn;
  const double centre = (p + kZ * kZ / (2 * nn)) / (1 + kZ * kZ / nn);
  const double half =
      kZ / (1 + kZ * kZ / nn) * std::sqrt(p * (1 - p) / nn + kZ * kZ / (4 * nn * nn));
  *low = std::max(0.0, centre - half);
  *high = std::min(1.0, centre + half);
}

std::string PowerResult::ObserverDescription() const {
  return observer_file.empty() ? std::string("built-in uncalibrated")
                               : fmt::format("{} (sha256 {})", observer_file, observer_sha256);
}

std::string PowerToJson(const PowerResult& r) {
  json rows = json::array();
  for (const auto& row : r.rows) {
    json effects = json::array();
    for (const auto& t : row.effects) {
      double lo, hi;
      WilsonInterval(t.hits, t.runs, &lo, &hi);
      effects.push_back({{"criterion", t.criterion},
                         {"effect", t.effect},
                         {"power", t.power()},
                         {"ci_low", lo},
                         {"ci_high", hi},
                         {"mean_pes", t.mean_pes()},
                         {"hits", t.hits},
                         {"runs", t.runs},
                         {"sum_pes", t.sum_pes}});
    }
    rows.push_back({{"participants", row.participants}, {"effects", effects}});
  }
  const json observer = {
      {"model", r.ObserverDescription()},
      {"file", r.observer_file.empty() ? json(nullptr) : json(r.observer_file)},
      {"sha256", r.observer_sha256.empty() ? json(nullptr) : json(r.observer_sha256)}};
  json j = {{"protocol", r.protocol},       {"title", r.title}, {"observer", observer},
            {"simulations", r.simulations}, {"seed", r.seed},   {"rows", rows}};
  if (r.shards > 1) {
    j["shard"] = r.shard;
    j["shards"] = r.shards;
  }
  return j.dump(2) + "\n";
}

PowerResult PowerFromJson(const std::string& text, const std::string& file) {
  PowerResult r;
  try {
    const json j = json::parse(text);
    r.protocol = j.at("protocol").get<std::string>();
    r.title = j.value("title", std::string());
    r.simulations = j.at("simulations").get<long>();
    r.seed = j.at("seed").get<std::uint64_t>();
    r.shard = j.value("shard", 0);
    r.shards = j.value("shards", 1);
    const json& obs = j.at("observer");
    r.observer_file = obs.at("file").is_null() ? "" : obs.at("file").get<std::string>();
    r.observer_sha256 = obs.at("sha256").is_null() ? "" : obs.at("sha256").get<std::string>();
    for (const auto& row : j.at("rows")) {
      PowerRow pr{.participants = row.at("participants").get<int>(), .effects = {}};
      for (const auto& e : row.at("effects"))
        pr.effects.push_back({.criterion = e.at("criterion").get<std::string>(),
                              .effect = e.at("effect").get<std::string>(),
                              .hits = e.at("hits").get<long>(),
                              .runs = e.at("runs").get<long>(),
                              .sum_pes = e.at("sum_pes").get<double>()});
      r.rows.push_back(std::move(pr));
    }
  } catch (const json::exception& e) {
    throw InputError(
        file, 0, "",
        std::string("not a study power result (the JSON the power analysis writes): ") + e.what());
  }
  return r;
}

PowerResult MergePower(const std::vector<PowerResult>& parts,
                       const std::vector<std::string>& files) {
  if (parts.empty()) throw InputError("<command line>", 0, "merge", "no files to merge");
  PowerResult m = parts[0];
  m.shard = 0;
  m.shards = 1;
  std::set<int> seen;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const auto& p = parts[i];
    const std::string& f = i < files.size() ? files[i] : std::string();
    if (p.protocol != m.protocol || p.seed != m.seed || p.simulations != m.simulations ||
        p.shards != parts[0].shards || p.observer_file != m.observer_file ||
        p.observer_sha256 != m.observer_sha256)
      throw InputError(f, 0, "protocol/observer/seed/simulations/shards",
                       "does not belong to the same run as " + files[0]);
    if (!seen.insert(p.shard).second)
      throw InputError(f, 0, "shard", fmt::format("shard {} given twice", p.shard));
    if (p.rows.size() != m.rows.size())
      throw InputError(f, 0, "rows", "different participant counts");
    if (i == 0) continue;
    for (std::size_t r = 0; r < p.rows.size(); ++r) {
      if (p.rows[r].participants != m.rows[r].participants)
        throw InputError(f, 0, "rows", "different participant counts");
      for (const auto& t : p.rows[r].effects) {
        auto& effs = m.rows[r].effects;
        auto it = std::find_if(effs.begin(), effs.end(), [&](const PowerTally& x) {
          return x.criterion == t.criterion && x.effect == t.effect;
        });
        if (it == effs.end())
          throw InputError(f, 0, "effects", "an effect the first file lacks: " + t.effect);
        it->hits += t.hits;
        it->runs += t.runs;
        it->sum_pes += t.sum_pes;
      }
    }
  }
  if (static_cast<int>(seen.size()) != parts[0].shards)
    throw InputError(files[0], 0, "shards",
                     fmt::format("{} of {} shards given", seen.size(), parts[0].shards));
  return m;
}

std::string PowerTable(const PowerResult& r) {
  std::ostringstream os;
  os << "observer: " << r.ObserverDescription() << "\n";
  os << fmt::format("{:>12} {:>10} {:>16} {:>7} {:>17} {:>9}\n", "participants", "criterion",
                    "effect", "power", "95% CI (Wilson)", "mean pes");
  for (const auto& row : r.rows)
    for (const auto& t : row.effects) {
      double lo, hi;
      WilsonInterval(t.hits, t.runs, &lo, &hi);
      os << fmt::format("{:>12} {:>10} {:>16} {:>7.3f}    [{:.3f}, {:.3f}] {:>9.3f}\n",
                        row.participants, t.criterion, t.effect, t.power(), lo, hi, t.mean_pes());
    }
  return os.str();
}

// The conventional target power (Cohen 1988) the figure marks.
constexpr double kTargetPower = 0.8;

std::vector<std::string> DrawPowerCurves(const PowerResult& r, const std::string& base) {
  LinePlot l;
  l.title = fmt::format("{}: power (p < 0.05), {} simulations each",
                        r.title.empty() ? r.protocol : r.title, r.simulations);
  l.note = "observer: " + r.ObserverDescription();
  l.x_label = "participants";
  l.y_label = "power";
  std::map<std::string, std::vector<double>> curves;
  std::vector<std::string> order;
  for (const auto& row : r.rows) {
    l.x.push_back(row.participants);
    for (const auto& t : row.effects) {
      const std::string name = t.criterion + " " + t.effect;
      if (!curves.count(name)) order.push_back(name);
      curves[name].push_back(t.power());
    }
  }
  for (const auto& n : order)
    if (curves[n].size() == l.x.size()) l.series.emplace_back(n, curves[n]);
  l.markers = true;
  l.y_min = 0;
  l.y_max = 1;
  l.hlines.emplace_back(kTargetPower, "power 0.8");
  // The chosen sample size: the smallest participant count from which every curve that
  // reaches 0.8 stays at or above it (a curve of a null effect never does and is ignored).
  double chosen = NAN;
  for (const auto& [name, y] : l.series) {
    std::size_t from = y.size();
    while (from > 0 && y[from - 1] >= kTargetPower) --from;
    if (from == y.size()) continue;
    chosen = std::isnan(chosen) ? l.x[from] : std::max(chosen, l.x[from]);
  }
  if (std::isfinite(chosen)) l.vlines.emplace_back(chosen, fmt::format("n = {:.0f}", chosen));
  return DrawLinePlot(l, base);
}

int ParticipantsFor(const PowerResult& r, const std::string& criterion, const std::string& effect,
                    double target) {
  for (const auto& row : r.rows)
    for (const auto& t : row.effects)
      if (t.criterion == criterion && t.effect == effect && t.power() >= target)
        return row.participants;
  return 0;
}

}  // namespace hapticlab::stats
