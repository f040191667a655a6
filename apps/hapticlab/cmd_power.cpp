// hapticlab study power: Monte-Carlo power of a protocol's analyses for several participant
// counts (docs/studies.md "Power analysis"). Physics through the runner once for a pool of
// simulated participants, then many simulated studies re-rated by fresh simulated observers
// and analysed as the report does.

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <chrono>
#include <cstdio>
#include <memory>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/design/power_pool.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/sim/sim_lab.hpp"
#include "hapticlab/stats/power.hpp"

namespace hapticlab::cli {

// Participant counts as 'study power --participants' and 'study freeze --power-participants'
// take them: increasing, 2..10000.
std::vector<int> ParseParticipantCounts(const std::string& s, const std::string& field) {
  std::vector<int> out;
  for (const auto& part : stats::SplitList(s)) {
    int n = 0;
    try {
      std::size_t used = 0;
      n = std::stoi(part, &used);
      if (used != part.size()) n = 0;
    } catch (const std::exception&) {
      n = 0;
    }
    if (n < 2 || n > 10000)
      throw InputError(kCommandLine, 0, field,
                       "expected counts 2..10000 such as 8,12,16, got '" + part + "'");
    if (!out.empty() && n <= out.back())
      throw InputError(kCommandLine, 0, field, "expected increasing counts");
    out.push_back(n);
  }
  if (out.empty()) throw InputError(kCommandLine, 0, field, "expected at least one count");
  return out;
}

namespace {

struct PowerArgs {
  std::string protocol, participants = "8,12,16,20,30", effect, plot, out, shard, observer;
  std::vector<std::string> merge;
  long simulations = 200;
  std::uint64_t seed = 1;
  int pool = 6, threads = 2, sites = 1;
  double site_sd = 0;
  bool json = false, quiet = false;
};

void ParseShard(const std::string& s, int* i, int* n) {
  const auto slash = s.find('/');
  bool ok = slash != std::string::npos;
  try {
    if (ok) *i = std::stoi(s.substr(0, slash)), *n = std::stoi(s.substr(slash + 1));
  } catch (const std::exception&) {  // std::stoi's own errors: not a number
    ok = false;
  }
  if (!ok) throw InputError(kCommandLine, 0, "--shard", "expected i/N, e.g. 0/8, got '" + s + "'");
  if (*n < 1 || *i < 0 || *i >= *n)
    throw InputError(kCommandLine, 0, "--shard", "expected 0 <= i < N in i/N, got '" + s + "'");
}

// A replication of `sites` sites with `per_site` participants each: every site's ratings come
// from the observer with the site's offset (drawn N(0, site_sd^2)) added to every rating;
// participants are site-qualified ("K2:S003") as `db merge` writes them.
stats::LongTable SiteStudy(const design::FeltPool& pool, const sim::ObserverParams& obs, int sites,
                           double site_sd, int per_site, Rng& rng) {
  stats::LongTable all;
  for (int k = 0; k < sites; ++k) {
    sim::ObserverParams site = obs;
    site.site_offset = rng.Normal(0, site_sd);
    auto t = design::SimulateRatings(pool, site, per_site, rng, true);
    for (auto& code : t.keys[t.Key("participant")]) code = fmt::format("K{}:{}", k + 1, code);
    if (k == 0) {
      all = std::move(t);
      continue;
    }
    for (std::size_t c = 0; c < all.keys.size(); ++c)
      all.keys[c].insert(all.keys[c].end(), t.keys[c].begin(), t.keys[c].end());
    all.y.insert(all.y.end(), t.y.begin(), t.y.end());
  }
  return all;
}

void Emit(const stats::PowerResult& r, const PowerArgs& a) {
  const std::string js = stats::PowerToJson(r);
  if (!a.out.empty()) WriteTextFile(a.out, js);
  if (a.json) {
    fmt::print("{}", js);
  } else {
    if (a.sites > 1 || a.site_sd > 0)
      fmt::print(
          "replication: {} sites x n participants per site (the counts below are n), site "
          "offsets drawn with SD {} rating points\n",
          a.sites, a.site_sd);
    fmt::print("{}", stats::PowerTable(r));
  }
  if (!a.plot.empty() && r.shards == 1) {
    const auto files = stats::DrawPowerCurves(r, a.plot);
    if (!a.json) fmt::print("power curves: {}\n", fmt::join(files, ", "));
  }
}

// study power's work: a merge of shard results, or the simulated studies of a protocol.
int RunPower(PowerArgs* a) {
  if (!a->merge.empty()) {
    if (!a->protocol.empty())
      throw InputError(kCommandLine, 0, "PROTOCOL", "give either a protocol or --merge FILES");
    std::vector<stats::PowerResult> parts;
    for (const auto& f : a->merge) parts.push_back(stats::PowerFromJson(ReadTextFile(f), f));
    Emit(stats::MergePower(parts, a->merge), *a);
    return kExitOk;
  }
  if (a->protocol.empty())
    throw InputError(kCommandLine, 0, "PROTOCOL", "missing (or give --merge FILES)");
  stats::PowerOptions o;
  o.participants = ParseParticipantCounts(a->participants, "--participants");
  o.simulations = a->simulations;
  o.seed = a->seed;
  o.threads = a->threads;
  if (!a->shard.empty()) ParseShard(a->shard, &o.shard, &o.shards);
  if (!a->effect.empty()) {
    if (a->effect != "method" && a->effect != "material" && a->effect != "method:material")
      throw InputError(kCommandLine, 0, "--effect",
                       "expected method, material or method:material, got '" + a->effect + "'");
    o.effects = {a->effect};
  }
  const auto p = protocols::LoadProtocol(a->protocol);
  const auto model = design::ChooseObserver(p, a->observer);  // before the physics
  const auto t0 = std::chrono::steady_clock::now();
  const auto log = StderrLog(a->quiet);
  const auto pool = design::RecordFeltPool(p, a->pool, a->threads, log);
  const double t_pool =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  int last = -1;
  if (!a->quiet)
    o.progress = [&last](long done, long total) {
      const int pct = static_cast<int>(100 * done / std::max(total, 1L));
      if (pct / 5 != last / 5) {
        fmt::print(stderr, "\rsimulated studies: {}/{} ({}%)", done, total, pct);
        if (done == total) fmt::print(stderr, "\n");
        last = pct;
      }
    };
  const auto& obs = model.params;
  const int sites = a->sites;
  const double site_sd = a->site_sd;
  auto r = stats::SimulatePower(
      p.name,
      [&pool, &obs, sites, site_sd](int n, Rng& rng) {
        return sites == 1 && site_sd == 0 ? design::SimulateRatings(pool, obs, n, rng, true)
                                          : SiteStudy(pool, obs, sites, site_sd, n, rng);
      },
      o);

  r.observer_file = model.file;
  r.observer_sha256 = model.sha256;
  r.title = p.title;
  const double t_all = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  long studies = 0;
  for (long s = o.shard; s < o.simulations; s += o.shards) ++studies;
  studies *= static_cast<long>(o.participants.size());
  log("observer: " + model.Describe());
  log(
      fmt::format("pool of {} participants through the runner: {:.1f} s; {} simulated studies: "
                  "{:.1f} s ({:.0f} studies/s)",
                  a->pool, t_pool, studies, t_all - t_pool,
                  static_cast<double>(studies) / std::max(t_all - t_pool, 1e-9)));
  Emit(r, *a);
  return kExitOk;
}

}  // namespace

void RegisterPower(CLI::App& study) {
  auto a = std::make_shared<PowerArgs>();
  auto* cmd = study.add_subcommand(
      "power",
      "Monte-Carlo power of the protocol's analyses (rm-ANOVA per criterion: method, material,\n"
      "method:material) for several participant counts: the probability of p < 0.05 with a 95 %\n"
      "Wilson interval and the mean partial eta^2. A pool of simulated participants runs through\n"
      "the runner once (the physics); each simulated study re-rates their interactions with fresh\n"
      "simulated observers of one observer model: the protocol's [study] observer file, or\n"
      "--observer. Power depends on that model: the text, JSON and plot name it (file and\n"
      "SHA-256, or \"built-in uncalibrated\"), and without one the command refuses (exit 2).\n"
      "Reproducible from --seed whatever the thread count or sharding.");
  cmd->add_option("PROTOCOL", a->protocol, "Study protocol (.toml); not with --merge");
  cmd->add_option("--participants,--participants-per-site", a->participants,
                  "Participant counts, increasing (per site with --sites)")
      ->capture_default_str();
  cmd->add_option("--sites", a->sites,
                  "A replication at K sites: each simulated study has K x n participants, each\n"
                  "site's ratings shifted by its own offset (docs/replication.md)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--site-sd", a->site_sd,
                  "SD of the site offsets [rating points] added to the observer's ratings")
      ->check(CLI::Range(0.0, 50.0))
      ->capture_default_str();
  cmd->add_option("--simulations", a->simulations, "Simulated studies per participant count")
      ->check(CLI::Range(1L, 10000000L))
      ->capture_default_str();
  cmd->add_option("--effect", a->effect,
                  "Report only this effect: method, material or method:material");
  cmd->add_option("--observer", a->observer,
                  "Observer model: an observer file (sim::Observer, e.g. the calibrated\n"
                  "studies/shin2019/observer.toml), or 'builtin' for the uncalibrated defaults\n"
                  "(default: the protocol's [study] observer)");
  cmd->add_option("--seed", a->seed, "Seed of the simulations")->capture_default_str();
  cmd->add_option("--pool", a->pool,
                  "Simulated participants whose physics is recorded through the runner")
      ->check(CLI::Range(1, 200))
      ->capture_default_str();
  cmd->add_option("--threads", a->threads, "Worker threads")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  cmd->add_flag("--json", a->json, "Print the result as JSON");
  cmd->add_option("--out", a->out,
                  "Also write the JSON result to this file (a shard's partial result)");
  cmd->add_option("--plot", a->plot, "Power-curve figure: writes F.svg and F.png");
  cmd->add_option("--shard", a->shard,
                  "Run only shard i of N (simulations s with s mod N == i): i/N");
  cmd->add_option("--merge", a->merge, "Combine the JSON results of all shards of one run")
      ->expected(1, -1);
  cmd->add_flag("--quiet", a->quiet, "No progress on stderr");
  cmd->callback([a] { RunGuarded([&] { return RunPower(a.get()); }); });
}

}  // namespace hapticlab::cli
