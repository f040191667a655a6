#include "hapticlab/design/power_pool.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <exception>
#include <filesystem>
#include <mutex>
#include <thread>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/protocols/participant_code.hpp"

namespace hapticlab::design {

namespace fs = std::filesystem;

sim::ObserverParams ProtocolObserver(const protocols::Protocol& p) {
  const fs::path dir = fs::path(p.file).parent_path();
  if (!p.observer.empty()) return sim::LoadObserver((dir / p.observer).string());
  if (!p.profiles.empty()) return sim::LoadProfiles((dir / p.profiles).string()).observer;
  return {};
}

std::string ObserverModel::Describe() const {
  return file.empty() ? std::string("built-in uncalibrated")
                      : fmt::format("{} (sha256 {})", file, sha256);
}

ObserverModel ChooseObserver(const protocols::Protocol& p, const std::string& choice,
                             const std::string& option) {
  ObserverModel m;
  if (choice == "builtin") return m;
  if (choice.empty() && p.observer.empty())
    throw InputError(p.file, 0, option,
                     "the protocol names no simulated observer ([study] observer) and power "
                     "depends on it: give " +
                         option +
                         " FILE (a calibrated observer, e.g. studies/shin2019/observer.toml) or " +
                         option + " builtin (uncalibrated defaults)");
  m.file = choice.empty()
               ? (fs::path(p.file).parent_path() / p.observer).lexically_normal().string()
               : choice;
  m.params = sim::LoadObserver(m.file);
  m.sha256 = db::HashText(ReadTextFile(m.file, "observer file"));
  return m;
}

FeltPool RecordFeltPool(const protocols::Protocol& p, int pool_size, int threads,
                        const std::function<void(const std::string&)>& log, int first_index) {
  HL_REQUIRE(pool_size >= 1, "a pool needs at least 1 participant");
  FeltPool pool;
  pool.protocol = p.name;
  pool.criteria = p.criteria;
  pool.scale_min = p.scale_min;
  pool.scale_max = p.scale_max;
  pool.observer = ProtocolObserver(p);
  pool.participants.resize(static_cast<std::size_t>(pool_size));
  // One temporary database per pool participant: sessions run in parallel (one writer each).
  static std::atomic<int> counter{0};
  const fs::path tmp =
      fs::temp_directory_path() /
      fmt::format("hapticlab-power-{}-{}", static_cast<long>(::getpid()), counter.fetch_add(1));
  fs::create_directories(tmp);
  struct Cleanup {
    fs::path dir;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } cleanup{tmp};
  // Codes the protocol's own pattern accepts (RunStudy checks them).
  const protocols::CodeFormat codes = protocols::InferCodeFormat(p);
  std::atomic<int> next{0};
  std::exception_ptr error;
  std::mutex m;
  auto work = [&] {
    for (int i; (i = next.fetch_add(1)) < pool_size;) {
      try {
        runner::RunOptions o;
        o.db_path = (tmp / fmt::format("pool{}.db", i)).string();
        o.participant = protocols::FormatCode(codes, first_index + i + 1);
        o.participant_index = first_index + i;
        o.record = runner::RecordMode::kNone;
        auto& out = pool.participants[static_cast<std::size_t>(i)];
        o.on_felt = [&out](const runner::FeltTrial& t) {
          // A re-run trial (fault) replaces its earlier attempt.
          for (auto& x : out)
            if (x.plan_index == t.plan_index) {
              x = t;
              return;
            }
          out.push_back(t);
        };
        const auto s = runner::RunStudy(p, o);
        if (s.status != db::SessionStatus::kCompleted)
          throw std::runtime_error(fmt::format("pool participant {} did not complete", i));
        if (log) {
          const std::lock_guard lock(m);
          log(fmt::format("pool participant {} of {}: {} trials recorded", i + 1, pool_size,
                          out.size()));
        }
      } catch (...) {
        const std::lock_guard lock(m);
        if (!error) error = std::current_exception();
        next = pool_size;
      }
    }
  };
  std::vector<std::thread> ts;
  for (int t = 1; t < std::max(1, std::min(threads, pool_size)); ++t) ts.emplace_back(work);
  work();
  for (auto& t : ts) t.join();
  if (error) std::rethrow_exception(error);
  return pool;
}

stats::LongTable SimulateRatings(const FeltPool& pool, const sim::ObserverParams& observer,
                                 int participants, Rng& rng, bool main_only) {
  stats::LongTable t;
  t.source = "simulated " + pool.protocol;
  t.y_name = "score";
  t.key_names = main_only
                    ? std::vector<std::string>{"participant", "criterion", "method", "material"}
                    : std::vector<std::string>{"participant", "criterion",  "phase",
                                               "material",    "comparison", "method"};
  t.keys.assign(t.key_names.size(), {});
  HL_REQUIRE(!pool.participants.empty(), "SimulateRatings needs a non-empty pool");
  for (int i = 0; i < participants; ++i) {
    const auto& trials = pool.participants[static_cast<std::size_t>(
        rng.NextU64() % static_cast<std::uint64_t>(pool.participants.size()))];
    const sim::Observer obs(observer, rng.NextU64(), pool.criteria);
    const std::string code = fmt::format("S{:03d}", i + 1);
    for (const auto& tr : trials) {
      if (main_only && tr.phase != PhaseKind::kMain) continue;
      for (std::size_t c = 0; c < pool.criteria.size() && c < tr.distances.size(); ++c) {
        const double y = obs.RateDistance(pool.criteria[c], tr.material, tr.method, tr.distances[c],
                                          pool.scale_min, pool.scale_max, rng);
        if (main_only) {
          t.keys[0].push_back(code);
          t.keys[1].push_back(pool.criteria[c]);
          t.keys[2].push_back(tr.method);
          t.keys[3].push_back(tr.material);
        } else {
          t.keys[0].push_back(code);
          t.keys[1].push_back(pool.criteria[c]);
          t.keys[2].emplace_back(NameOf(kPhaseKindNames, tr.phase));
          t.keys[3].push_back(tr.material);
          t.keys[4].push_back(tr.comparison);
          t.keys[5].push_back(tr.method);
        }
        t.y.push_back(y);
      }
    }
  }
  return t;
}

}  // namespace hapticlab::design
