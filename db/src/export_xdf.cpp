// XDF export: one file per session, a stream per recorded channel set plus two marker
// streams, every timestamp on the session clock (interchange_internal.hpp).

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/export_formats.hpp"
#include "hapticlab/db/interchange.hpp"
#include "interchange_internal.hpp"
#include "xdf_writer.hpp"

namespace hapticlab::db {
namespace {

namespace fs = std::filesystem;
using internal::SessionRecord;
using internal::XmlEscape;

std::string Tag(const std::string& name, const std::string& text) {
  return "<" + name + ">" + XmlEscape(text) + "</" + name + ">";
}
std::string Num(double v) { return fmt::format("{:.17g}", v); }

// "left_force" -> "Force": the kind after the side prefix.
std::string StreamType(const std::string& stream) {
  const auto u = stream.find('_');
  std::string k = u == std::string::npos ? stream : stream.substr(u + 1);
  if (!k.empty()) k[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(k[0])));
  return k;
}

std::string ChannelType(const std::string& unit) {
  if (unit == "m") return "Position";
  if (unit == "m/s") return "Velocity";
  if (unit == "m/s^2") return "Acceleration";
  if (unit == "N") return "Force";
  return "Flag";
}

struct DataStream {
  std::uint32_t id = 0;
  std::string name;
  double rate_hz = 0;
  std::vector<std::string> channels;
  std::size_t samples = 0;
  double first_s = 0, last_s = 0;
};

std::string CommonDesc(const SessionRecord& s) {
  return "<hapticlab>" + Tag("study", s.study.name) + Tag("participant", s.participant.code) +
         Tag("session", std::to_string(s.number)) + Tag("device", s.session.device) +
         Tag("software_version", s.session.software_version) +
         Tag("protocol_sha256", s.study.protocol_hash) +
         Tag("clock",
             "seconds since the session's start; a trial starts at its recorded start time, or "
             "where the "
             "previous trial's stimuli and ratings end when later (simulated sessions run faster "
             "than real "
             "time); the right stimulus follows the left") +
         "</hapticlab>";
}

std::string Header(const std::string& name, const std::string& type, std::size_t channels,
                   double rate_hz, const std::string& format, const std::string& source_id,
                   const std::string& desc) {
  return Tag("name", name) + Tag("type", type) + Tag("channel_count", std::to_string(channels)) +
         Tag("nominal_srate", rate_hz > 0 ? Num(rate_hz) : "0") + Tag("channel_format", format) +
         Tag("source_id", source_id) + Tag("version", "1.1") + Tag("created_at", "0") + "<desc>" +
         desc + "</desc>";
}

std::string Footer(double first_s, double last_s, std::size_t n) {
  return Tag("first_timestamp", Num(first_s)) + Tag("last_timestamp", Num(last_s)) +
         Tag("sample_count", std::to_string(n)) + "<clock_offsets></clock_offsets>";
}

// The XDF stream of a recording: one per (stream name, rate, channel layout), in order of first
// appearance; added to `streams` when new (a name taken by another layout gets "_<id>").
DataStream& StreamOf(std::vector<DataStream>& streams, const internal::StreamRecording& r) {
  for (auto& d : streams)
    if (d.name == r.stream && d.rate_hz == r.rate_hz && d.channels == r.channels) return d;
  DataStream d;
  d.id = static_cast<std::uint32_t>(streams.size() + 1);
  d.name = r.stream;
  for (const auto& e : streams)
    if (e.name == r.stream) d.name = r.stream + "_" + std::to_string(d.id);
  d.rate_hz = r.rate_hz;
  d.channels = r.channels;
  streams.push_back(d);
  return streams.back();
}

// A data stream's header: its channels (label, unit, type, description) and the session.
void WriteDataHeader(internal::XdfWriter& w, const DataStream& d, const SessionRecord& s,
                     const std::string& source) {
  std::string ch = "<channels>";
  for (const auto& c : d.channels) {
    const auto m = internal::DescribeChannel(c);
    ch += "<channel>" + Tag("label", c) + Tag("unit", m.unit) + Tag("type", ChannelType(m.unit)) +
          Tag("description", m.description) + "</channel>";
  }
  ch += "</channels>";
  w.StreamHeader(d.id, Header(d.name, StreamType(d.name), d.channels.size(), d.rate_hz, "float32",
                              source + ":" + d.name, ch + CommonDesc(s)));
}

// Every recorded chunk on the session clock; returns the samples written.
std::size_t WriteDataSamples(internal::XdfWriter& w, const SessionRecord& s,
                             std::vector<DataStream>& streams) {
  std::size_t written = 0;
  for (const auto& t : s.trials)
    for (const auto& r : t.streams) {
      auto& d = StreamOf(streams, r);
      for (const auto& c : r.chunks) {
        const std::size_t n = c.sample_count();
        if (n == 0) continue;
        const double t0 = t.origin_s + t.offset_s.at(r.stream) + c.start_time_s;
        w.FloatSamples(d.id, c.channels.size(), c.samples.data(), n, t0);
        if (d.samples == 0) d.first_s = t0;
        d.last_s = t0 + static_cast<double>(n - 1) / c.rate_hz;
        d.samples += n;
        written += n;
      }
    }
  return written;
}

using Markers = std::vector<std::pair<double, std::string>>;

// The event markers: trial starts and logged events, time-ordered (a stable sort keeps a
// trial's start before events stamped at the same instant).
Markers EventMarkers(const SessionRecord& s) {
  Markers events;
  for (const auto& t : s.trials) {
    const auto& x = t.trial;
    events.emplace_back(t.origin_s,
                        nlohmann::json{{"marker", "trial_start"},
                                       {"trial", x.plan_index + 1},
                                       {"phase", std::string(NameOf(kPhaseKindNames, x.phase))},
                                       {"material", x.material},
                                       {"comparison", x.comparison},
                                       {"method", x.method},
                                       {"repetition", x.repetition},
                                       {"left", x.left},
                                       {"right", x.right},
                                       {"attempts", x.attempts},
                                       {"stimulus_s", t.stimulus_s}}
                            .dump());
  }
  for (std::size_t i = 0; i < s.events.size(); ++i) {
    const auto& e = s.events[i];
    nlohmann::json j{{"marker", "event"},
                     {"kind", std::string(NameOf(kEventKindNames, e.kind))},
                     {"detail", e.detail},
                     {"established_by", e.established_by}};
    for (const auto& t : s.trials)
      if (e.trial_id && *e.trial_id == t.trial.id) j["trial"] = t.trial.plan_index + 1;
    events.emplace_back(s.event_time_s[i], j.dump());
  }
  std::stable_sort(events.begin(), events.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  return events;
}

// The rating markers, each at its response after the trial's stimuli, time-ordered.
Markers RatingMarkers(const SessionRecord& s) {
  Markers ratings;
  for (const auto& t : s.trials)
    for (const auto& r : t.ratings)
      ratings.emplace_back(t.origin_s + t.stimulus_s + r.response_time_s,
                           nlohmann::json{{"trial", t.trial.plan_index + 1},
                                          {"criterion", r.criterion},
                                          {"score", r.score},
                                          {"response_time_s", r.response_time_s},
                                          {"source", r.source}}
                               .dump());
  std::stable_sort(ratings.begin(), ratings.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  return ratings;
}

// Writes one session's file; returns it with its stream and sample counts.
ExportedFile WriteSession(const SessionRecord& s, const std::string& path) {
  internal::XdfWriter w(path);
  const std::string source =
      "hapticlab:" + s.study.name + ":" + s.participant.code + ":ses-" + std::to_string(s.number);
  std::vector<DataStream> streams;
  for (const auto& t : s.trials)
    for (const auto& r : t.streams) StreamOf(streams, r);
  for (const auto& d : streams) WriteDataHeader(w, d, s, source);
  const auto events_id = static_cast<std::uint32_t>(streams.size() + 1);
  const auto ratings_id = events_id + 1;
  const std::string marker_ch =
      "<channels><channel><label>marker</label><type>Marker</type>"
      "<description>a JSON object per marker</description></channel></channels>";
  w.StreamHeader(events_id, Header("events", "Markers", 1, 0, "string", source + ":events",
                                   marker_ch + CommonDesc(s)));
  w.StreamHeader(ratings_id, Header("ratings", "Markers", 1, 0, "string", source + ":ratings",
                                    marker_ch + CommonDesc(s)));

  std::size_t written = WriteDataSamples(w, s, streams);
  const Markers events = EventMarkers(s);
  const Markers ratings = RatingMarkers(s);
  for (const auto& [id, list] : {std::pair{events_id, &events}, std::pair{ratings_id, &ratings}}) {
    std::vector<std::string> v;
    std::vector<double> ts;
    for (const auto& [time, text] : *list) ts.push_back(time), v.push_back(text);
    w.StringSamples(id, v, ts);
    written += v.size();
  }

  for (const auto& d : streams) w.StreamFooter(d.id, Footer(d.first_s, d.last_s, d.samples));
  w.StreamFooter(events_id, Footer(events.empty() ? 0 : events.front().first,
                                   events.empty() ? 0 : events.back().first, events.size()));
  w.StreamFooter(ratings_id, Footer(ratings.empty() ? 0 : ratings.front().first,
                                    ratings.empty() ? 0 : ratings.back().first, ratings.size()));
  w.Close();
  return {.path = path, .rows = 0, .streams = streams.size() + 2, .samples = written};
}

std::string Progress(const SessionRecord& s, std::size_t sessions, std::size_t streams,
                     std::size_t samples) {
  return fmt::format("{}: {} session{}, {} streams, {} samples", s.participant.code, sessions,
                     sessions == 1 ? "" : "s", streams, samples);
}

}  // namespace

std::vector<ExportedFile> ExportXdf(const Database& db, const std::string& out,
                                    const std::string& participant,
                                    const ExportProgress& progress) {
  const auto sessions = internal::LoadSessions(db, participant);
  std::vector<ExportedFile> files;
  if (out.ends_with(".xdf")) {
    if (sessions.size() != 1)
      throw InputError(
          out, 0, "out",
          fmt::format("a file name holds one session and the selection has {}; name a directory, "
                      "or choose one participant (--participant CODE)",
                      sessions.size()));
    files.push_back(WriteSession(sessions[0], out));
    if (progress) progress(Progress(sessions[0], 1, files.back().streams, files.back().samples));
    return files;
  }
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw std::runtime_error(out + ": cannot create directory: " + ec.message());
  std::size_t n = 0, streams = 0, samples = 0;  // of the participant so far
  for (std::size_t i = 0; i < sessions.size(); ++i) {
    const auto& s = sessions[i];
    const std::string path =
        (fs::path(out) / fmt::format("sub-{}_ses-{}_task-{}.xdf", s.participant.code, s.number,
                                     internal::Alnum(s.study.name)))
            .string();
    files.push_back(WriteSession(s, path));
    ++n, streams += files.back().streams, samples += files.back().samples;
    if (i + 1 == sessions.size() || sessions[i + 1].participant.id != s.participant.id) {
      if (progress) progress(Progress(s, n, streams, samples));
      n = streams = samples = 0;
    }
  }
  return files;
}

ExportFormat XdfExportFormat() {
  ExportFormat f;
  f.name = "xdf";
  f.help =
      "XDF (Lab Streaming Layer) files, one per session: a stream per trajectory\n"
      "stream plus event and rating marker streams on one clock; --out FILE.xdf (one\n"
      "session: pick it with --participant) or --out DIR (one file per session)";
  f.selects_participants = true;
  f.counts_streams = true;
  f.file_extension = ".xdf";
  f.write = [](const Database& db, const ExportRequest& r) {
    return ExportXdf(db, r.out, r.participant, r.progress);
  };
  f.describe = [](const std::vector<ExportedFile>& files) {
    std::size_t streams = 0, samples = 0;
    for (const auto& x : files) streams += x.streams, samples += x.samples;
    return fmt::format("{} XDF file{}, {} streams, {} samples", files.size(),
                       files.size() == 1 ? "" : "s", streams, samples);
  };
  return f;
}

}  // namespace hapticlab::db
