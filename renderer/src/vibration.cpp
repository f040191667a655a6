#include "hapticlab/renderer/vibration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace hapticlab::renderer {
namespace {

// Index i such that axis[i] <= v <= axis[i+1], and the fraction, clamped to the axis ends.
void Bracket(const std::vector<double>& axis, double v, int* i, double* frac) noexcept {
  const int n = static_cast<int>(axis.size());
  if (n == 1 || v <= axis[0]) {
    *i = 0;
    *frac = 0;
    return;
  }
  if (v >= axis[static_cast<std::size_t>(n - 1)]) {
    *i = n - 2;
    *frac = 1;
    return;
  }
  std::size_t k = 0;
  while (k + 2 < static_cast<std::size_t>(n) && axis[k + 1] <= v) ++k;
  *i = static_cast<int>(k);
  *frac = (v - axis[k]) / (axis[k + 1] - axis[k]);
}

}  // namespace

VibrationInterpolator::VibrationInterpolator(const VibrationBank& bank) : bank_(bank) {
  const auto p = static_cast<std::size_t>(bank_.order());
  const std::size_t q = bank_.cells.empty() ? 0 : bank_.cells[0].ma.size();
  lsf_.resize(p);
  coeff_.resize(p);
  ma_lsf_.resize(q);
  ma_coeff_.resize(q);
  work_.resize(4 * (std::max(p, q) + 3));
}

CellWeights VibrationInterpolator::Weights(double speed_mps, double force_N) const noexcept {
  CellWeights w;
  const auto& b = bank_;
  if (b.cells.empty()) return w;
  if (b.cells.size() == 1) {
    w.count = 1;
    w.cell[0] = 0;
    w.weight[0] = 1;
    return w;
  }
  if (!b.grid_speeds_mps.empty()) {
    int i, j;
    double fs, ff;
    Bracket(b.grid_speeds_mps, speed_mps, &i, &fs);
    Bracket(b.grid_forces_N, force_N, &j, &ff);
    const int nf = static_cast<int>(b.grid_forces_N.size());
    const int ns = static_cast<int>(b.grid_speeds_mps.size());
    const int i1 = ns > 1 ? i + 1 : i, j1 = nf > 1 ? j + 1 : j;
    w.count = 4;
    w.cell = {i * nf + j, i * nf + j1, i1 * nf + j, i1 * nf + j1};
    w.weight = {(1 - fs) * (1 - ff), (1 - fs) * ff, fs * (1 - ff), fs * ff};
    return w;
  }
  // Triangulation: barycentric coordinates in each triangle; keep the best.
  double best = -std::numeric_limits<double>::infinity();
  for (const auto& t : b.triangles) {
    const auto& a = b.cells[static_cast<std::size_t>(t[0])];
    const auto& bb = b.cells[static_cast<std::size_t>(t[1])];
    const auto& c = b.cells[static_cast<std::size_t>(t[2])];
    const double det = (bb.force_N - c.force_N) * (a.speed_mps - c.speed_mps) +
                       (c.speed_mps - bb.speed_mps) * (a.force_N - c.force_N);
    if (std::abs(det) < 1e-300) continue;
    const double l1 = ((bb.force_N - c.force_N) * (speed_mps - c.speed_mps) +
                       (c.speed_mps - bb.speed_mps) * (force_N - c.force_N)) /
                      det;
    const double l2 = ((c.force_N - a.force_N) * (speed_mps - c.speed_mps) +
                       (a.speed_mps - c.speed_mps) * (force_N - c.force_N)) /
                      det;
    const double l3 = 1 - l1 - l2;
    const double worst = std::min({l1, l2, l3});
    if (worst > best) {
      best = worst;
      w.count = 3;
      w.cell = {t[0], t[1], t[2], 0};
      w.weight = {l1, l2, l3, 0};
      if (worst >= 0) break;  // inside this triangle
    }
  }
  if (w.count == 0) {  // no usable triangle: nearest cell
    double dmin = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < b.cells.size(); ++k) {
      const double d = std::hypot(b.cells[k].speed_mps - speed_mps, b.cells[k].force_N - force_N);
      if (d < dmin) {
        dmin = d;
        w.cell[0] = static_cast<int>(k);
      }
    }
    w.count = 1;
    w.weight[0] = 1;
    return w;
  }
  double sum = 0;
  for (int k = 0; k < 3; ++k)
    sum += (w.weight[static_cast<std::size_t>(k)] =
                std::max(0.0, w.weight[static_cast<std::size_t>(k)]));
  for (int k = 0; k < 3; ++k) w.weight[static_cast<std::size_t>(k)] /= sum;
  return w;
}

void VibrationInterpolator::Interpolate(double speed_mps, double force_N, bool in_contact,
                                        ArFilter* out) noexcept {
  const int p = bank_.order();
  out->order = p;
  out->active = in_contact && p > 0 && speed_mps >= bank_.min_speed_mps;
  if (!out->active) {
    out->sigma = 0;
    return;
  }
  // The modelled range: saturate just inside it (the Penn toolkit's rule).
  if (bank_.max_speed_mps > 0 && speed_mps > bank_.max_speed_mps)
    speed_mps = bank_.max_speed_mps - kSaturationMarginSpeed_mps;
  if (bank_.max_force_N > 0 && force_N > bank_.max_force_N)
    force_N = bank_.max_force_N - kSaturationMarginForce_N;
  else if (force_N < bank_.light_force_N)  // the toolkit's light-load rule
    force_N = kLightForceAs_N;
  const CellWeights w = Weights(speed_mps, force_N);
  std::fill(lsf_.begin(), lsf_.end(), 0.0);
  std::fill(ma_lsf_.begin(), ma_lsf_.end(), 0.0);
  double var = 0, gain = 0;
  for (int k = 0; k < w.count; ++k) {
    const auto& cell = bank_.cells[static_cast<std::size_t>(w.cell[static_cast<std::size_t>(k)])];
    const double wk = w.weight[static_cast<std::size_t>(k)];
    for (std::size_t i = 0; i < lsf_.size(); ++i) lsf_[i] += wk * cell.lsf[i];
    for (std::size_t i = 0; i < ma_lsf_.size(); ++i) ma_lsf_[i] += wk * cell.ma_lsf[i];
    var += wk * cell.variance;
    gain += wk * cell.gain;
  }
  LsfToAr(lsf_, coeff_, work_);
  for (std::size_t i = 0; i < coeff_.size(); ++i) out->c[i] = coeff_[i];
  // MA LSFs are those of B(z) written as 1 - sum (-b_j) z^-j.
  out->ma_order = static_cast<int>(ma_lsf_.size());
  if (!ma_lsf_.empty()) {
    LsfToAr(ma_lsf_, ma_coeff_, work_);
    for (std::size_t i = 0; i < ma_coeff_.size(); ++i) out->b[i] = -ma_coeff_[i];
  }
  out->sigma = std::sqrt(var);
  out->gain = gain;
}

void ArSynth::Reset() noexcept {
  hist_.fill(0);
  exc_.fill(0);
  head_ = 0;
  running_ = false;
}

double ArSynth::StepWith(const ArFilter& f, double x) noexcept {
  if (!f.active || f.order <= 0) {
    if (running_) Reset();
    return 0.0;
  }
  running_ = true;
  // hist_[(head_ - i) mod N] holds a[k - i] for i = 1..order.
  constexpr int kN = kMaxArOrder;
  double ex = x;
  double a = 0;
  int idx = head_;
  for (int i = 0; i < f.order || i < f.ma_order; ++i) {
    idx = idx == 0 ? kN - 1 : idx - 1;
    const auto u = static_cast<std::size_t>(idx), ii = static_cast<std::size_t>(i);
    if (i < f.order) a += f.c[ii] * hist_[u];
    if (i < f.ma_order) ex += f.b[ii] * exc_[u];
  }
  a += f.gain * ex;
  hist_[static_cast<std::size_t>(head_)] = a;
  exc_[static_cast<std::size_t>(head_)] = x;
  head_ = head_ + 1 == kN ? 0 : head_ + 1;
  return a;
}

}  // namespace hapticlab::renderer
