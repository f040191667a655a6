#include "hapticlab/core/measurement.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>

#include "csv_internal.hpp"
#include "hapticlab/core/csv.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"

namespace hapticlab {

namespace {

// Bounds of the streaming reader (docs/formats.md, "Bounds"): 88 bytes per row held, so
// 5 million rows (8 minutes at 10 kHz) take about 460 MB; one line is at most 1 MiB.
constexpr std::size_t kMaxRows = 5'000'000;
constexpr std::size_t kMaxLineBytes = std::size_t{1} << 20;
constexpr std::size_t kMaxFileBytes = std::size_t{2} << 30;

// Lines of a stream, each bounded (a file without newlines is not read whole into a string).
class LineReader {
 public:
  LineReader(std::istream& in, const std::string& name) : in_(in), name_(name) {}
  bool Next(std::string* line) {
    buf_.resize(kMaxLineBytes + 2);
    in_.getline(buf_.data(), static_cast<std::streamsize>(buf_.size()));
    const auto got = static_cast<std::size_t>(in_.gcount());
    if (got == 0 && !in_) return false;
    ++number_;
    if (in_.fail() && !in_.eof())  // the buffer filled before a newline
      throw InputError(name_, number_, "", "line longer than 1 MiB");
    bytes_ += got;
    if (bytes_ > kMaxFileBytes)
      throw InputError(name_, number_, "", "file larger than the 2 GiB allowed");
    const bool newline = !in_.eof();  // getline counted the newline it consumed
    line->assign(buf_.data(), newline ? got - 1 : got);
    return true;
  }
  int number() const { return number_; }

 private:
  std::istream& in_;
  const std::string& name_;
  std::string buf_;
  int number_ = 0;
  std::size_t bytes_ = 0;
};

// The cell as a finite number (the messages of CsvTable::Number, then finiteness).
double Finite(const std::string& s, const std::string& name, int line, const std::string& column) {
  if (s.empty()) throw InputError(name, line, column, "empty cell, expected a number");
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s.c_str(), &end);
  if (end == s.c_str() || end != s.c_str() + s.size())  // a NUL byte ends no number
    throw InputError(name, line, column, "expected a number, got '" + s + "'");
  if (!std::isfinite(v)) throw InputError(name, line, column, "value is not finite");
  return v;
}

struct Columns {
  std::size_t t = 0, x = 0, y = 0, z = 0;
  std::optional<std::size_t> vx, vy, vz, fx, fy, fz, acc, recording;
  bool has_v = false;
  bool vibration_only = false;  ///< t_s and acc_mps2 only (MeasurementReadOptions)
};

// The header's columns; throws for a missing required one (CsvTable::Require's message).
Columns FindColumns(const CsvTable& t, const MeasurementReadOptions& o, Measurement* m) {
  Columns c;
  c.t = t.Require("t_s");
  if (o.allow_vibration_only && !t.Find("x_m") && !t.Find("y_m") && !t.Find("z_m") &&
      t.Find("acc_mps2")) {
    // A vibration recording without kinematics.
    c.vibration_only = true;
    c.acc = t.Find("acc_mps2");
    m->has_kinematics = m->has_forces = false;
    m->has_acceleration = true;
    return c;
  }
  c.x = t.Require("x_m"), c.y = t.Require("y_m"), c.z = t.Require("z_m");
  c.vx = t.Find("vx_mps"), c.vy = t.Find("vy_mps"), c.vz = t.Find("vz_mps");
  c.has_v = c.vx && c.vy && c.vz;
  if (!c.has_v && !o.kinematics_only) t.Require(!c.vx ? "vx_mps" : !c.vy ? "vy_mps" : "vz_mps");
  c.fx = t.Find("fx_N"), c.fy = t.Find("fy_N"), c.fz = t.Find("fz_N");
  m->has_forces = c.fx && c.fy && c.fz;
  if (!m->has_forces && !o.kinematics_only) t.Require(!c.fx ? "fx_N" : !c.fy ? "fy_N" : "fz_N");
  c.acc = t.Find("acc_mps2");
  m->has_acceleration = c.acc.has_value();
  c.recording = t.Find("recording");
  return c;
}

// Reads the file line by line into rows of numbers: the text and its cells are never held
// whole (a CsvTable of a 2e6-row file took 925 MB).
Measurement ParseStream(std::istream& in, const std::string& name,
                        const MeasurementReadOptions& o) {
  Measurement m;
  m.file = name;
  CsvTable head;  // comments, metadata and header, as ParseCsv reads them
  head.file = name;
  Columns c;
  LineReader lines(in, name);
  std::string line;
  while (lines.Next(&line)) {
    const int lineno = lines.number();
    if (lineno == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (internal::Trim(line).empty()) continue;
    if (head.header.empty() && line[0] == '#') {
      const std::string text = line.substr(1);
      head.comments.push_back(internal::Trim(text));
      if (const auto colon = text.find(':'); colon != std::string::npos)
        head.metadata[internal::Trim(text.substr(0, colon))] =
            internal::Trim(text.substr(colon + 1));
      continue;
    }
    auto cells = internal::SplitLine(line, name, lineno);
    if (head.header.empty()) {
      head.header = std::move(cells);
      if (head.comments.empty() || head.comments[0].rfind("hapticlab-measurement v1", 0) != 0)
        throw InputError(name, 1, "", "first line must be '# hapticlab-measurement v1'");
      c = FindColumns(head, o, &m);
      continue;
    }
    if (cells.size() != head.header.size())
      throw InputError(name, lineno, "",
                       "row has " + std::to_string(cells.size()) + " cells, header has " +
                           std::to_string(head.header.size()));
    if (m.rows.size() >= kMaxRows)
      throw InputError(name, lineno, "",
                       "more than " + std::to_string(kMaxRows) + " rows (split the recording)");
    auto num = [&](std::size_t col) { return Finite(cells[col], name, lineno, head.header[col]); };
    MeasurementRow row;
    row.t_s = num(c.t);
    if (!c.vibration_only) row.p_m = {num(c.x), num(c.y), num(c.z)};
    if (c.has_v) row.v_mps = {num(*c.vx), num(*c.vy), num(*c.vz)};
    if (m.has_forces) row.f_N = {num(*c.fx), num(*c.fy), num(*c.fz)};
    if (c.acc) row.acc_mps2 = num(*c.acc);
    if (c.recording) {
      const double id = num(*c.recording);
      if (!(id >= 0 && id <= 1e6 && id == std::floor(id)))
        throw InputError(name, lineno, "recording",
                         "expected a recording id (an integer from 0 to 1000000)");
      m.recording_ids.push_back(static_cast<int>(id));
    }
    if (!m.rows.empty() && !(row.t_s > m.rows.back().t_s))
      throw InputError(
          name, lineno, "t_s",
          "time must increase (previous row has t_s = " + std::to_string(m.rows.back().t_s) + ")");
    m.rows.push_back(row);
    m.row_lines.push_back(lineno);
  }
  if (head.header.empty()) {
    if (head.comments.empty() || head.comments[0].rfind("hapticlab-measurement v1", 0) != 0)
      throw InputError(name, 1, "", "first line must be '# hapticlab-measurement v1'");
    throw InputError(name, 0, "", "no header row found");
  }
  m.metadata = head.metadata;
  if (auto it = m.metadata.find("material"); it != m.metadata.end()) m.material = it->second;
  if (!c.has_v && !c.vibration_only) {
    const std::size_t n = m.rows.size();
    for (std::size_t r = 0; r < n; ++r) {
      const std::size_t a = r == 0 ? 0 : r - 1, b = r + 1 == n ? r : r + 1;
      if (a != b)
        m.rows[r].v_mps = (m.rows[b].p_m - m.rows[a].p_m) / (m.rows[b].t_s - m.rows[a].t_s);
    }
  }
  return m;
}

}  // namespace

Measurement ParseMeasurementCsv(const std::string& text, const std::string& name,
                                const MeasurementReadOptions& o) {
  std::istringstream in(text);
  return ParseStream(in, name, o);
}

Measurement ReadMeasurementCsv(const std::string& path, const MeasurementReadOptions& o) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "", "cannot open measurement");
  return ParseStream(in, path, o);
}

void WriteMeasurementCsv(const std::string& path, const Measurement& m) {
  std::string text = "# hapticlab-measurement v1\n";
  if (!m.material.empty()) text += "# material: " + m.material + "\n";
  for (const auto& [k, v] : m.metadata)
    if (k != "material" && k != "hapticlab-measurement v1") text += "# " + k + ": " + v + "\n";
  text += "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N,fz_N";
  const bool ids = m.recording_ids.size() == m.rows.size() && !m.rows.empty();
  text += m.has_acceleration ? ",acc_mps2" : "";
  text += ids ? ",recording\n" : "\n";
  auto num = [&text](double v, char sep) {
    char buf[32];
    const int n = std::snprintf(buf, sizeof buf, "%.17g", v);
    text.append(buf, static_cast<std::size_t>(n));
    text += sep;
  };
  for (std::size_t i = 0; i < m.rows.size(); ++i) {
    const auto& r = m.rows[i];
    for (const double v : {r.t_s, r.p_m.x(), r.p_m.y(), r.p_m.z(), r.v_mps.x(), r.v_mps.y(),
                           r.v_mps.z(), r.f_N.x(), r.f_N.y()})
      num(v, ',');
    num(r.f_N.z(), m.has_acceleration || ids ? ',' : '\n');
    if (m.has_acceleration) num(r.acc_mps2, ids ? ',' : '\n');
    if (ids) text += std::to_string(m.recording_ids[i]) + "\n";
  }
  WriteTextFile(path, text);
}

}  // namespace hapticlab
