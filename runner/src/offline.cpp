#include "hapticlab/runner/offline.hpp"

#include <cmath>

namespace hapticlab::runner {

OfflineResult RenderOffline(const renderer::MaterialModel& model,
                            const renderer::RenderOptions& options, const Measurement& trajectory,
                            const OfflineOptions& offline) {
  renderer::HybridRenderer r(model, options);
  OfflineResult out;
  out.rows.reserve(trajectory.rows.size());
  if (trajectory.rows.empty()) return out;
  const double t0 = trajectory.rows.front().t_s;
  const double vib_period = 1.0 / options.vibration_rate_hz;
  double next_vib_s = 0;  // time of the next vibration sample, relative to t0
  for (const auto& row : trajectory.rows) {
    const double t = row.t_s - t0;
    DeviceSample s;
    s.state.p_m = row.p_m;
    s.state.v_mps = row.v_mps;
    s.t_s = t;
    if (offline.measured_normal_force) {
      s.has_normal_force = true;
      s.normal_force_N = row.f_N.z();
    }
    const auto cmd = r.ForceTick(s, t);
    OfflineRow o;
    o.t_s = row.t_s;
    o.force_N = cmd.raw.force_N;
    o.command_N = cmd.force_N;
    o.normal_N = cmd.raw.normal_force_N;
    o.friction_N = cmd.raw.friction_N;
    o.speed_mps = cmd.raw.tangential_speed_mps;
    o.in_contact = cmd.raw.in_contact;
    o.fault = cmd.fault;
    // Vibration samples due up to this tick use the filter this tick published.
    double last = out.vibration_mps2.empty() ? 0.0 : out.vibration_mps2.back();
    while (next_vib_s <= t + 1e-12) {
      last = r.VibrationTick();
      out.vibration_mps2.push_back(last);
      next_vib_s += vib_period;
    }
    o.acc_mps2 = last;
    out.rows.push_back(o);
  }
  return out;
}

}  // namespace hapticlab::runner
