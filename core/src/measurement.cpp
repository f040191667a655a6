#include "hapticlab/core/measurement.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"

namespace hapticlab {
namespace {

// t_s and acc_mps2 only: a vibration recording without kinematics.
Measurement ParseVibrationOnly(const CsvTable& t, std::size_t ct, std::size_t ca, Measurement m) {
  m.has_kinematics = m.has_forces = false;
  m.has_acceleration = true;
  m.rows.resize(t.rows.size());
  m.row_lines = t.row_lines;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    for (const std::size_t c : {ct, ca})
      if (!std::isfinite(t.Number(r, c)))
        throw InputError(m.file, t.row_lines[r], t.header[c], "value is not finite");
    m.rows[r].t_s = t.Number(r, ct);
    m.rows[r].acc_mps2 = t.Number(r, ca);
    if (r > 0 && !(m.rows[r].t_s > m.rows[r - 1].t_s))
      throw InputError(m.file, t.row_lines[r], "t_s", "time must increase");
  }
  return m;
}

}  // namespace

Measurement ParseMeasurementCsv(const std::string& text, const std::string& name,
                                const MeasurementReadOptions& o) {
  const CsvTable t = ParseCsv(text, name);
  Measurement m;
  m.file = name;
  m.metadata = t.metadata;
  if (auto it = t.metadata.find("material"); it != t.metadata.end()) m.material = it->second;
  const bool tagged =
      !t.comments.empty() && t.comments[0].rfind("hapticlab-measurement v1", 0) == 0;
  if (!tagged) throw InputError(name, 1, "", "first line must be '# hapticlab-measurement v1'");
  const std::size_t ct = t.Require("t_s");
  if (o.allow_vibration_only && !t.Find("x_m") && !t.Find("y_m") && !t.Find("z_m") &&
      t.Find("acc_mps2"))
    return ParseVibrationOnly(t, ct, *t.Find("acc_mps2"), std::move(m));
  const std::size_t cx = t.Require("x_m"), cy = t.Require("y_m"), cz = t.Require("z_m");
  const auto cvx = t.Find("vx_mps"), cvy = t.Find("vy_mps"), cvz = t.Find("vz_mps");
  const bool has_v = cvx && cvy && cvz;
  if (!has_v && !o.kinematics_only) t.Require(!cvx ? "vx_mps" : !cvy ? "vy_mps" : "vz_mps");
  const auto cfx = t.Find("fx_N"), cfy = t.Find("fy_N"), cfz = t.Find("fz_N");
  m.has_forces = cfx && cfy && cfz;
  if (!m.has_forces && !o.kinematics_only) t.Require(!cfx ? "fx_N" : !cfy ? "fy_N" : "fz_N");
  const auto ca = t.Find("acc_mps2");
  m.has_acceleration = ca.has_value();
  m.rows.resize(t.rows.size());
  m.row_lines = t.row_lines;
  auto num = [&](std::size_t r, std::size_t c) {
    const double v = t.Number(r, c);
    if (!std::isfinite(v))
      throw InputError(name, t.row_lines[r], t.header[c], "value is not finite");
    return v;
  };
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    MeasurementRow& row = m.rows[r];
    row.t_s = num(r, ct);
    row.p_m = {num(r, cx), num(r, cy), num(r, cz)};
    if (has_v) row.v_mps = {num(r, *cvx), num(r, *cvy), num(r, *cvz)};
    if (m.has_forces) row.f_N = {num(r, *cfx), num(r, *cfy), num(r, *cfz)};
    if (ca) row.acc_mps2 = num(r, *ca);
    if (r > 0 && !(row.t_s > m.rows[r - 1].t_s))
      throw InputError(
          name, t.row_lines[r], "t_s",
          "time must increase (previous row has t_s = " + std::to_string(m.rows[r - 1].t_s) + ")");
  }
  if (!has_v) {
    const std::size_t n = m.rows.size();
    for (std::size_t r = 0; r < n; ++r) {
      const std::size_t a = r == 0 ? 0 : r - 1, b = r + 1 == n ? r : r + 1;
      if (a != b)
        m.rows[r].v_mps = (m.rows[b].p_m - m.rows[a].p_m) / (m.rows[b].t_s - m.rows[a].t_s);
    }
  }
  return m;
}

Measurement ReadMeasurementCsv(const std::string& path, const MeasurementReadOptions& o) {
  return ParseMeasurementCsv(ReadTextFile(path, "measurement"), path, o);
}

void WriteMeasurementCsv(const std::string& path, const Measurement& m) {
  std::string text = "# hapticlab-measurement v1\n";
  if (!m.material.empty()) text += "# material: " + m.material + "\n";
  for (const auto& [k, v] : m.metadata)
    if (k != "material" && k != "hapticlab-measurement v1") text += "# " + k + ": " + v + "\n";
  text += "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N,fz_N";
  text += m.has_acceleration ? ",acc_mps2\n" : "\n";
  auto num = [&text](double v, char sep) {
    char buf[32];
    const int n = std::snprintf(buf, sizeof buf, "%.17g", v);
    text.append(buf, static_cast<std::size_t>(n));
    text += sep;
  };
  for (const auto& r : m.rows) {
    for (const double v : {r.t_s, r.p_m.x(), r.p_m.y(), r.p_m.z(), r.v_mps.x(), r.v_mps.y(),
                           r.v_mps.z(), r.f_N.x(), r.f_N.y()})
      num(v, ',');
    num(r.f_N.z(), m.has_acceleration ? ',' : '\n');
    if (m.has_acceleration) num(r.acc_mps2, '\n');
  }
  WriteTextFile(path, text);
}

}  // namespace hapticlab
