#include "hapticlab/modeling/neural.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <mutex>
#include <span>
#include <thread>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/modeling/cross_validation.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "neural_fit.hpp"
#include "neural_internal.hpp"

namespace hapticlab::modeling {

using namespace neural_internal;  // NOLINT(google-build-using-namespace): FitNeural's own helpers
using namespace neural_fit;       // NOLINT(google-build-using-namespace): its shared state

namespace {

// The training grid from the recordings' conditions (a full speed x force grid, one recording
// per cell); returns each recording's cell. @throws InputError naming every gap and repeat.
std::vector<int> GridCells(const std::vector<Recording>& recs, renderer::NeuralModel* m) {
  std::vector<double> vs, fs;
  for (const auto& r : recs) vs.push_back(r.speed_mps), fs.push_back(r.force_N);
  m->speeds_mps = Unique(vs);
  m->forces_N = Unique(fs);
  const std::size_t nf = m->forces_N.size(), cells = m->speeds_mps.size() * nf;
  std::vector<int> cell_of(recs.size());
  std::vector<int> rec_of(cells, -1);
  Diagnostics d;
  for (std::size_t i = 0; i < recs.size(); ++i) {
    const int c = Index(m->speeds_mps, recs[i].speed_mps) * static_cast<int>(nf) +
                  Index(m->forces_N, recs[i].force_N);
    cell_of[i] = c;
    if (rec_of[static_cast<std::size_t>(c)] >= 0)
      d.Add(recs[i].file, 0, "speed_mps",
            fmt::format("a second recording at {} m/s, {} N", recs[i].speed_mps, recs[i].force_N));
    rec_of[static_cast<std::size_t>(c)] = static_cast<int>(i);
  }
  for (std::size_t c = 0; c < cells; ++c)
    if (rec_of[c] < 0)
      d.Add("", 0, "recordings",
            fmt::format(
                "the neural model needs a full speed x force grid: no recording at {} m/s, {} N",
                m->speeds_mps[c / nf], m->forces_N[c % nf]));
  d.ThrowIfAny();
  return cell_of;
}

// Band signals (decimated) per recording, each band's scale, and the bands' sigma and network
// slots.
void BandSignals(FitShared& s, const std::vector<std::vector<double>>& pre) {
  s.m.bands = s.o.bands;
  s.sig.assign(s.m.bands.size(), {});
  for (std::size_t b = 0; b < s.m.bands.size(); ++b) {
    auto& band = s.m.bands[b];
    band.nets.clear();
    double ss = 0, n = 0;
    for (std::size_t i = 0; i < s.recs.size(); ++i) {
      // The network's signal: the recording low-passed (ideal) to its decimated Nyquist
      // frequency, not band-passed to the band: a band-passed signal is zero over most of
      // the decimated range, so a predictor fitted to it is ill-conditioned (it needed a
      // dither whose white floor then showed in and around every band). The band itself is
      // selected at synthesis by the crossover filters (renderer/neural.cpp).
      const auto full =
          BandSplit(pre[i], s.m.sample_rate_hz, 0, 0.5 * s.m.sample_rate_hz / band.decimation);
      std::vector<double> dec;
      for (std::size_t k = 0; k < full.size(); k += static_cast<std::size_t>(band.decimation))
        dec.push_back(full[k]);
      for (const double x : dec) ss += x * x, n += 1;
      s.sig[b].push_back(std::move(dec));
    }
    band.scale = n > 0 && ss > 0 ? std::sqrt(ss / n) : 1.0;
    Rng dither(s.o.train.seed + 7 * b + 1);
    for (auto& sg : s.sig[b])
      for (auto& x : sg)
        x = x / band.scale + (s.o.signal_noise > 0 ? s.o.signal_noise * dither.Normal() : 0.0);
    band.sigma.assign(s.cells, 0.0);
    band.nets.resize(s.unified ? 1 : s.cells);
  }
}

JobRows BuildRows(const FitShared& s, const Job& j) {
  JobRows out;
  out.M = s.m.bands[j.band].history;
  const int M = out.M;
  out.inputs = M + (s.unified ? 2 : 0);
  for (std::size_t i = 0; i < s.recs.size(); ++i)
    if (s.unified || s.cell_of[i] == j.cell) out.use.push_back(i);
  for (const bool val : {false, true})
    for (const auto i : out.use) {
      const auto [a, b] = s.RowsOf(j, i, val);
      out.total += static_cast<Eigen::Index>(b - a);
    }
  out.X.resize(out.total, out.inputs);
  out.y.resize(out.total);
  out.row_cell.resize(static_cast<std::size_t>(out.total));
  Eigen::Index r = 0;
  for (const bool val : {false, true})
    for (const auto i : out.use) {
      const auto& x = s.sig[j.band][i];
      const auto [a, b] = s.RowsOf(j, i, val);
      for (std::size_t t = a; t < b; ++t, ++r) {
        for (int q = 0; q < M; ++q) out.X(r, q) = x[t - 1 - static_cast<std::size_t>(q)];
        if (s.unified) {
          out.X(r, M) = s.m.NormSpeed(s.recs[i].speed_mps);
          out.X(r, M + 1) = s.m.NormForce(s.recs[i].force_N);
        }
        out.y(r) = x[t];
        out.row_cell[static_cast<std::size_t>(r)] = static_cast<std::size_t>(s.cell_of[i]);
      }
      if (val) out.nval += static_cast<Eigen::Index>(b - a);
    }
  return out;
}

// A network's name in progress messages.
std::string JobName(const FitShared& s, const Job& j) {
  return s.unified ? fmt::format("band {}", j.band + 1)
                   : fmt::format("band {} cell ({} m/s, {} N)", j.band + 1,
                                 s.m.speeds_mps[static_cast<std::size_t>(j.cell) / s.nf],
                                 s.m.forces_N[static_cast<std::size_t>(j.cell) % s.nf]);
}

// The network of job k, trained on what the linear part leaves (y_mlp) from histories with
// input noise (NeuralFitOptions::input_noise, added to rows.X here).
Mlp TrainNetwork(const FitShared& s, const Job& j, std::size_t k, JobRows& rows,
                 const Eigen::VectorXd& y_mlp, Eigen::Index nlin, std::vector<int>* layers) {
  const auto& o = s.o;
  if (o.input_noise > 0) {
    Rng nr(o.train.seed + 31 * k);
    for (Eigen::Index r = 0; r < rows.total; ++r)
      for (int q = 0; q < rows.M; ++q) rows.X(r, q) += o.input_noise * nr.Normal();
  }
  *layers = {rows.inputs};
  const auto& hidden = (s.unified || j.band == 0) ? o.hidden_large : o.hidden_small;
  layers->insert(layers->end(), hidden.begin(), hidden.end());
  layers->push_back(1);
  Mlp net(*layers, o.train.seed + 1000 * k);
  MlpTrainOptions to = o.train;
  to.validation_fraction =
      rows.total > 0 ? static_cast<double>(rows.nval) / static_cast<double>(rows.total) : 0.2;
  to.seed = o.train.seed + k;
  to.progress = nullptr;
  if (o.progress)  // every 5th epoch: training can take minutes per network
    to.progress = [&s, name = JobName(s, j)](int epoch, double val_mse) {
      if (epoch % 5 == 0)
        s.Progress(fmt::format("{}: epoch {}/{}, validation MSE {:.4f}", name, epoch,
                               s.o.train.max_epochs, val_mse));
    };
  // Zero output layer: the network starts as exactly the linear part (its output is 0), so
  // training can only move away from the linear predictor where the data ask for it.
  const auto& l = *layers;
  if (nlin > 0) net.params().tail(l[l.size() - 2] + 1).setZero();
  net.Train(rows.X, y_mlp, to);
  return net;
}

// One job's predictor as synthesis runs it: the network (unless `mlp` is false: the linear
// part alone) plus the linear part at a cell.
struct Predictor {
  const Mlp& net;
  bool mlp;
  const LinearFit& lin;
  Eigen::Index nlin;
  int M;
  double operator()(const Eigen::VectorXd& in, std::size_t c) const {
    double v = mlp ? net.Predict(in) : 0.0;
    if (nlin > 0) v += in.head(M).dot(lin.a_cell[c]);
    return v;
  }
};

// Sigma scaled until the free-running signal has each recording's RMS inside the band (what
// the crossovers pass; three fixed-point passes): a trained predictor shrinks toward zero, so
// synthesis driven by the one-step residual would have too little power.
void CalibrateSigmas(const FitShared& s, const Job& j, std::size_t k, const JobRows& rows,
                     const Predictor& predict, std::vector<double>* sigma) {
  const auto& band = s.m.bands[j.band];
  const double rate_dec = s.m.sample_rate_hz / band.decimation;
  auto in_band_rms = [&](const std::vector<double>& x) {
    const auto bx = BandSplit(x, rate_dec, band.lo_hz, band.hi_hz);
    double q = 0;
    for (const double v : bx) q += v * v;
    return std::sqrt(q / static_cast<double>(std::max<std::size_t>(1, bx.size())));
  };
  const int M = rows.M;
  for (const auto i : rows.use) {
    const auto c = static_cast<std::size_t>(s.cell_of[i]);
    const double target = in_band_rms(s.sig[j.band][i]);
    Rng rng(s.o.train.seed + 7919 * k + c);
    Eigen::VectorXd in = Eigen::VectorXd::Zero(rows.inputs);
    if (s.unified) {
      in(M) = s.m.NormSpeed(s.recs[i].speed_mps);
      in(M + 1) = s.m.NormForce(s.recs[i].force_N);
    }
    std::vector<double> run;
    for (int pass = 0; pass < 3 && target > 0; ++pass) {
      in.head(M).setZero();
      run.clear();
      const int warm = 300, steps = 3000;
      for (int t = 0; t < warm + steps; ++t) {
        double yv = predict(in, c) + (*sigma)[c] * rng.Normal();
        yv = std::clamp(std::isfinite(yv) ? yv : 0.0, -10.0, 10.0);
        for (int q = M - 1; q > 0; --q) in(q) = in(q - 1);
        in(0) = yv;
        if (t >= warm) run.push_back(yv);
      }
      const double got = in_band_rms(run);
      if (!(got > 0)) break;
      (*sigma)[c] *= std::clamp(target / got, 0.25, 4.0);
    }
  }
}

// Sigma per cell for the network with (mlp) or without its nonlinear part: the one-step residual
// RMS on every row of the cell's recording (with a linear part, on the clean histories the
// synthesis feeds it), then calibrated (CalibrateSigmas).
std::vector<double> Sigmas(const FitShared& s, const Job& j, std::size_t k, const JobRows& rows,
                           const Eigen::MatrixXd& Xclean, const Mlp& net, bool mlp,
                           const LinearForm& form, const LinearFit& lin) {
  std::vector<double> sigma(s.cells, 0.0);
  const Eigen::VectorXd p = !mlp            ? lin.ylin
                            : form.nlin > 0 ? Eigen::VectorXd(net.PredictRows(Xclean) + lin.ylin)
                                            : net.PredictRows(rows.X);
  std::vector<double> se(s.cells, 0.0), cnt(s.cells, 0.0);
  Eigen::Index row = 0;
  for (const bool val : {false, true})
    for (const auto i : rows.use) {
      const auto [a, b] = s.RowsOf(j, i, val);
      for (std::size_t t = a; t < b; ++t, ++row) {
        const auto c = static_cast<std::size_t>(s.cell_of[i]);
        se[c] += (p(row) - rows.y(row)) * (p(row) - rows.y(row));
        cnt[c] += 1;
      }
    }
  for (std::size_t c = 0; c < s.cells; ++c)
    if (cnt[c] > 0) sigma[c] = std::sqrt(se[c] / cnt[c]);
  CalibrateSigmas(s, j, k, rows, Predictor{net, mlp, lin, form.nlin, rows.M}, &sigma);
  return sigma;
}

// What one network's fit leaves besides the network itself: its clean histories, layers and
// linear forms, for the linear-part-alone variants.
struct JobFit {
  const Job& j;
  std::size_t k;
  const JobRows& rows;
  const Eigen::MatrixXd& Xclean;
  const Mlp& net;
  const LinearForm& form;
  const std::vector<int>& layers;
};

// The linear part alone (the network's output 0) into `to_bands`, with sigma calibrated for it:
// as selected on validation data (fitted on the training rows), and as returned when selected
// (refit_linear_part: the same least squares on every row).
void SetLinearAlone(const FitShared& s, const JobFit& f, const LinearFit& lin,
                    std::vector<renderer::NeuralBand>* to_bands) {
  const auto without = Sigmas(s, f.j, f.k, f.rows, f.Xclean, f.net, false, f.form, lin);
  auto& band = (*to_bands)[f.j.band];
  for (const auto i : f.rows.use)
    band.sigma[static_cast<std::size_t>(s.cell_of[i])] =
        without[static_cast<std::size_t>(s.cell_of[i])];
  renderer::NeuralNet net0{
      f.layers, std::vector<double>(static_cast<std::size_t>(f.net.params().size()), 0.0),
      std::vector<double>(lin.w.data(), lin.w.data() + lin.w.size())};
  band.nets[s.unified ? 0 : static_cast<std::size_t>(f.j.cell)] = std::move(net0);
  band.cell_ar = lin.cell_ar;
}

// The refit on every row must stay a stable filter wherever the model plays, as the
// training-rows fit is (Γ_D's at its cell, where its linear weights are one AR(M)): a refit that
// is not keeps the training-rows fit (per-cell Levinson fits always are).
void SetRefitLinearAlone(FitShared& s, const JobFit& f, const LinearFit& lin_train,
                         const LinearFit& lin_all) {
  bool stable = true;
  std::string where;
  if (!f.form.per_cell) {
    const auto hull = ConditionBasisMaxRadius(
        Eigen::Map<const Eigen::MatrixXd>(lin_all.w.data(), f.rows.M, f.form.terms),
        s.unified ? 41 : 1);
    stable = hull.radius < 1;
    if (!stable) where = fmt::format(" (pole radius {:.3f})", hull.radius);
  }
  SetLinearAlone(s, f, stable ? lin_all : lin_train, &s.linear_refit);
  if (!stable)
    s.Progress(
        fmt::format("{}: the linear part refitted on every row is not a stable filter{}; "
                    "if the linear parts alone are kept, this one keeps its training-rows "
                    "fit",
                    JobName(s, f.j), where));
}

// Job k: its rows, its stable linear part, its network and sigmas, and the linear-part-alone
// variants the validation chooses between.
void FitJob(FitShared& s, std::size_t k) {
  const Job& j = s.jobs[k];
  auto& band = s.m.bands[j.band];
  JobRows rows = BuildRows(s, j);
  LinearForm form;
  const LinearFit lin_train = FitStableLinear(s, j, rows, &form);
  // Before the input noise: the refit, like the first fit, is on clean histories.
  const LinearFit lin_all =
      s.refit && form.nlin > 0 ? FitLinear(s, j, rows, form, true) : LinearFit{};
  const Eigen::MatrixXd Xclean = form.nlin > 0 ? rows.X : Eigen::MatrixXd();
  const Eigen::VectorXd y_mlp = rows.y - lin_train.ylin;  // what the MLP learns
  std::vector<int> layers;
  const Mlp net = TrainNetwork(s, j, k, rows, y_mlp, form.nlin, &layers);
  renderer::NeuralNet out{
      layers, std::vector<double>(net.params().data(), net.params().data() + net.params().size()),
      std::vector<double>(lin_train.w.data(), lin_train.w.data() + lin_train.w.size())};
  const auto with_mlp = Sigmas(s, j, k, rows, Xclean, net, true, form, lin_train);
  for (const auto i : rows.use)
    band.sigma[static_cast<std::size_t>(s.cell_of[i])] =
        with_mlp[static_cast<std::size_t>(s.cell_of[i])];
  const JobFit f{j, k, rows, Xclean, net, form, layers};
  if (form.nlin > 0) SetLinearAlone(s, f, lin_train, &s.linear_only);
  if (form.nlin > 0 && s.refit) SetRefitLinearAlone(s, f, lin_train, lin_all);
  band.nets[s.unified ? 0 : static_cast<std::size_t>(j.cell)] = std::move(out);
  band.cell_ar = lin_train.cell_ar;
  if (s.o.progress)
    s.o.progress(JobName(s, j) + ": trained", static_cast<int>(++s.done),
                 static_cast<int>(s.jobs.size()));
}

// Every job, on o.threads threads (0: all cores); the first exception is rethrown.
void RunJobs(FitShared& s) {
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex err_mu;
  auto work = [&] {
    for (std::size_t k; (k = next++) < s.jobs.size();) {
      try {
        FitJob(s, k);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(err_mu);
        if (!error) error = std::current_exception();
      }
    }
  };
  const int threads =
      s.o.threads > 0 ? s.o.threads : std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

// Model selection on validation data: free-running E_s (the Fig. 3.7 measure) of each variant
// against the last validation_fraction of every recording, which no linear part was fitted on;
// both variants driven by the same noise (seed per recording).
void SelectOnValidation(FitShared& s, const std::vector<std::vector<double>>& pre) {
  auto& m = s.m;
  const auto& o = s.o;
  auto validation_es = [&](const std::vector<renderer::NeuralBand>& bands) {
    return ValidationEs(m, bands, s.recs, pre, o.train.validation_fraction, o.train.seed);
  };
  const double es_mlp = validation_es(m.bands), es_lin = validation_es(s.linear_only);
  const bool keep = !(es_lin <= es_mlp);
  if (!keep) {
    m.bands = std::move(s.refit ? s.linear_refit : s.linear_only);
    if (s.refit) renderer::FillNeuralCellLsf(&m);  // the refitted cell_ar's LSFs
  }
  if (o.progress)
    o.progress(fmt::format("validation E_s: {:.4f} with the nonlinear part, {:.4f} with the "
                           "linear part alone: {} kept{}",
                           es_mlp, es_lin, keep ? "nonlinear part" : "linear part alone",
                           !keep && s.refit ? ", refitted on every row" : ""),
               static_cast<int>(s.jobs.size()), static_cast<int>(s.jobs.size()));
}

}  // namespace

renderer::NeuralModel FitNeural(const std::vector<Recording>& recs, const NeuralFitOptions& o) {
  renderer::NeuralModel m;
  m.topology = o.topology;
  m.sample_rate_hz = o.preprocess.model_rate_hz;
  m.min_speed_mps = o.min_speed_mps;
  m.calibrated = AllCalibrated(recs);
  FitShared s{recs, o, m};
  s.unified = o.topology == renderer::NeuralTopology::kUnified;
  s.cell_of = GridCells(recs, &m);
  s.nf = m.forces_N.size();
  s.cells = m.speeds_mps.size() * s.nf;
  std::vector<std::vector<double>> pre(recs.size());
  for (std::size_t i = 0; i < recs.size(); ++i) pre[i] = Preprocess(recs[i], o.preprocess);
  BandSignals(s, pre);
  for (std::size_t b = 0; b < m.bands.size(); ++b) {
    if (s.unified)
      s.jobs.push_back({b, -1});
    else
      for (std::size_t c = 0; c < s.cells; ++c) s.jobs.push_back({b, static_cast<int>(c)});
  }
  s.linear_only = m.bands;
  s.refit = o.linear_part && o.validate_nonlinear_part && o.refit_linear_part;
  s.linear_refit = m.bands;
  RunJobs(s);
  renderer::FillNeuralCellLsf(&m);  // once here, not in every synthesizer
  for (std::size_t b = 0; b < m.bands.size(); ++b) s.linear_only[b].cell_lsf = m.bands[b].cell_lsf;
  if (o.linear_part && o.validate_nonlinear_part) SelectOnValidation(s, pre);
  RequireStableLinearParts(m, [&](const std::string& what) {
    if (o.progress)
      o.progress(what, static_cast<int>(s.jobs.size()), static_cast<int>(s.jobs.size()));
  });
  renderer::ValidateNeuralModel(m);
  return m;
}

}  // namespace hapticlab::modeling
