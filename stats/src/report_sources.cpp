// The report's inputs: ratings from study databases, the timing sentence.
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
#include "hapticlab/stats/report.hpp"
#include "hapticlab/stats/shapiro.hpp"
#include "hapticlab/stats/tukey.hpp"
#include "report_internal.hpp"

namespace hapticlab::stats {

using namespace report_internal;

// The methods-section sentence on real-time timing over a study's trial sides (db/timing.hpp):
// achieved rates and lateness percentiles of the merged histograms of each loop.
std::string TimingMethodsSentence(const db::Database& d, std::int64_t study_id) {
  const auto rows = db::StudySideTimings(d, study_id);
  if (rows.empty())
    return "No real-time timing was recorded for this study (recorded from schema v6 on).\n";
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
    return fmt::format(
        "All {} trial sides ran on the simulated rig's virtual clock (stepped in time order, not "
        "timed): there is no real-time timing to report.\n",
        sides);
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
        throw InputError(d.path(), 0, "side_timing.late_histogram",
                         fmt::format("trial {}: malformed histogram", r.trial_id));
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
        " the {} loop (requested {:.0f} Hz) achieved {:.1f}-{:.1f} Hz per side; its wake-up "
        "lateness over {} ticks was "
        "p50 {:.1f} us, p99 {:.1f} us, p99.9 {:.1f} us (max {:.1f} us), with {} deadline misses "
        "and a tick duration of "
        "at most {:.1f} us at the 99th percentile of any side",
        loop, rate, lo, hi, ticks, late.Quantile(0.5) * 1e6, late.Quantile(0.99) * 1e6,
        late.Quantile(0.999) * 1e6, late.max_s * 1e6, misses, tick_p99);
    out += std::string(loop) == "force" ? fmt::format(" ({} recording overflows);", overflows)
                                        : fmt::format(" ({} audio underruns).", underruns);
  }
  if (out.back() == ';') out.back() = '.';
  out += fmt::format(
      " Loop threads: timer slack 1 ns on {} of {} sides, SCHED_FIFO on {}, memory locked on {}.\n",
      slack1, sides - virt, fifo, locked);
  return out;
}

LongTable RatingsFromDatabase(const std::string& db_path, bool include_simulated,
                              RatingSources* sources) {
  RatingSources local;
  RatingSources& src = sources ? *sources : local;
  // quick_check first: a damaged record is refused, never analysed.
  const db::Database d = db::OpenForReading(db_path);
  LongTable t;
  t.source = db_path;
  t.y_name = "score";
  t.key_names = {"study",      "participant", "phase",      "material",
                 "comparison", "method",      "repetition", "criterion"};
  t.keys.assign(t.key_names.size(), {});
  for (const auto& st : d.Studies()) {
    // Scores are checked against the scale of the protocol the study ran.
    const auto proto =
        protocols::ParseProtocol(st.protocol_toml, db_path + " (protocol of " + st.name + ")");
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
              throw InputError(
                  db_path, 0, "rating.score",
                  fmt::format(
                      "study '{}' participant {} trial {} criterion '{}': score {} (response "
                      "time {} s) is outside the protocol's scale [{}, {}] or negative",
                      st.name, p.code, tr.plan_index + 1, r.criterion, r.score, r.response_time_s,
                      proto.scale_min, proto.scale_max));
            if (r.source == db::kRaterSimulated) {
              if (human && !include_simulated) {
                ++src.simulated_excluded[st.name];
                continue;
              }
              ++src.simulated_kept[st.name];
            } else {
              ++src.human[st.name];
            }
            const std::string row[] = {st.name,
                                       p.code,
                                       std::string(NameOf(kPhaseKindNames, tr.phase)),
                                       tr.material,
                                       tr.comparison,
                                       tr.method,
                                       std::to_string(tr.repetition),
                                       r.criterion};
            for (std::size_t c = 0; c < t.key_names.size(); ++c) t.keys[c].push_back(row[c]);
            t.y.push_back(r.score);
          }
  }
  return t;
}

}  // namespace hapticlab::stats
