#include "hapticlab/runner/rig.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/core/toml_util.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/runner/open_rig.hpp"

namespace hapticlab::runner {
namespace {

const char* const kSideNames[2] = {"left", "right"};

// What is wrong with two axes for PoseFromAxes (empty: nothing).
std::string AxesProblem(const Eigen::Vector3d& x_axis, const Eigen::Vector3d& z_axis) {
  if (!(z_axis.norm() > 1e-9)) return "z_axis is zero";
  const Eigen::Vector3d z = z_axis.normalized();
  const Eigen::Vector3d xp = x_axis - x_axis.dot(z) * z;
  if (!(xp.norm() > 1e-6 * std::max(1.0, x_axis.norm())))
    return "x_axis is zero or parallel to z_axis";
  return {};
}

std::string Vec(const Eigen::Vector3d& v) {
  return fmt::format("[{:.6g}, {:.6g}, {:.6g}]", v.x(), v.y(), v.z());
}

// Positions and offsets in a rig file: a bench, not a building.
constexpr double kMaxRigLength_m = 10;

// Reads [x, y, z] at `t[key]`; reports a problem and keeps `*out` when malformed.
void ReadVec(const toml::table& t, const std::string& table, const char* key, Eigen::Vector3d* out,
             Diagnostics& d, const std::string& path, bool required) {
  const toml::node* n = t.get(key);
  const std::string field = table + "." + key;
  if (!n) {
    if (required)
      d.Add(path, static_cast<int>(t.source().begin.line), field, "missing; expected [x, y, z]");
    return;
  }
  const toml::array* a = n->as_array();
  const int line = static_cast<int>(n->source().begin.line);
  if (!a || a->size() != 3) {
    d.Add(path, line, field, "expected [x, y, z] (three numbers)");
    return;
  }
  Eigen::Vector3d v;
  for (std::size_t i = 0; i < 3; ++i) {
    const auto x = (*a)[i].value<double>();
    // Lengths of a bench rig lie within kMaxRigLength_m; axes are directions, but their
    // squares must stay finite when normalised.
    const double max_abs = field.ends_with("_m") ? kMaxRigLength_m : 1e6;
    if (!x || !(std::abs(*x) <= max_abs)) {
      d.Add(path, line, field,
            fmt::format("expected [x, y, z] (three finite numbers, each within +-{:g}{})", max_abs,
                        field.ends_with("_m") ? " m" : ""));
      return;
    }
    v[static_cast<Eigen::Index>(i)] = *x;
  }
  *out = v;
}

// A pose table {origin_m, x_axis, z_axis}.
void ReadPose(const toml::table& root, const std::string& name, Eigen::Isometry3d* out,
              Diagnostics& d, const std::string& path, bool required) {
  const toml::node* n = root.at_path(name).node();
  if (!n) {
    if (required) d.Add(path, 1, name, "missing table [" + name + "] {origin_m, x_axis, z_axis}");
    return;
  }
  const toml::table* t = n->as_table();
  if (!t) {
    d.Add(path, static_cast<int>(n->source().begin.line), name,
          "expected a table {origin_m, x_axis, z_axis}");
    return;
  }
  for (const auto& [k, v] : *t)
    if (k.str() != "origin_m" && k.str() != "x_axis" && k.str() != "z_axis")
      d.Add(path, static_cast<int>(v.source().begin.line), name + "." + std::string(k.str()),
            "unknown key (a typo?)");
  Eigen::Vector3d o = out->translation(), x = out->linear().col(0), z = out->linear().col(2);
  const std::size_t before = d.size();
  ReadVec(*t, name, "origin_m", &o, d, path, true);
  ReadVec(*t, name, "x_axis", &x, d, path, true);
  ReadVec(*t, name, "z_axis", &z, d, path, true);
  if (d.size() != before) return;
  if (const std::string problem = AxesProblem(x, z); !problem.empty())
    d.Add(path, static_cast<int>(t->source().begin.line), name, problem);
  else
    *out = PoseFromAxes(o, x, z);
}

}  // namespace

Eigen::Isometry3d PoseFromAxes(const Eigen::Vector3d& origin, const Eigen::Vector3d& x_axis,
                               const Eigen::Vector3d& z_axis) {
  const std::string problem = AxesProblem(x_axis, z_axis);
  HL_REQUIRE(problem.empty(), problem);
  const Eigen::Vector3d z = z_axis.normalized();
  const Eigen::Vector3d x = (x_axis - x_axis.dot(z) * z).normalized();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = z.cross(x);
  T.linear().col(2) = z;
  T.translation() = origin;
  return T;
}

Eigen::Isometry3d RigFile::DeviceFromSample(int side) const {
  // p_world = world_from_device * (p_point + tip) = world_from_sample * p_sample.
  Eigen::Isometry3d tip = Eigen::Isometry3d::Identity();
  tip.translation() = -tip_offset_m;
  return tip * world_from_device.inverse() * world_from_sample[static_cast<std::size_t>(side)];
}

RigFile ParseRig(const std::string& text, const std::string& path) {
  const toml::table doc = ParseTomlText(text, path);
  Diagnostics d;
  RigFile r = DefaultRig(DefaultBackendName());
  r.path = path;
  r.text = text;
  r.sha256 = db::HashText(text);
  for (const auto& [k, v] : doc) {
    static const char* known[] = {"device", "device_pose", "stylus", "force", "sample"};
    if (std::find(std::begin(known), std::end(known), k.str()) == std::end(known))
      d.Add(path, static_cast<int>(v.source().begin.line), std::string(k.str()),
            "unknown key (a typo?)");
  }
  if (const toml::node* n = doc.get("device")) {
    if (auto s = n->value<std::string>())
      r.device = *s;
    else
      d.Add(path, static_cast<int>(n->source().begin.line), "device",
            "expected a string (sim, falcon, ...)");
  }
  ReadPose(doc, "device_pose", &r.world_from_device, d, path, false);
  if (const toml::table* s = doc["stylus"].as_table())
    ReadVec(*s, "stylus", "tip_offset_m", &r.tip_offset_m, d, path, false);
  if (const toml::table* f = doc["force"].as_table()) {
    auto num = [&](const char* key, double* out, double lo, double hi) {
      const toml::node* n = f->get(key);
      if (!n) return;
      const auto v = n->value<double>();
      if (!v || !(*v >= lo && *v <= hi))
        d.Add(path, static_cast<int>(n->source().begin.line), std::string("force.") + key,
              fmt::format("expected a number in [{}, {}]", lo, hi));
      else
        *out = *v;
    };
    num("motor_units_per_Nm", &r.motor_units_per_Nm, 1, 1e7);
    num("max_force_N", &r.max_force_N, 0, 100);
  }
  for (int side = 0; side < 2; ++side)
    ReadPose(doc, std::string("sample.") + kSideNames[side],
             &r.world_from_sample[static_cast<std::size_t>(side)], d, path, true);
  d.ThrowIfAny();
  return r;
}

RigFile LoadRig(const std::string& path) { return ParseRig(ReadTextFile(path, "rig file"), path); }

std::string RigToToml(const RigFile& r) {
  auto pose = [](const std::string& name, const Eigen::Isometry3d& T) {
    return fmt::format("[{}]\norigin_m = {}\nx_axis = {}\nz_axis = {}\n", name,
                       Vec(T.translation()), Vec(T.linear().col(0)), Vec(T.linear().col(2)));
  };
  std::string s =
      "# HapticLab rig file: frames and calibration (docs/hardware.md). Lengths in metres.\n";
  s += fmt::format("device = \"{}\"\n\n", r.device);
  s += "# The device frame in the world (lab) frame.\n" + pose("device_pose", r.world_from_device) +
       "\n";
  s += fmt::format(
      "[stylus]\n# From the point the device reports to the stylus tip, device "
      "frame.\ntip_offset_m = {}\n\n",
      Vec(r.tip_offset_m));
  s += fmt::format(
      "[force]\nmotor_units_per_Nm = {:.8g}   # Falcon force calibration (docs/hardware.md)\n",
      r.motor_units_per_Nm);
  if (r.max_force_N > 0) s += fmt::format("max_force_N = {:.6g}\n", r.max_force_N);
  s += "\n# Each sample's frame in the world frame: origin on its surface, z out of it.\n";
  for (int side = 0; side < 2; ++side)
    s += pose(std::string("sample.") + kSideNames[side],
              r.world_from_sample[static_cast<std::size_t>(side)]) +
         "\n";
  return s;
}

RigFile DefaultRig(const std::string& device) {
  RigFile r;
  r.device = device;
  const RigBackend* backend = FindBackend(device);
  if (backend && backend->falcon_frame) {
    const Eigen::Vector3d up(0, 1, 0), right(1, 0, 0);
    r.world_from_sample[0] = PoseFromAxes({-0.025, -0.04, 0.125}, right, up);
    r.world_from_sample[1] = PoseFromAxes({0.025, -0.04, 0.125}, right, up);
  } else {
    r.world_from_sample[0].translation() = Eigen::Vector3d(-0.03, 0, 0);
    r.world_from_sample[1].translation() = Eigen::Vector3d(0.03, 0, 0);
  }
  r.text = RigToToml(r);
  r.sha256 = db::HashText(r.text);
  return r;
}

PlaneFit FitSamplePlane(const std::vector<Eigen::Vector3d>& pts, const Eigen::Vector3d& up_hint,
                        const std::string& source) {
  if (pts.size() < 3)
    throw InputError(source, 0, "points",
                     fmt::format("a plane needs at least 3 touches, got {}", pts.size()));
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : pts) c += p;
  c /= static_cast<double>(pts.size());
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) S += (p - c) * (p - c).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(S);
  // Eigenvalues ascending: the smallest is the normal; the middle one must not vanish.
  const double spread = std::sqrt(es.eigenvalues()[1] / static_cast<double>(pts.size()));
  if (!(spread > 1e-4))
    throw InputError(source, 0, "points",
                     "the touches lie on a line (or one point): touch three spread-out points");
  Eigen::Vector3d n = es.eigenvectors().col(0);
  if (n.dot(up_hint) < 0) n = -n;
  Eigen::Vector3d x = pts[1] - pts[0];
  if ((x - x.dot(n) * n).norm() < 1e-4)
    x = es.eigenvectors().col(2);  // first two touches too close
  PlaneFit f;
  f.device_from_sample = PoseFromAxes(c, x, n);
  double ss = 0;
  for (const auto& p : pts) {
    const double r = std::abs((p - c).dot(n));
    ss += r * r;
    f.max_residual_m = std::max(f.max_residual_m, r);
  }
  f.rms_residual_m = std::sqrt(ss / static_cast<double>(pts.size()));
  return f;
}

}  // namespace hapticlab::runner
