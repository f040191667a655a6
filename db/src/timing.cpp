#include "hapticlab/db/timing.hpp"

#include "sqlite_util.hpp"

namespace hapticlab::db {

using internal::Stmt;

void SaveSideTiming(Database& d, const SideTiming& t) {
  Stmt s(d.handle(),
         "INSERT OR REPLACE INTO side_timing(trial_id, attempt, side, loop, clock, rate_hz, "
         "achieved_rate_hz, ticks, "
         "deadline_misses, late_p50_us, late_p99_us, late_p999_us, late_max_us, tick_p50_us, "
         "tick_p99_us, "
         "tick_p999_us, tick_max_us, late_histogram, recording_overflows, audio_underruns, "
         "priority, memory_locked, "
         "timer_slack_ns) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)");
  s.Bind(1, t.trial_id)
      .Bind(2, t.attempt)
      .Bind(3, t.side)
      .Bind(4, t.loop)
      .Bind(5, t.clock)
      .Bind(6, t.rate_hz);
  s.Bind(7, t.achieved_rate_hz).Bind(8, t.ticks).Bind(9, t.deadline_misses).Bind(10, t.late_p50_us);
  s.Bind(11, t.late_p99_us)
      .Bind(12, t.late_p999_us)
      .Bind(13, t.late_max_us)
      .Bind(14, t.tick_p50_us);
  s.Bind(15, t.tick_p99_us)
      .Bind(16, t.tick_p999_us)
      .Bind(17, t.tick_max_us)
      .Bind(18, t.late_histogram);
  s.Bind(19, t.recording_overflows).Bind(20, t.audio_underruns).Bind(21, t.priority);
  s.Bind(22, static_cast<std::int64_t>(t.memory_locked ? 1 : 0)).Bind(23, t.timer_slack_ns).Run();
}

std::vector<SideTiming> StudySideTimings(const Database& d, std::int64_t study_id) {
  Stmt s(
      d.handle(),
      "SELECT st.trial_id, st.attempt, st.side, st.loop, st.clock, st.rate_hz, "
      "st.achieved_rate_hz, st.ticks, "
      "st.deadline_misses, st.late_p50_us, st.late_p99_us, st.late_p999_us, st.late_max_us, "
      "st.tick_p50_us, "
      "st.tick_p99_us, st.tick_p999_us, st.tick_max_us, st.late_histogram, st.recording_overflows, "
      "st.audio_underruns, st.priority, st.memory_locked, st.timer_slack_ns "
      "FROM side_timing st JOIN trial t ON t.id = st.trial_id JOIN session se ON se.id = "
      "t.session_id "
      "JOIN participant p ON p.id = se.participant_id WHERE p.study_id = ? ORDER BY st.trial_id, "
      "st.id");
  s.Bind(1, study_id);
  std::vector<SideTiming> out;
  while (s.Step()) {
    SideTiming t;
    t.trial_id = s.Int(0);
    t.attempt = static_cast<int>(s.Int(1));
    t.side = s.Text(2);
    t.loop = s.Text(3);
    t.clock = s.Text(4);
    t.rate_hz = s.Real(5);
    t.achieved_rate_hz = s.Real(6);
    t.ticks = s.Int(7);
    t.deadline_misses = s.Int(8);
    t.late_p50_us = s.Real(9);
    t.late_p99_us = s.Real(10);
    t.late_p999_us = s.Real(11);
    t.late_max_us = s.Real(12);
    t.tick_p50_us = s.Real(13);
    t.tick_p99_us = s.Real(14);
    t.tick_p999_us = s.Real(15);
    t.tick_max_us = s.Real(16);
    t.late_histogram = s.Text(17);
    t.recording_overflows = s.Int(18);
    t.audio_underruns = s.Int(19);
    t.priority = s.Text(20);
    t.memory_locked = s.Int(21) != 0;
    t.timer_slack_ns = s.Int(22);
    out.push_back(std::move(t));
  }
  return out;
}

}  // namespace hapticlab::db
