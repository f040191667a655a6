#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/force_record.hpp"
#include "interchange_internal.hpp"
#include "sqlite_util.hpp"

namespace hapticlab::db::internal {
namespace {

struct Suffix {
  const char* suffix;
  const char* unit;
  const char* quantity;
};
// Longest first: "_mps2" before "_mps".
constexpr Suffix kSuffixes[] = {{"_mps2", "m/s^2", "acceleration"},
                                {"_mps", "m/s", "velocity"},
                                {"_N", "N", "force"},
                                {"_m", "m", "position"},
                                {"_s", "s", "time"},
                                {"_Hz", "Hz", "frequency"}};

// Meanings of the recorded channels (db/force_record.hpp); other names get a generic
// sentence from their unit suffix.
std::string KnownMeaning(const std::string& name) {
  for (const auto& c : kForceChannels)
    if (c.name == name) return std::string(c.meaning);
  if (kVibrationChannel.name == name) return std::string(kVibrationChannel.meaning);
  return {};
}

}  // namespace

ChannelMeaning DescribeChannel(const std::string& name) {
  ChannelMeaning m;
  m.description = KnownMeaning(name);
  for (const auto& s : kSuffixes) {
    const std::string suf = s.suffix;
    if (name.size() > suf.size() && name.ends_with(suf)) {
      m.unit = s.unit;
      if (m.description.empty()) m.description = std::string(s.quantity) + " (" + name + ")";
      return m;
    }
  }
  m.unit = "n/a";
  if (m.description.empty()) m.description = name + " (dimensionless)";
  return m;
}

std::string Alnum(const std::string& s) {
  std::string out;
  for (const char c : s)
    if (std::isalnum(static_cast<unsigned char>(c))) out += c;
  return out;
}

std::optional<std::int64_t> ParseUtcMicros(const std::string& iso) {
  int y = 0, mo = 0, d = 0, h = 0, mi = 0;
  double sec = 0;
  char z = 0;
  if (std::sscanf(iso.c_str(), "%d-%d-%dT%d:%d:%lf%c", &y, &mo, &d, &h, &mi, &sec, &z) != 7 ||
      z != 'Z' || !(sec >= 0 && sec < 61))
    return std::nullopt;
  std::tm tm{};
  tm.tm_year = y - 1900;
  tm.tm_mon = mo - 1;
  tm.tm_mday = d;
  tm.tm_hour = h;
  tm.tm_min = mi;
  tm.tm_sec = 0;
  return static_cast<std::int64_t>(timegm(&tm)) * 1000000 + std::llround(sec * 1e6);
}

double StreamRecording::end_s() const {
  double e = 0;
  for (const auto& c : chunks)
    e = std::max(e, c.start_time_s + static_cast<double>(c.sample_count()) / c.rate_hz);
  return e;
}

std::size_t StreamRecording::sample_count() const {
  std::size_t n = 0;
  for (const auto& c : chunks) n += c.sample_count();
  return n;
}

namespace {

// The stimulus side a stream belongs to: the name's prefix before '_' ("left_force").
std::string Side(const std::string& stream) { return stream.substr(0, stream.find('_')); }

int SideRank(const std::string& side) { return side == "left" ? 0 : side == "right" ? 1 : 2; }

void PlaceOnClock(const Database& db, SessionRecord* s) {
  const auto session_start = ParseUtcMicros(s->session.started_at);
  if (!session_start)
    throw std::runtime_error(db.path() + ": session " + std::to_string(s->session.id) +
                             ": started_at '" + s->session.started_at +
                             "' is not an ISO-8601 UTC stamp");
  // The trials' start stamps are not in the typed API's Trial; read them here.
  auto since_start = [&](const std::string& stamp) {
    const auto us = ParseUtcMicros(stamp);
    return us ? static_cast<double>(*us - *session_start) * 1e-6 : 0.0;
  };
  std::map<std::int64_t, double> starts;
  {
    Stmt q(db.handle(), "SELECT id, coalesce(started_at,'') FROM trial WHERE session_id=?");
    q.Bind(1, s->session.id);
    while (q.Step()) starts[q.Int(0)] = since_start(q.Text(1));
  }
  for (auto& t : s->trials) t.wall_start_s = starts[t.trial.id];
  std::stable_sort(
      s->trials.begin(), s->trials.end(), [](const TrialRecord& a, const TrialRecord& b) {
        return a.wall_start_s != b.wall_start_s ? a.wall_start_s < b.wall_start_s
                                                : a.trial.plan_index < b.trial.plan_index;
      });
  double free_from = 0;  // where the previous trial's stimuli and ratings end
  for (auto& t : s->trials) {
    t.origin_s = std::max(t.wall_start_s, free_from);
    // Sides back to back in the order the participant meets them.
    std::map<std::pair<int, std::string>, double> side_len;
    for (const auto& r : t.streams) {
      auto& len = side_len[{SideRank(Side(r.stream)), Side(r.stream)}];
      len = std::max(len, r.end_s());
    }
    std::map<std::string, double> side_offset;
    double at = 0;
    for (const auto& [key, len] : side_len) {
      side_offset[key.second] = at;
      at += len;
    }
    t.stimulus_s = at;
    for (const auto& r : t.streams) t.offset_s[r.stream] = side_offset[Side(r.stream)];
    double respond = 0;
    for (const auto& r : t.ratings) respond = std::max(respond, r.response_time_s);
    free_from = t.origin_s + t.stimulus_s + respond;
  }
  for (const auto& e : s->events) {
    const double w = since_start(e.created_at);
    double shift = 0;
    for (const auto& t : s->trials)
      if (t.wall_start_s <= w) shift = t.origin_s - t.wall_start_s;
    s->event_time_s.push_back(w + shift);
  }
}

}  // namespace

std::vector<SessionRecord> LoadSessions(const Database& db, const std::string& participant) {
  std::vector<SessionRecord> out;
  bool found = participant.empty();
  for (const auto& st : db.Studies()) {
    for (const auto& p : db.Participants(st.id)) {
      if (!participant.empty() && p.code != participant) continue;
      found = true;
      int number = 0;
      for (const auto& se : db.Sessions(p.id)) {
        SessionRecord s;
        s.study = st;
        s.participant = p;
        s.session = se;
        s.number = ++number;
        for (const auto& t : db.Trials(se.id)) {
          if (t.status != TrialStatus::kCompleted) continue;
          TrialRecord r;
          r.trial = t;
          r.ratings = db.Ratings(t.id);
          // Chunks come ordered by stream, then time.
          for (auto& c : db.TrajectoryChunks(t.id)) {
            if (r.streams.empty() || r.streams.back().stream != c.stream) {
              r.streams.push_back(
                  {.stream = c.stream, .rate_hz = c.rate_hz, .channels = c.channels});
            }
            auto& rec = r.streams.back();
            if (rec.rate_hz != c.rate_hz || rec.channels != c.channels)
              throw std::runtime_error(db.path() + ": trial " + std::to_string(t.id) + ", stream " +
                                       c.stream + ": chunks disagree on rate or channels");
            rec.chunks.push_back(std::move(c));
          }
          s.trials.push_back(std::move(r));
        }
        s.events = db.Events(se.id);
        PlaceOnClock(db, &s);
        out.push_back(std::move(s));
      }
    }
  }
  if (!found)
    throw InputError(db.path(), 0, "participant",
                     "no participant " + participant + " in this database");
  return out;
}

}  // namespace hapticlab::db::internal
