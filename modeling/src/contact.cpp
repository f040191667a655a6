// Contact identification: Algorithm 1 (2-D) as the initialiser of the workbench's friction
// channel, and `model fit-contact` as the workbench's friction and normal channels fitted on
// strokes and pokes (one engine; see contact.hpp).

#include "hapticlab/modeling/contact.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>
#include <optional>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"

namespace hapticlab::modeling {
namespace {

bool InSplit(int block, wb::Split s) {
  return s == wb::Split::kAll || (s == wb::Split::kTrain) == (block % 2 == 0);
}

const wb::ParamEstimate* FindParam(const wb::ChannelFit& c, wb::ParamKey key, int* at) {
  for (std::size_t k = 0; k < c.params.size(); ++k)
    if (c.params[k].effect == key.effect && c.params[k].name == key.name) {
      if (at) *at = static_cast<int>(k);
      return &c.params[k];
    }
  return nullptr;
}

Estimate FromParam(const wb::ChannelFit& c, wb::ParamKey key) {
  Estimate e;
  if (const auto* p = FindParam(c, key, nullptr)) e = {p->value, p->sd, p->lo95, p->hi95};
  return e;
}

// Renderer units: X = X1mm / (1 mm)^n, so ln X = ln X1mm - n ln(1 mm); its variance by the
// delta method from the channel's covariance, the interval exp(ln X -+ t sd).
Estimate ToRendererUnits(const wb::ChannelFit& c, wb::ParamKey key) {
  Estimate e;
  int i = -1, j = -1;
  const auto* x = FindParam(c, key, &i);
  const auto* n = FindParam(c, wb::key::kN, &j);
  if (!x || !n) return e;
  const double l = std::log(1e-3);
  e.value = x->value / std::exp(n->value * l);
  const std::size_t np = c.params.size();
  if (c.covariance.size() == np * np && x->value > 0) {
    const double vx = c.covariance[i * np + i], vn = c.covariance[j * np + j],
                 cxn = c.covariance[i * np + j];
    const double var_log = vx / (x->value * x->value) + l * l * vn - 2 * l * cxn / x->value;
    const double sd_log = std::sqrt(std::max(var_log, 0.0));
    e.sd = e.value * sd_log;
    const double t = x->sd > 0 ? (x->hi95 - x->value) / x->sd : 1.96;  // the channel's t quantile
    e.lo95 = e.value * std::exp(-t * sd_log);
    e.hi95 = e.value * std::exp(t * sd_log);
  } else {
    e.lo95 = e.hi95 = e.value;
  }
  return e;
}

double RmsNormal(const wb::Model& m, const wb::Replay& r, double max_force_N) {
  const auto p = wb::Predict(m, r);
  double s = 0;
  int n = 0;
  for (std::size_t i = 0; i < r.samples().size(); ++i)
    if (r.samples()[i].contact && r.samples()[i].fload_N <= max_force_N)
      s += std::pow(r.samples()[i].fn_N - p.fn_N[i], 2), ++n;
  return n ? std::sqrt(s / n) : 0;
}

}  // namespace

std::vector<std::string> ContactEffects() {
  using namespace wb::effect;
  return {std::string(kCoulomb), std::string(kViscous), std::string(kDahl), std::string(kHcDamping),
          std::string(kHcExponent)};
}

void SplitStrokesAndPokes(const Measurement& m, Measurement* strokes, Measurement* pokes) {
  *strokes = m;
  *pokes = m;
  strokes->rows.clear();
  pokes->rows.clear();
  strokes->row_lines.clear();
  pokes->row_lines.clear();
  for (std::size_t i = 0; i < m.rows.size(); ++i) {
    const auto& r = m.rows[i];
    const bool poke = r.v_mps.head<2>().norm() < 1e-3 && std::abs(r.v_mps.z()) > 1e-4;
    auto* dst = poke ? pokes : strokes;
    dst->rows.push_back(r);
    if (i < m.row_lines.size()) dst->row_lines.push_back(m.row_lines[i]);
  }
}

namespace {

// A sample Algorithm 1 uses: in contact and in the split.
bool Uses(const wb::Replay::Sample& x, wb::Split split) {
  return x.contact && InSplit(x.block, split);
}

// estMu (eq. 4.10, vector form): the surface's force on the tool is -(f_C u + mu_b v) while
// sliding, with f_C = mu_k f_n and u the previous sample's direction of motion. Returns
// (mu_k, mu_b) by least squares.
Eigen::Vector2d EstimateMu(const wb::Replay& r, wb::Split split, const ContactFitOptions& o) {
  const auto& s = r.samples();
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (std::size_t t = 1; t < s.size(); ++t) {
    if (!Uses(s[t], split) || !s[t - 1].contact || s[t].speed_mps < o.sliding_speed_mps ||
        s[t - 1].speed_mps < o.sliding_speed_mps)
      continue;
    const double ux = s[t - 1].vx_mps / s[t - 1].speed_mps,
                 uy = s[t - 1].vy_mps / s[t - 1].speed_mps;
    const Eigen::Vector2d ax(s[t - 1].fload_N * ux, s[t].vx_mps),
        ay(s[t - 1].fload_N * uy, s[t].vy_mps);
    A += ax * ax.transpose() + ay * ay.transpose();
    b += ax * -s[t].ftx_N + ay * -s[t].fty_N;
  }
  return A.ldlt().solve(b);
}

// estKappa (eq. 4.9, vector form): between bristle updates (the tool moved at least the
// position resolution from the anchor), y - z = -kappa (|dx| / f_C) z with z = F_D(anchor) - T,
// y = F_D(t) - T, T = f_C dx / |dx|, F_D = -f_t - mu_b v the measured bristle force. Returns the
// new estimate, or `kappa` when the pre-sliding samples give none.
double EstimateKappa(const wb::Replay& r, wb::Split split, const ContactFitOptions& o,
                     const Eigen::Vector2d& mu, double kappa) {
  const auto& s = r.samples();
  double num = 0, den = 0;
  std::size_t anchor = 0;
  bool have_anchor = false;
  for (std::size_t t = 0; t < s.size(); ++t) {
    if (!s[t].contact) {
      have_anchor = false;
      continue;
    }
    if (!have_anchor) {
      anchor = t, have_anchor = true;
      continue;
    }
    const double dx = s[t].x_m - s[anchor].x_m, dy = s[t].y_m - s[anchor].y_m,
                 len = std::hypot(dx, dy);
    if (len < r.position_resolution_m) continue;
    const std::size_t a0 = anchor;
    anchor = t;
    if (!Uses(s[t], split) || s[t].speed_mps > o.presliding_speed_mps) continue;
    const double fc = mu(0) * s[a0].fload_N;
    if (!(fc > 0)) continue;
    const double tx = fc * dx / len, ty = fc * dy / len;
    const double zx = -s[a0].ftx_N - mu(1) * s[a0].vx_mps - tx,
                 zy = -s[a0].fty_N - mu(1) * s[a0].vy_mps - ty;
    const double yx = -s[t].ftx_N - mu(1) * s[t].vx_mps - tx,
                 yy = -s[t].fty_N - mu(1) * s[t].vy_mps - ty;
    const double wx = len / fc * zx, wy = len / fc * zy;
    num += wx * (zx - yx) + wy * (zy - yy);
    den += wx * wx + wy * wy;
  }
  return den > 0 && num > 0 ? num / den : kappa;
}

}  // namespace

Algorithm1Result AlgorithmOne(const wb::Replay& r, wb::Split split, const ContactFitOptions& o) {
  Algorithm1Result a;
  const auto& s = r.samples();
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (!Uses(s[i], split)) continue;
    a.presliding_samples += s[i].speed_mps <= o.presliding_speed_mps;
    a.sliding_samples += s[i].speed_mps >= o.sliding_speed_mps;
  }
  if (a.sliding_samples < 20 || a.presliding_samples < 5)
    throw InputError(
        r.file, 0, "vx_mps",
        fmt::format(
            "strokes need sliding (>= {:.1f} mm/s) and pre-sliding (<= {:.1f} mm/s) samples in "
            "contact; found {} and {}",
            o.sliding_speed_mps * 1e3, o.presliding_speed_mps * 1e3, a.sliding_samples,
            a.presliding_samples));
  const Eigen::Vector2d mu = EstimateMu(r, split, o);
  double kappa = 2000, mu_k = 0, mu_b = 0;
  for (int pass = 1; pass <= 100; ++pass) {
    const double k_new = EstimateKappa(r, split, o, mu, kappa);
    const double dk = std::abs(k_new - kappa), dmk = std::abs(mu(0) - mu_k),
                 dmb = std::abs(mu(1) - mu_b);
    kappa = k_new, mu_k = mu(0), mu_b = mu(1);
    a.passes = pass;
    if (dk < o.convergence && dmk < o.convergence && dmb < o.convergence) {
      a.converged = true;
      break;
    }
  }
  a.kappa_N_per_m = kappa;
  a.mu_k = mu_k;
  a.mu_b_Ns_per_m = mu_b;
  return a;
}

namespace {

// The pokes the normal law is fitted on: a separate pokes file, the measurement's pokes (rows
// of vertical motion), or all of it; `source` says which. At least 10 samples in contact.
const Measurement* PokesOf(const Measurement& m, const Measurement* pokes_in,
                           const Measurement& pokes, const ContactFitOptions& o,
                           std::string* source) {
  auto in_contact = [&](const Measurement& x) {
    int n = 0;
    for (const auto& row : x.rows) n += row.f_N.z() > 0.02 && row.f_N.z() <= o.max_force_N;
    return n;
  };
  const Measurement* src = &m;
  if (pokes_in) {
    src = pokes_in;
    *source = fmt::format("the pokes file {}", pokes_in->file);
  } else if (in_contact(pokes) >= 200) {
    src = &pokes;
    *source =
        fmt::format("the measurement's {} poke rows (vertical motion, tangential speed < 1 mm/s)",
                    pokes.rows.size());
  } else {
    *source = "every sample of the measurement in contact (it has no pokes)";
  }
  if (in_contact(*src) < 10)
    throw InputError(
        src->file, 0, "fz_N",
        fmt::format(
            "{} samples in contact at most {:.1f} N for Hunt-Crossley; at least 10 are needed",
            in_contact(*src), o.max_force_N));
  return src;
}

// The replay with each contact sample's load taken from the fitted normal law (its prediction
// from the penetration, where positive).
wb::Replay LawLoadReplay(const wb::Model& model, const wb::Replay& r) {
  wb::Replay law_load = r;
  const auto pred = wb::Predict(model, r).fn_N;
  for (std::size_t i = 0; i < r.samples().size(); ++i)
    if (r.samples()[i].contact && pred[i] > 0) law_load.mutable_samples()[i].fload_N = pred[i];
  return law_load;
}

// RMS of the friction force's error over r's contact samples, predicted on `fr_replay`.
double RmsFriction(const wb::Model& model, const wb::Replay& fr_replay, const wb::Replay& r) {
  const auto p = wb::Predict(model, fr_replay);
  double s = 0;
  int n = 0;
  for (std::size_t i = 0; i < r.samples().size(); ++i)
    if (r.samples()[i].contact)
      s += std::pow(r.samples()[i].ftx_N - p.ftx_N[i], 2) +
           std::pow(r.samples()[i].fty_N - p.fty_N[i], 2),
          ++n;
  return n ? std::sqrt(s / n) : 0;
}

}  // namespace

ContactFit FitContact(const Measurement& m, const Measurement* pokes_in,
                      const ContactFitOptions& o) {
  ContactFit out;
  out.uncertainty_method =
      "cluster jackknife over 3 s clusters of blocks (delete-one-cluster one-step refits d_g = "
      "(J'J - J_g'J_g)^-1 J_g' "
      "r_g, cov = (G-1)/G sum (d_g - mean)(d_g - mean)'), 95 % intervals with "
      "t(0.975, G-1)";
  // The whole measurement replayed (pokes carry no sliding), as the workbench does.
  const auto r = wb::PrepareReplay(m, o.replay);
  wb::Model model;
  wb::AddEffects(&model, ContactEffects(), r);
  wb::FitOptions fo;
  fo.uncertainty = true;
  fo.vibration = false;

  // Hunt-Crossley first: a separate pokes file, the measurement's pokes, or all of it.
  Measurement strokes, pokes;
  SplitStrokesAndPokes(m, &strokes, &pokes);
  const Measurement* src = PokesOf(m, pokes_in, pokes, o, &out.poke_source);
  const auto pr = src == &m ? r : wb::PrepareReplay(*src, o.replay);
  fo.normal = true;
  fo.friction = false;
  fo.max_normal_force_N = o.max_force_N;
  const auto nr = wb::Fit(&model, pr, fo);
  const auto* nf = nr.Find(wb::Channel::kNormal);
  HL_REQUIRE(nf != nullptr, "the cost functor must exist");
  out.normal_summary = nf->summary;

  // Friction. The Coulomb level is mu_k times the measured load, whose force-sensor noise biases
  // the replayed friction through the bristle's saturation |F| <= f_C (errors in variables).
  // With load_from_normal_law (off by default) the friction replay takes the load from the
  // Hunt-Crossley law just fitted, predicted from the penetration instead; measured in
  // docs/modeling-geometry-contact.md and not the default, because the law's own error then
  // enters mu_k without being in its interval.
  std::optional<wb::Replay> law_load;
  if (o.load_from_normal_law) law_load = LawLoadReplay(model, r);
  const wb::Replay& fr_replay = law_load ? *law_load : r;
  out.algorithm1 = AlgorithmOne(fr_replay, wb::Split::kAll, o);
  fo.normal = false;
  fo.friction = true;
  auto fr = wb::Fit(&model, fr_replay, fo);
  auto* cf = fr.Find(wb::Channel::kFriction);
  HL_REQUIRE(cf != nullptr, "the contact cost functor must exist");
  out.friction_summary = cf->summary;
  if (o.bootstrap && !o.load_from_normal_law && cf->summary.usable) {
    out.bootstrap = wb::BootstrapFriction(&model, m, o.replay, fo, cf, o.bootstrap_options);
    if (out.bootstrap.applied) out.uncertainty_method += "; friction: " + out.bootstrap.method;
  }
  out.kappa_N_per_m = FromParam(*cf, wb::key::kKappa_N_per_m);
  out.mu_k = FromParam(*cf, wb::key::kMuK);
  out.mu_b_Ns_per_m = FromParam(*cf, wb::key::kMuB_Ns_per_m);
  out.stroke_samples = cf->samples;
  out.friction_rms_N = RmsFriction(model, fr_replay, r);
  out.K1mm_N = FromParam(*nf, wb::key::kK1mm_N);
  out.B1mm_Ns_per_m = FromParam(*nf, wb::key::kB1mm_Ns_per_m);
  out.n = FromParam(*nf, wb::key::kN);
  out.K = ToRendererUnits(*nf, wb::key::kK1mm_N);
  out.B = ToRendererUnits(*nf, wb::key::kB1mm_Ns_per_m);
  out.poke_samples = nf->samples;
  out.normal_rms_N = RmsNormal(model, pr, o.max_force_N);
  return out;
}

}  // namespace hapticlab::modeling
