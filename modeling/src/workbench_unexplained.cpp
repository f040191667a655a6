// The workbench's report of what no candidate effect explains: noise floors estimated from the
// measurement, the residual's variance ranked over every axis the workbench knows.

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <set>
#include <thread>
#include <utility>

#include "hapticlab/modeling/workbench.hpp"
#include "workbench_internal.hpp"

namespace hapticlab::modeling::wb {
namespace {

constexpr int kMinBinCount = 20;  // bins with fewer samples are left out of the variance shares

bool InSplit(int block, Split s) {
  return s == Split::kAll || (s == Split::kTrain) == (block % 2 == 0);
}

// Robust SD of white noise on a smooth signal (internal::NoiseSdFromSecondDifferences), 0 with
// fewer than 10 second differences.
double NoiseSd(const std::vector<double>& second_differences) {
  return second_differences.size() < 10
             ? 0
             : internal::NoiseSdFromSecondDifferences(second_differences);
}

// A binning of one axis.
struct AxisBins {
  std::string axis, unit;
  bool ordinal = false, log_scale = false;
  std::vector<double> edges;
  std::vector<std::string> labels;
  std::vector<double> centers;  // for the linear trend of ordinal axes
};

AxisBins MakeAxis(const std::string& axis, const std::string& unit,
                  const std::vector<double>& edges, bool log_scale) {
  AxisBins a;
  a.axis = axis;
  a.unit = unit;
  a.ordinal = true;
  a.log_scale = log_scale;
  a.edges = edges;
  for (std::size_t j = 0; j + 1 < edges.size(); ++j) {
    const double lo = edges[j], hi = edges[j + 1];
    const bool open = !(hi < 1e8);
    a.labels.push_back(open ? fmt::format(">= {:g} {}", lo, unit)
                            : fmt::format("{:g}-{:g} {}", lo, hi, unit));
    double c = open ? 1.5 * lo : 0.5 * (lo + hi);
    if (log_scale) c = open ? lo * 1.5 : (lo > 0 ? std::sqrt(lo * hi) : 0.5 * hi);
    a.centers.push_back(log_scale ? std::log10(std::max(c, 1e-9)) : c);
  }
  return a;
}

AxisBins Categorical(const std::string& axis, std::vector<std::string> labels) {
  AxisBins a;
  a.axis = axis;
  for (std::size_t j = 0; j <= labels.size(); ++j) a.edges.push_back(static_cast<double>(j));
  a.labels = std::move(labels);
  a.centers.assign(a.labels.size(), 0);
  return a;
}

struct Quantity {
  Channel channel = Channel::kNormal;
  std::string name;
  std::function<std::string(double)> fmt;
};

// Share of the variance of `value` (over the samples with use) explained by the bins of `key`,
// and the shape of the dependence in words.
ResidualAxis Analyze(const Quantity& q, const AxisBins& a, const std::vector<double>& key,
                     const std::vector<double>& value, const std::vector<char>& use) {
  ResidualAxis out;
  out.axis = a.axis;
  out.channel = q.channel;
  const std::size_t nb = a.labels.size();
  std::vector<double> sum(nb, 0), sum2(nb, 0);
  std::vector<int> n(nb, 0);
  for (std::size_t i = 0; i < key.size(); ++i) {
    if (!use[i] || !std::isfinite(value[i])) continue;
    for (std::size_t j = 0; j < nb; ++j)
      if (key[i] >= a.edges[j] && key[i] < a.edges[j + 1]) {
        sum[j] += value[i], sum2[j] += value[i] * value[i], ++n[j];
        break;
      }
  }
  double N = 0, S = 0, S2 = 0;
  std::vector<std::size_t> bins;
  for (std::size_t j = 0; j < nb; ++j)
    if (n[j] >= kMinBinCount) N += n[j], S += sum[j], S2 += sum2[j], bins.push_back(j);
  if (bins.size() < 2 || N < 2) {
    out.description = fmt::format("{}: too few samples in two or more {} bins", q.name, a.axis);
    return out;
  }
  const double gm = S / N, total = S2 - N * gm * gm;
  double between = 0;
  for (const auto j : bins) between += n[j] * std::pow(sum[j] / n[j] - gm, 2);
  out.share = total > 0 ? std::clamp(between / total, 0.0, 1.0) : 0;
  // Shape: an ordinal axis whose bin means are mostly a straight line is described by the
  // line; anything else by its highest and lowest bins.
  std::size_t jmax = bins.front(), jmin = bins.front();
  for (const auto j : bins) {
    if (sum[j] / n[j] > sum[jmax] / n[jmax]) jmax = j;
    if (sum[j] / n[j] < sum[jmin] / n[jmin]) jmin = j;
  }
  if (a.ordinal) {
    double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (const auto j : bins) {
      const double w = n[j], x = a.centers[j], y = sum[j] / n[j];
      sw += w, sx += w * x, sy += w * y, sxx += w * x * x, sxy += w * x * y;
    }
    const double vx = sxx - sx * sx / sw;
    const double slope = vx > 0 ? (sxy - sx * sy / sw) / vx : 0;
    const double linear = slope * slope * vx;
    if (between > 0 && linear >= 0.75 * between) {
      const double x0 = a.centers[bins.front()], x1 = a.centers[bins.back()];
      const double span = slope * (x1 - x0);
      const std::string over =
          a.log_scale ? fmt::format("{} per decade of {} ({} over {}..{})", q.fmt(slope), a.axis,
                                    q.fmt(span), a.labels[bins.front()], a.labels[bins.back()])
                      : fmt::format("{} over {:.3g}-{:.3g} {}", q.fmt(span), a.edges[bins.front()],
                                    std::min(a.edges[bins.back() + 1], 1e8), a.unit);
      out.description =
          fmt::format("{} {} linearly with {}{}, {}", q.name, slope > 0 ? "rises" : "falls",
                      a.log_scale ? "log " : "", a.axis, over);
      return out;
    }
  }
  out.description =
      fmt::format("{} is highest at {} ({}) and lowest at {} ({})", q.name, a.labels[jmax],
                  q.fmt(sum[jmax] / n[jmax]), a.labels[jmin], q.fmt(sum[jmin] / n[jmin]));
  return out;
}

// `value` less the mean of its recording's used entries: what a time axis reads when recordings
// are concatenated (a level that differs between recordings is not a drift within one).
std::vector<double> WithinRecording(const std::vector<double>& value, const std::vector<char>& use,
                                    const std::vector<double>& recording) {
  std::map<double, std::pair<double, int>> mean;
  for (std::size_t i = 0; i < value.size(); ++i)
    if (use[i] && std::isfinite(value[i]))
      mean[recording[i]].first += value[i], ++mean[recording[i]].second;
  std::vector<double> out(value);
  for (std::size_t i = 0; i < value.size(); ++i)
    if (const auto it = mean.find(recording[i]); it != mean.end() && it->second.second > 0)
      out[i] -= it->second.first / it->second.second;
  return out;
}

std::string Hint(const std::string& axis) {
  if (axis == "recording")
    return "that differs between the concatenated recordings (a per-recording level: another "
           "sample, tool, grip, session or calibration)";
  if (axis == "time")
    return "that changes over the recording (a drifting coefficient: warming, wear, creep, "
           "humidity)";
  if (axis == "speed") return "that depends on the sliding speed";
  if (axis == "load") return "that depends on the normal load";
  if (axis == "direction") return "that depends on the direction of motion";
  if (axis == "position") return "that varies over the surface";
  if (axis == "regime") return "that differs between pre-sliding, transition and sliding";
  return "that changes the shape of the spectrum in some frequency bands";
}

}  // namespace

// ---------------------------------------------------------------------------------------------
std::map<Channel, double> EstimateNoiseFloor(const Replay& r, Split split, const Model* m) {
  std::map<Channel, double> floor;
  std::vector<double> dn, dx, dy, dvz, dvx, dvy;
  for (std::size_t i = 1; i + 1 < r.samples().size(); ++i) {
    const auto &a = r.samples()[i - 1], &b = r.samples()[i], &c = r.samples()[i + 1];
    if (!a.contact || !b.contact || !c.contact) continue;
    dn.push_back(a.fn_N - 2 * b.fn_N + c.fn_N);
    dx.push_back(a.ftx_N - 2 * b.ftx_N + c.ftx_N);
    dy.push_back(a.fty_N - 2 * b.fty_N + c.fty_N);
    dvz.push_back(a.ddot_mps - 2 * b.ddot_mps + c.ddot_mps);
    dvx.push_back(a.vx_mps - 2 * b.vx_mps + c.vx_mps);
    dvy.push_back(a.vy_mps - 2 * b.vy_mps + c.vy_mps);
  }
  const double sn = NoiseSd(dn), st2 = std::pow(NoiseSd(dx), 2) + std::pow(NoiseSd(dy), 2);
  // The model's sensitivity to the measured velocities, by replaying them shifted.
  std::vector<double> gn(r.samples().size(), 0), gt(r.samples().size(), 0);
  double svz = 0, svt = 0;
  if (m) {
    svz = NoiseSd(dvz);
    svt = std::sqrt(0.5 * (std::pow(NoiseSd(dvx), 2) + std::pow(NoiseSd(dvy), 2)));
    constexpr double kDv_mps = 1e-3;
    const auto p0 = Predict(*m, r);
    Replay shifted = r;
    for (auto& s : shifted.mutable_samples()) s.ddot_mps += kDv_mps, s.vx_mps += kDv_mps;
    const auto p1 = Predict(*m, shifted);
    for (std::size_t i = 0; i < r.samples().size(); ++i) {
      gn[i] = (p1.fn_N[i] - p0.fn_N[i]) / kDv_mps;
      gt[i] = (p1.ftx_N[i] - p0.ftx_N[i]) / kDv_mps;
    }
  }
  double nn = 0, nt = 0, vn = 0, vt = 0;
  for (std::size_t i = 0; i < r.samples().size(); ++i) {
    const auto& s = r.samples()[i];
    if (!s.contact || !InSplit(s.block, split)) continue;
    nn += s.fn_N * s.fn_N, nt += s.ftx_N * s.ftx_N + s.fty_N * s.fty_N;
    vn += sn * sn + gn[i] * gn[i] * svz * svz;
    vt += st2 + 2 * gt[i] * gt[i] * svt * svt;
  }
  if (nn > 0) floor[Channel::kNormal] = std::sqrt(vn / nn);
  if (nt > 0) floor[Channel::kFriction] = std::sqrt(vt / nt);
  // Vibration: a band's power is the mean of k periodogram bins, about k / 1.5 of them
  // independent under a Hann window (its noise bandwidth is 1.5 bins); for X = mean of k_eff
  // unit exponentials E(sqrt X - 1)^2 = 2 - 2 Gamma(k + 1/2) / (Gamma(k) sqrt k), so the
  // expected E_s of a perfect model is about sqrt(sum_b P_b c_b / sum_b P_b).
  if (r.has_vibration && !r.windows.empty()) {
    double se = 0;
    int nw = 0;
    for (const auto& w : r.windows) {
      if (!InSplit(w.block, split)) continue;
      double num = 0, den = 0;
      for (std::size_t b = 0; b < w.band_power.size(); ++b) {
        int bins = 0;
        for (int k = 1; k < w.rows / 2; ++k) {
          const double f = k * r.acc_rate_hz / w.rows;
          bins += f >= r.band_lo_hz[b] && f < r.band_hi_hz[b];
        }
        const double k_eff = std::max(1.0, bins / 1.5);
        const double c =
            2 - 2 * std::exp(std::lgamma(k_eff + 0.5) - std::lgamma(k_eff)) / std::sqrt(k_eff);
        num += w.band_power[b] * c, den += w.band_power[b];
      }
      if (den > 0) se += std::sqrt(num / den), ++nw;
    }
    if (nw) floor[Channel::kVibration] = se / nw;
  }
  return floor;
}

namespace {

// The axes the residual is ranked along, and the recordings of a replay (concatenated
// recordings, Measurement::recording_ids: time runs within each recording, and a recording
// axis shows differences between them).
struct Axes {
  std::map<int, std::pair<double, double>> span;  // recording -> first, last sample time
  std::map<int, double> rec_index;                // recording -> its bin on the recording axis
  bool multi = false;                             // more than one recording
  AxisBins recording, time, speed, load, dir, pos, regime;
  double StartOf(int rec) const {
    const auto it = span.find(rec);
    return it != span.end() ? it->second.first : span.begin()->second.first;
  }
  double IndexOf(int rec) const { return rec_index.count(rec) ? rec_index.at(rec) : 0; }
};

Axes MakeAxes(const Replay& r) {
  Axes a;
  const double pi = std::numbers::pi;
  for (const auto& s : r.samples()) {
    auto [it, fresh] = a.span.try_emplace(s.recording, s.t_s, s.t_s);
    if (!fresh) it->second.second = s.t_s;
  }
  a.multi = a.span.size() > 1;
  double longest = 0;
  std::vector<std::string> rec_labels;
  for (const auto& [id, se] : a.span) {
    longest = std::max(longest, se.second - se.first);
    a.rec_index[id] = static_cast<double>(rec_labels.size());
    rec_labels.push_back(fmt::format("recording {}", id));
  }
  a.recording = Categorical("recording", rec_labels);
  std::vector<double> tedges;
  for (int k = 0; k <= 10; ++k) tedges.push_back(longest * k / 10 + (k == 10 ? 1e-9 : 0));
  a.time = MakeAxis("time", "s", tedges, false);
  a.speed = MakeAxis("speed", "mm/s", {0, 0.5, 1, 2, 3, 5, 10, 20, 50, 100, 200, 1e9}, true);
  a.load = MakeAxis("load", "N", {0, 0.25, 0.5, 0.75, 1, 1.5, 2, 3, 1e9}, false);
  a.dir = Categorical("direction", {});
  a.dir.edges.clear();
  for (int k = 0; k <= 8; ++k) a.dir.edges.push_back(-pi - pi / 8 + k * pi / 4);
  for (int k = 0; k < 8; ++k) a.dir.labels.push_back(fmt::format("{:.0f} deg", -180 + 45.0 * k));
  a.dir.centers.assign(8, 0);
  a.pos =
      Categorical("position", {"front-left", "front-centre", "front-right", "middle-left", "centre",
                               "middle-right", "back-left", "back-centre", "back-right"});
  a.regime = Categorical(
      "regime", {"pre-sliding (<= 0.5 mm/s)", "transition (0.5-3 mm/s)", "sliding (>= 3 mm/s)"});
  return a;
}

// A direction in (-pi, pi] in the direction axis's bins (near +180 belongs to -180).
double WrapDirection(double d) {
  const double pi = std::numbers::pi;
  return d >= pi - pi / 8 ? d - 2 * pi : d;
}

// The force-sample channels (normal force; the friction ratio along the motion) over every axis.
void RankForceAxes(const Axes& ax, const Replay& r, const Residuals& res,
                   std::vector<ResidualAxis>* out) {
  const std::size_t n = r.samples().size();
  std::vector<double> kt(n), ks(n), kl(n), kd(n), kp(n), kr(n), krec(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& s = r.samples()[i];
    kt[i] = s.t_s - ax.StartOf(s.recording);
    krec[i] = ax.IndexOf(s.recording);
    ks[i] = s.speed_mps * 1e3;
    kl[i] = s.fn_N;
    kd[i] = WrapDirection(s.dir_rad);
    const int tx = std::clamp(
        static_cast<int>(3 * (s.x_m - r.x_min) / std::max(r.x_max - r.x_min, 1e-9)), 0, 2);
    const int ty = std::clamp(
        static_cast<int>(3 * (s.y_m - r.y_min) / std::max(r.y_max - r.y_min, 1e-9)), 0, 2);
    kp[i] = 3 * ty + tx;
    kr[i] = s.speed_mps <= kPreslidingSpeed_mps ? 0 : (s.speed_mps < kSlidingSpeed_mps ? 1 : 2);
  }
  const std::pair<const AxisBins*, const std::vector<double>*> axes[] = {
      {&ax.time, &kt}, {&ax.speed, &ks}, {&ax.load, &kl},
      {&ax.dir, &kd},  {&ax.pos, &kp},   {&ax.regime, &kr}};
  auto analyze = [&](const Quantity& q, const std::vector<double>& v,
                     const std::vector<char>& use) {
    for (const auto& [axis, keys] : axes)
      out->push_back(Analyze(
          q, *axis, *keys, ax.multi && axis == &ax.time ? WithinRecording(v, use, krec) : v, use));
    if (ax.multi) out->push_back(Analyze(q, ax.recording, krec, v, use));
  };
  // Normal force: every sample in contact.
  std::vector<char> use(n);
  for (std::size_t i = 0; i < n; ++i) use[i] = r.samples()[i].contact;
  analyze({Channel::kNormal, "normal-force residual",
           [](double v) { return fmt::format("{:+.4f} N", v); }},
          res.normal_N, use);
  // Friction: the friction ratio along the motion (friction / measured load) where the motion
  // has a direction.
  std::vector<double> v(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& s = r.samples()[i];
    use[i] = s.contact && s.speed_mps >= kPreslidingSpeed_mps && s.fn_N > 0.05;
    if (use[i]) v[i] = res.friction_N[i] / s.fn_N;
  }
  analyze({Channel::kFriction, "friction-ratio residual",
           [](double x) { return fmt::format("{:+.3f}", x); }},
          v, use);
}

// Vibration: the window's mean band-power residual over time, speed, load and direction (and
// recording); each band's residual over the bands.
void RankVibrationAxes(const Axes& ax, const Replay& r, const Residuals& res,
                       std::vector<ResidualAxis>* out) {
  if (res.log_band.empty()) return;
  const Quantity q{Channel::kVibration, "band-power residual",
                   [](double v) { return fmt::format("{:+.1f} dB", v); }};
  const std::size_t nw = r.windows.size(), nb = r.band_lo_hz.size();
  const double db = 10 / std::log(10.0);
  std::vector<double> wt(nw), wsp(nw), wl(nw), wd(nw), wv(nw), wrec(nw);
  std::vector<char> all(nw, 1);
  for (std::size_t w = 0; w < nw; ++w) {
    const auto& x = r.windows[w];
    wt[w] = x.t_s - ax.StartOf(x.recording);
    wrec[w] = ax.IndexOf(x.recording);
    wsp[w] = x.speed_mps * 1e3, wl[w] = x.force_N;
    wd[w] = WrapDirection(std::atan2(x.dir[1], x.dir[0]));
    double s = 0;
    for (const double e : res.log_band[w]) s += e;
    wv[w] = s / static_cast<double>(nb) * db;
  }
  out->push_back(Analyze(q, ax.time, wt, ax.multi ? WithinRecording(wv, all, wrec) : wv, all));
  out->push_back(Analyze(q, ax.speed, wsp, wv, all));
  out->push_back(Analyze(q, ax.load, wl, wv, all));
  out->push_back(Analyze(q, ax.dir, wd, wv, all));
  if (ax.multi) out->push_back(Analyze(q, ax.recording, wrec, wv, all));
  std::vector<std::string> labels;
  for (std::size_t b = 0; b < nb; ++b)
    labels.push_back(fmt::format("{:.0f}-{:.0f} Hz", r.band_lo_hz[b], r.band_hi_hz[b]));
  const AxisBins band = Categorical("band", labels);
  std::vector<double> bk, bv;
  for (std::size_t w = 0; w < nw; ++w)
    for (std::size_t b = 0; b < nb; ++b)
      bk.push_back(static_cast<double>(b)), bv.push_back(res.log_band[w][b] * db);
  out->push_back(Analyze(q, band, bk, bv, std::vector<char>(bk.size(), 1)));
}

}  // namespace

std::vector<ResidualAxis> RankResidualAxes(const Model& m, const Replay& r, const Prediction& p) {
  std::vector<ResidualAxis> out;
  const auto res = ComputeResiduals(m, r, p);
  const Axes ax = MakeAxes(r);
  RankForceAxes(ax, r, res, &out);
  RankVibrationAxes(ax, r, res, &out);
  std::stable_sort(out.begin(), out.end(),
                   [](const ResidualAxis& a, const ResidualAxis& b) { return a.share > b.share; });
  return out;
}

// ---------------------------------------------------------------------------------------------
Unexplained ExplainResidual(const Model& base, const Replay& r, const Prediction& pbase,
                            const Errors& ebase, bool any_supported, double unexplained_ratio) {
  Unexplained u;
  const auto floor = EstimateNoiseFloor(r, Split::kHeldOut, &base);
  std::set<Channel> above;
  for (const auto& [ch, e] : ebase.Normalized()) {
    UnexplainedChannel x{ch, e, floor.count(ch) ? floor.at(ch) : 0, 0};
    x.ratio = x.noise_floor > 0 ? x.error / x.noise_floor : 0;
    if (x.ratio >= unexplained_ratio) above.insert(ch);
    u.channels.push_back(x);
  }
  std::stable_sort(
      u.channels.begin(), u.channels.end(),
      [](const UnexplainedChannel& a, const UnexplainedChannel& b) { return a.ratio > b.ratio; });
  u.axes = RankResidualAxes(base, r, pbase);
  std::stable_sort(u.axes.begin(), u.axes.end(), [&](const ResidualAxis& a, const ResidualAxis& b) {
    const bool ia = above.count(a.channel) > 0, ib = above.count(b.channel) > 0;
    return ia != ib ? ia : a.share > b.share;
  });
  u.flagged = !any_supported && !above.empty();
  if (!u.channels.empty()) {
    const auto& worst = u.channels.front();
    const ResidualAxis* top = nullptr;
    for (const auto& a : u.axes)
      if (a.channel == worst.channel) {
        top = &a;
        break;
      }
    if (u.flagged && top) {
      u.summary = fmt::format(
          "No catalogue effect explains the residual: the held-out {} error is {:.1f}x its noise "
          "floor ({:.4f} against "
          "{:.4f}). It lives mostly along {} ({:.0f} % of its variance): {}. An effect of the {} "
          "channel {} is needed; "
          "docs/workbench.md, \"Adding an effect\", shows how to add one.",
          ChannelName(worst.channel), worst.ratio, worst.error, worst.noise_floor, top->axis,
          100 * top->share, top->description, ChannelName(worst.channel), Hint(top->axis));
    } else if (!above.empty() && top) {
      u.summary = fmt::format(
          "The held-out {} error is {:.1f}x its noise floor; most of its residual variance is "
          "along "
          "{} ({:.0f} %): {}.",
          ChannelName(worst.channel), worst.ratio, top->axis, 100 * top->share, top->description);
    } else {
      u.summary = fmt::format(
          "Every channel's held-out error is within {:.1f}x its noise floor (largest: {} at "
          "{:.2f}x).",
          unexplained_ratio, ChannelName(worst.channel), worst.ratio);
    }
  }
  return u;
}

}  // namespace hapticlab::modeling::wb
