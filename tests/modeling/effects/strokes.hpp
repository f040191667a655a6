#pragma once
// Hand-written data for the effect tests (tests/modeling/effects/*_test.cpp): straight strokes
// at constant or sweeping speed and load in chosen directions, press-and-release cycles, and
// vibration windows, each with forces from a law the test writes out itself. They are built
// here, not by the workbench simulator (workbench_sim.cpp), so that a fit is checked on data of
// a shape that code never produces. Frames and units as workbench_replay.hpp: positions in the
// sample's surface frame [m], forces of the surface on the tool [N], 500 Hz force samples.

#include <cmath>
#include <functional>
#include <random>
#include <string_view>
#include <vector>

#include "hapticlab/modeling/workbench.hpp"

namespace hapticlab::modeling::wb::effect_test {

inline constexpr double kRate_hz = 500;

/// One straight stroke; speed and load change linearly from start to end.
struct Stroke {
  double dir_rad = 0;
  double v0_mps = 0.05, v1_mps = 0.05;
  double f0_N = 1, f1_N = 1;
  double duration_s = 1;
  double x0_m = 0, y0_m = 0;
};

/// The truth's Coulomb level f_C [N] of a sliding sample (kinematics and load filled in).
using FrictionLaw = std::function<double(const Replay::Sample&)>;

/// Sets the bounds of the positions in contact and the force rate.
inline void Finish(Replay* r) {
  bool first = true;
  for (const auto& s : r->samples()) {
    if (!s.contact) continue;
    if (first) r->x_min = r->x_max = s.x_m, r->y_min = r->y_max = s.y_m;
    r->x_min = std::min(r->x_min, s.x_m), r->x_max = std::max(r->x_max, s.x_m);
    r->y_min = std::min(r->y_min, s.y_m), r->y_max = std::max(r->y_max, s.y_m);
    first = false;
  }
  r->rate_hz = kRate_hz;
  r->file = "hand-written strokes";
}

/// Appends `s` as the next force sample: its time *t_s (then advanced by one sample period),
/// `contact`, its block (the whole second) and its row are set here.
inline void Append(Replay* r, Replay::Sample s, bool contact, double* t_s) {
  s.t_s = *t_s;
  s.contact = contact;
  s.block = static_cast<int>(*t_s);
  s.row = static_cast<int>(r->samples().size());
  r->mutable_samples().push_back(s);
  *t_s += 1 / kRate_hz;
}

/// Appends `n` samples out of contact (a lift-off between strokes).
inline void LiftOff(Replay* r, double* t_s, int n = 10) {
  for (int k = 0; k < n; ++k) Append(r, {}, false, t_s);
}

/// Strokes with the friction -(f_C u + mu_b v) (u the unit velocity, ideal Coulomb: no
/// pre-sliding) plus Gaussian noise of `noise_N` on every measured force component.
inline Replay MakeStrokes(const std::vector<Stroke>& strokes, const FrictionLaw& fc,
                          double mu_b_Ns_per_m = 0, double noise_N = 0, unsigned seed = 1) {
  Replay r;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 1);
  double t_s = 0;
  for (const auto& st : strokes) {
    const int n = static_cast<int>(st.duration_s * kRate_hz);
    double x = st.x0_m, y = st.y0_m;
    const double ux = std::cos(st.dir_rad), uy = std::sin(st.dir_rad);
    for (int k = 0; k < n; ++k) {
      const double a = n > 1 ? static_cast<double>(k) / (n - 1) : 0;
      const double v = st.v0_mps + (st.v1_mps - st.v0_mps) * a;
      const double f = st.f0_N + (st.f1_N - st.f0_N) * a;
      Replay::Sample s{};
      s.x_m = x, s.y_m = y;
      s.vx_mps = v * ux, s.vy_mps = v * uy;
      s.speed_mps = v;
      s.dir_rad = std::atan2(uy, ux);
      s.fload_N = f;
      s.fn_N = f + noise_N * noise(rng);
      s.d_m = f * 0.5e-3;  // a 2 N/mm layer (the friction channel does not read it)
      const double c = fc(s);
      s.ftx_N = -(c * ux + mu_b_Ns_per_m * s.vx_mps) + noise_N * noise(rng);
      s.fty_N = -(c * uy + mu_b_Ns_per_m * s.vy_mps) + noise_N * noise(rng);
      x += s.vx_mps / kRate_hz, y += s.vy_mps / kRate_hz;
      Append(&r, s, true, &t_s);
    }
    LiftOff(&r, &t_s);
  }
  Finish(&r);
  return r;
}

/// Strokes in `directions` evenly spaced directions, each at a constant slow, a constant fast
/// and a sweeping speed, with the load sweeping 0.5-3 N or back, each starting 1 cm behind the
/// origin so that the strokes cross there.
inline std::vector<Stroke> StarOfStrokes(int directions = 8, double v_lo_mps = 0.01,
                                         double v_hi_mps = 0.12) {
  std::vector<Stroke> out;
  for (int k = 0; k < directions; ++k) {
    const double phi = -3.141592653589793 + (k + 0.5) * 2 * 3.141592653589793 / directions;
    const double x0 = -0.01 * std::cos(phi), y0 = -0.01 * std::sin(phi);
    out.push_back({phi, v_lo_mps, v_lo_mps, 0.5, 3.0, 0.8, x0, y0});
    out.push_back({phi, v_hi_mps, v_hi_mps, 3.0, 0.5, 0.25, x0, y0});
    out.push_back({phi, v_lo_mps, v_hi_mps, 1.0, 2.0, 0.6, x0, y0});
  }
  return out;
}

/// Press-and-release cycles at one spot: depth d = d_max (1 - cos(2 pi t / T)) / 2 over cycles
/// of several depths and periods, normal force from `law(d_m, ddot_mps)` plus noise.
inline Replay MakePresses(const std::function<double(double, double)>& law, double noise_N = 0,
                          unsigned seed = 1) {
  Replay r;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 1);
  double t_s = 0;
  const double depths_m[] = {0.4e-3, 0.8e-3, 1.2e-3, 1.0e-3};
  const double periods_s[] = {0.6, 1.0, 0.3, 1.6};
  for (int c = 0; c < 8; ++c) {
    const double dmax = depths_m[c % 4], T = periods_s[(c + c / 4) % 4];
    const int n = static_cast<int>(T * kRate_hz);
    for (int k = 1; k < n; ++k) {
      const double w = 2 * 3.141592653589793 / T, tau = k / kRate_hz;
      Replay::Sample s{};
      s.d_m = dmax * (1 - std::cos(w * tau)) / 2;
      s.ddot_mps = dmax * w * std::sin(w * tau) / 2;
      const double f = law(s.d_m, s.ddot_mps);
      s.fn_N = f + noise_N * noise(rng);
      s.fload_N = f;
      Append(&r, s, true, &t_s);
    }
    LiftOff(&r, &t_s);
  }
  Finish(&r);
  return r;
}

/// 960 vibration windows over a grid of speeds (12-230 mm/s), loads (0.3-2.7 N) and directions,
/// with eight log-spaced bands from 20 Hz to 1 kHz whose power is exp(law(band, window)) times
/// log-normal noise of `noise_ln` (SD of ln power). The force samples are left empty.
inline Replay MakeWindows(const std::function<double(int, const Replay::Window&)>& law,
                          double noise_ln = 0, unsigned seed = 1) {
  Replay r;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 1);
  r.has_vibration = true;
  r.acc_rate_hz = 2800;
  for (int b = 0; b < 8; ++b) {
    r.band_lo_hz.push_back(20 * std::pow(50.0, b / 8.0));
    r.band_hi_hz.push_back(20 * std::pow(50.0, (b + 1) / 8.0));
  }
  const double pi = 3.141592653589793;
  int k = 0;
  for (int i = 0; i < 16; ++i)
    for (int j = 0; j < 10; ++j)
      for (int a = 0; a < 6; ++a, ++k) {
        Replay::Window w{};
        w.t_s = 0.128 * k;
        w.speed_mps = 0.012 * std::pow(250.0 / 12, (i + 0.5 * (a % 2)) / 16.0);
        w.force_N = 0.3 * std::pow(10.0, (j + 0.3 * (a % 3)) / 10.0);
        const double phi = -pi + (a + 0.37 * i + 0.11 * j) * pi / 3;
        w.dir = {std::cos(phi), std::sin(phi), std::cos(2 * phi), std::sin(2 * phi)};
        w.block = static_cast<int>(w.t_s);
        w.row0 = 64 * k, w.rows = 256;
        for (int b = 0; b < 8; ++b)
          w.band_power.push_back(std::exp(law(b, w) + noise_ln * noise(rng)));
        r.windows.push_back(std::move(w));
      }
  r.file = "hand-written windows";
  return r;
}

/// Mean over bands of ln(measured / predicted) band power of window w, in dB (the residual the
/// vibration evidence reports), from the model's prediction.
inline std::vector<double> WindowResidualDb(const Model& m, const Replay& r) {
  const auto p = Predict(m, r);
  std::vector<double> out;
  for (std::size_t w = 0; w < r.windows.size(); ++w) {
    double s = 0;
    for (std::size_t b = 0; b < p.band_power[w].size(); ++b)
      s += std::log(r.windows[w].band_power[b] / p.band_power[w][b]);
    out.push_back(10 * std::log10(std::exp(s / static_cast<double>(p.band_power[w].size()))));
  }
  return out;
}

/// What the effect's evidence says about the residuals of `m` on `r`.
inline EvidenceNote EvidenceOf(std::string_view effect_name, const Model& m, const Replay& r) {
  const auto res = ComputeResiduals(m, r, Predict(m, r));
  return FindEffect(effect_name)->Evidence(r, res);
}

/// A model of the listed effects with their initial values from the data.
inline Model ModelOf(const std::vector<std::string>& effects, const Replay& r) {
  Model m;
  AddEffects(&m, effects, r);
  return m;
}

}  // namespace hapticlab::modeling::wb::effect_test
