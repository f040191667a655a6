#include "hapticlab/renderer/force.hpp"

#include <cmath>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab::renderer {

ForceAlgorithm ParseForceAlgorithm(const std::string& name, const std::string& source) {
  if (name == "wall") return ForceAlgorithm::kWall;
  if (name == "norm") return ForceAlgorithm::kNorm;
  if (name == "fric1") return ForceAlgorithm::kFric1;
  if (name == "fric2") return ForceAlgorithm::kFric2;
  if (name == "none") return ForceAlgorithm::kNone;
  throw InputError(source, 0, "algorithm", "wall, norm, fric1, fric2 or none (got '" + name + "')");
}

const char* ToString(ForceAlgorithm a) {
  switch (a) {
    case ForceAlgorithm::kWall:
      return "wall";
    case ForceAlgorithm::kNorm:
      return "norm";
    case ForceAlgorithm::kFric1:
      return "fric1";
    case ForceAlgorithm::kFric2:
      return "fric2";
    case ForceAlgorithm::kNone:
      return "none";
  }
  return "?";
}

double SinThetaT(double dhdx, double dhdy, double ux, double uy) noexcept {
  const double s = dhdx * ux + dhdy * uy;
  return s / std::sqrt(1.0 + s * s);
}

ForceModel::ForceModel(const MaterialModel& m, ForceAlgorithm algorithm,
                       double base_stiffness_N_per_m)
    : contact_(m.contact), friction_(m.friction), geometry_(m.geometry), algorithm_(algorithm) {
  if (!geometry_) geometry_ = std::make_shared<HeightMap>(HeightMap::Flat());
  if (contact_.base.K == 0) {
    if (!(base_stiffness_N_per_m > 0))
      throw InputError(m.source_path.empty() ? m.name : m.source_path, 0, "contact.base",
                       "a base stiffness: the material gives none and the device's is not > 0");
    contact_.base = {base_stiffness_N_per_m, 0, 1};
    contact_.base_model = BaseModel::kLinear;
  }
}

void ForceModel::Reset() noexcept {
  dahl_N_.setZero();
  had_contact_ = false;
}

ForceOutput ForceModel::Step(const ToolState& s) noexcept {
  ForceOutput out;
  const double x = s.p_m.x(), y = s.p_m.y(), z = s.p_m.z();
  const Eigen::Vector2d v_t(s.v_mps.x(), s.v_mps.y());
  out.tangential_speed_mps = v_t.norm();
  const bool flat = algorithm_ == ForceAlgorithm::kWall || algorithm_ == ForceAlgorithm::kNone;

  // Texture layer geometry at the tool: top T(x) and its slope.
  const HeightSample hs = flat ? HeightSample{} : geometry_->Sample(x, y);
  const double top_m = contact_.layer_thickness_m + (flat ? 0.0 : hs.h_m - geometry_->min_m());
  const double top_rate = flat ? 0.0 : hs.dhdx * s.v_mps.x() + hs.dhdy * s.v_mps.y();

  // Penetrations, eq. (4.14) and the base below z = 0.
  double d_t = 0, d_t_rate = 0;
  if (z < 0) {
    d_t = top_m;
    d_t_rate = top_rate;
  } else if (z < top_m) {
    d_t = top_m - z;
    d_t_rate = top_rate - s.v_mps.z();
  }
  const double d_b = z < 0 ? -z : 0.0;
  const double d_b_rate = z < 0 ? -s.v_mps.z() : 0.0;

  const double f_m = HuntCrossleyForce(contact_.texture, d_t, d_t_rate);
  const double f_b = contact_.base_model == BaseModel::kLinear
                         ? contact_.base.K * d_b
                         : HuntCrossleyForce(contact_.base, d_b, d_b_rate);
  out.normal_force_N = f_m + f_b;  // both along z_hat, so |F_m + F_b| is their sum
  out.penetration_m = d_t + d_b;
  out.in_contact = out.penetration_m > 0;

  // Dahl friction along the tangential displacement since the last tick.
  const Eigen::Vector2d xy(x, y);
  const double f_c = friction_.mu_k * out.normal_force_N;
  if (!out.in_contact || f_c <= 0) {
    dahl_N_.setZero();
  } else if (had_contact_) {
    const Eigen::Vector2d ds = xy - prev_xy_m_;
    const double len = ds.norm();
    if (len > 0) {
      const Eigen::Vector2d target = f_c * ds / len;
      dahl_N_ = target + (dahl_N_ - target) * std::exp(-friction_.kappa_N_per_m * len / f_c);
    }
    // Bristle force cannot exceed the Coulomb level when the load drops.
    const double mag = dahl_N_.norm();
    if (mag > f_c) dahl_N_ *= f_c / mag;
  }
  prev_xy_m_ = xy;
  had_contact_ = out.in_contact;
  const Eigen::Vector2d f_f = out.in_contact
                                  ? Eigen::Vector2d(-(dahl_N_ + friction_.mu_b_Ns_per_m * v_t))
                                  : Eigen::Vector2d::Zero();

  // Force-texture algorithm.
  double gain = 1.0;
  Eigen::Vector3d normal_part(0, 0, f_m + f_b);
  switch (algorithm_) {
    case ForceAlgorithm::kWall:
    case ForceAlgorithm::kNone:
      break;
    case ForceAlgorithm::kNorm: {
      const Eigen::Vector3d n_t = Eigen::Vector3d(-hs.dhdx, -hs.dhdy, 1.0).normalized();
      normal_part = f_m * n_t + Eigen::Vector3d(0, 0, f_b);
      break;
    }
    case ForceAlgorithm::kFric1:
      gain = 1.0 - geometry_->Normalized(hs.h_m);
      break;
    case ForceAlgorithm::kFric2: {
      const double speed = out.tangential_speed_mps;
      const double sin_t =
          speed > 0 ? SinThetaT(hs.dhdx, hs.dhdy, v_t.x() / speed, v_t.y() / speed) : 0.0;
      gain = 1.0 + sin_t;
      break;
    }
  }
  out.force_N = normal_part + Eigen::Vector3d(gain * f_f.x(), gain * f_f.y(), 0.0);
  out.friction_N = gain * f_f.norm();
  return out;
}

}  // namespace hapticlab::renderer
