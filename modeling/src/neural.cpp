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
#include "neural_internal.hpp"

namespace hapticlab::modeling {

using namespace neural_internal;  // NOLINT(google-build-using-namespace): FitNeural's own helpers

renderer::NeuralModel FitNeural(const std::vector<Recording>& recs, const NeuralFitOptions& o) {
  renderer::NeuralModel m;
  m.topology = o.topology;
  m.sample_rate_hz = o.preprocess.model_rate_hz;
  m.min_speed_mps = o.min_speed_mps;
  std::vector<double> vs, fs;
  for (const auto& r : recs) vs.push_back(r.speed_mps), fs.push_back(r.force_N);
  m.speeds_mps = Unique(vs);
  m.forces_N = Unique(fs);
  const std::size_t nv = m.speeds_mps.size(), nf = m.forces_N.size(), cells = nv * nf;
  // The recordings must form a full grid, one per cell.
  std::vector<int> cell_of(recs.size());
  std::vector<int> rec_of(cells, -1);
  Diagnostics d;
  for (std::size_t i = 0; i < recs.size(); ++i) {
    const int c = Index(m.speeds_mps, recs[i].speed_mps) * static_cast<int>(nf) +
                  Index(m.forces_N, recs[i].force_N);
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
                m.speeds_mps[c / nf], m.forces_N[c % nf]));
  d.ThrowIfAny();

  std::vector<std::vector<double>> pre(recs.size());
  for (std::size_t i = 0; i < recs.size(); ++i) pre[i] = Preprocess(recs[i], o.preprocess);

  const bool unified = o.topology == renderer::NeuralTopology::kUnified;
  m.bands = o.bands;
  // Band signals (decimated) per recording, and each band's scale.
  std::vector<std::vector<std::vector<double>>> sig(m.bands.size());
  for (std::size_t b = 0; b < m.bands.size(); ++b) {
    auto& band = m.bands[b];
    band.nets.clear();
    double ss = 0, n = 0;
    for (std::size_t i = 0; i < recs.size(); ++i) {
      // The network's signal: the recording low-passed (ideal) to its decimated Nyquist
      // frequency, not band-passed to the band: a band-passed signal is zero over most of
      // the decimated range, so a predictor fitted to it is ill-conditioned (it needed a
      // dither whose white floor then showed in and around every band). The band itself is
      // selected at synthesis by the crossover filters (renderer/neural.cpp).
      const auto full =
          BandSplit(pre[i], m.sample_rate_hz, 0, 0.5 * m.sample_rate_hz / band.decimation);
      std::vector<double> dec;
      for (std::size_t k = 0; k < full.size(); k += static_cast<std::size_t>(band.decimation))
        dec.push_back(full[k]);
      for (const double x : dec) ss += x * x, n += 1;
      sig[b].push_back(std::move(dec));
    }
    band.scale = n > 0 && ss > 0 ? std::sqrt(ss / n) : 1.0;
    Rng dither(o.train.seed + 7 * b + 1);
    for (auto& s : sig[b])
      for (auto& x : s)
        x = x / band.scale + (o.signal_noise > 0 ? o.signal_noise * dither.Normal() : 0.0);
    band.sigma.assign(cells, 0.0);
    band.nets.resize(unified ? 1 : cells);
  }

  // One job per network: (band, cell) for Γ_D, (band) for Γ_U.
  struct Job {
    std::size_t band;
    int cell;  // -1: unified
  };
  std::vector<Job> jobs;
  for (std::size_t b = 0; b < m.bands.size(); ++b) {
    if (unified)
      jobs.push_back({b, -1});
    else
      for (std::size_t c = 0; c < cells; ++c) jobs.push_back({b, static_cast<int>(c)});
  }
  auto rows_of = [&](const Job& j, std::size_t i, bool validation) {
    // Pairs of recording i: training rows are the first 80 %, validation the last 20 %.
    const auto& x = sig[j.band][i];
    const int M = m.bands[j.band].history;
    const std::size_t first = static_cast<std::size_t>(M),
                      n = x.size() > first ? x.size() - first : 0;
    const std::size_t cut =
        first + n -
        static_cast<std::size_t>(std::floor(o.train.validation_fraction * static_cast<double>(n)));
    return validation ? std::make_pair(cut, x.size()) : std::make_pair(first, cut);
  };
  // The same networks without their nonlinear part (output 0: the linear part alone), with
  // their own calibrated sigma; kept when it synthesizes the validation data better.
  std::vector<renderer::NeuralBand> linear_only = m.bands;
  // The linear parts refitted on every row of every recording, returned in place of
  // linear_only when validation keeps the linear parts alone (NeuralFitOptions::refit_linear_part).
  const bool refit = o.linear_part && o.validate_nonlinear_part && o.refit_linear_part;
  std::vector<renderer::NeuralBand> linear_refit = m.bands;
  std::atomic<std::size_t> next{0}, done{0};
  std::exception_ptr error;
  std::mutex err_mu;
  auto work = [&] {
    for (std::size_t k; (k = next++) < jobs.size();) {
      try {
        const Job& j = jobs[k];
        auto& band = m.bands[j.band];
        const int M = band.history;
        const int inputs = M + (unified ? 2 : 0);
        std::vector<std::size_t> use;
        for (std::size_t i = 0; i < recs.size(); ++i)
          if (unified || cell_of[i] == j.cell) use.push_back(i);
        // Rows: every used recording's training part, then every validation part.
        Eigen::Index total = 0;
        for (const bool val : {false, true})
          for (const auto i : use) {
            const auto [a, b] = rows_of(j, i, val);
            total += static_cast<Eigen::Index>(b - a);
          }
        Eigen::MatrixXd X(total, inputs);
        Eigen::VectorXd y(total);
        std::vector<std::size_t> row_cell(static_cast<std::size_t>(total));  // grid cell per row
        Eigen::Index r = 0, nval = 0;
        for (const bool val : {false, true})
          for (const auto i : use) {
            const auto& x = sig[j.band][i];
            const auto [a, b] = rows_of(j, i, val);
            for (std::size_t t = a; t < b; ++t, ++r) {
              for (int q = 0; q < M; ++q) X(r, q) = x[t - 1 - static_cast<std::size_t>(q)];
              if (unified) {
                X(r, M) = m.NormSpeed(recs[i].speed_mps);
                X(r, M + 1) = m.NormForce(recs[i].force_N);
              }
              y(r) = x[t];
              row_cell[static_cast<std::size_t>(r)] = static_cast<std::size_t>(cell_of[i]);
            }
            if (val) nval += static_cast<Eigen::Index>(b - a);
          }
        // The linear part (NeuralFitOptions::linear_part): least squares on the clean training
        // rows. Γ_U with per-cell AR fits (UnifiedLinearPart::kCellAr): one AR(M) per
        // recording, on its own rows; at synthesis the cells' fits are mixed as the LPC bank's
        // (renderer/neural.cpp). Otherwise the features are phi(v', f') (x) x (Γ_D: phi = 1;
        // Γ_U: the condition basis, with no more terms than the grid has nodes: issue #33, the 9
        // terms on a 2 x 2 grid were underdetermined and unstable between nodes; the terms
        // ActiveConditionTerms leaves out are fitted as zero), phi constant within a recording:
        // the normal matrix is sum over recordings of (phi phi^T) (x) (X_i^T X_i). Either way
        // the linear part at a training cell is one AR(M), `a_cell[c]`.
        bool per_cell = unified && o.unified_linear == UnifiedLinearPart::kCellAr;
        Eigen::Index terms = unified && !per_cell ? 9 : 1, nlin = o.linear_part ? terms * M : 0;
        const auto active = ActiveConditionTerms(nv, nf);
        auto basis = [&](double v, double fo) { return ConditionBasis(v, fo, terms); };
        // Per-cell AR order: as the LPC bank chooses its order (PerCellArOrder).
        Eigen::Index p_lin = M;
        auto choose_p_lin = [&] {
          std::vector<std::vector<double>> train;
          for (const auto i : use) {
            const auto& x = sig[j.band][i];
            train.emplace_back(
                x.begin(), x.begin() + static_cast<std::ptrdiff_t>(rows_of(j, i, false).second));
          }
          p_lin = PerCellArOrder(train, M, o.preprocess);
          if (o.progress)
            o.progress(fmt::format("band {}: per-cell AR order {} (as the LPC bank chooses)",
                                   j.band + 1, p_lin),
                       static_cast<int>(done.load()), static_cast<int>(jobs.size()));
        };
        if (per_cell && o.linear_part) choose_p_lin();
        // The linear part fitted on the training rows (all_rows false: the first 80 % of every
        // recording, what the networks are trained beside and the model selection compares) or
        // on every row (the refit of the linear part alone once validation has chosen it).
        struct LinearFit {
          Eigen::VectorXd w;                         // the network's linear weights (terms x M)
          std::vector<Eigen::VectorXd> a_cell;       // the AR(M) at each training cell
          std::vector<std::vector<double>> cell_ar;  // per_cell: the band's NeuralBand::cell_ar
          Eigen::VectorXd ylin;                      // its one-step prediction of every row
        };
        auto fit_linear = [&](bool all_rows) {
          LinearFit f{Eigen::VectorXd::Zero(nlin),
                      std::vector<Eigen::VectorXd>(cells, Eigen::VectorXd::Zero(M)),
                      {},
                      Eigen::VectorXd::Zero(total)};
          if (nlin == 0) return f;
          const Eigen::Index p = per_cell ? p_lin : M;
          // Per recording (as laid out in X): the Gram matrix and moment vector of its rows.
          std::vector<Eigen::MatrixXd> G(use.size(), Eigen::MatrixXd::Zero(p, p));
          std::vector<Eigen::VectorXd> g(use.size(), Eigen::VectorXd::Zero(p));
          Eigen::Index off = 0;
          for (const bool val : {false, true})
            for (std::size_t u = 0; u < use.size(); ++u) {
              const auto [a, b] = rows_of(j, use[u], val);
              const auto n = static_cast<Eigen::Index>(b - a);
              if (!val || all_rows) {
                const auto Xi = X.block(off, 0, n, p);
                G[u] += Xi.transpose() * Xi;
                g[u] += Xi.transpose() * y.segment(off, n);
              }
              off += n;
            }
          Eigen::MatrixXd A = Eigen::MatrixXd::Zero(nlin, nlin);
          Eigen::VectorXd rhs = Eigen::VectorXd::Zero(nlin);
          for (std::size_t u = 0; u < use.size(); ++u) {
            const auto i = use[u];
            const auto c = static_cast<std::size_t>(cell_of[i]);
            if (per_cell) {
              G[u].diagonal().array() += o.linear_ridge * G[u].trace() / static_cast<double>(p);
              f.a_cell[c].head(p) = G[u].ldlt().solve(g[u]);
              if (!renderer::IsStableAr(
                      std::span<const double>(f.a_cell[c].data(), static_cast<std::size_t>(p)))) {
                // The covariance-method fit need not be minimum phase, and LSF mixing needs
                // it: the autocorrelation method (Levinson, as the LPC bank) always is.
                const auto& x = sig[j.band][i];
                const auto end = all_rows ? x.size() : rows_of(j, i, false).second;
                const auto fit = FitAr(
                    std::vector<double>(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(end)),
                    static_cast<int>(p));
                f.a_cell[c].head(p) = Eigen::Map<const Eigen::VectorXd>(fit.coeffs.data(), p);
                if (o.progress)
                  o.progress(fmt::format("band {}: the least-squares AR({}) at {} m/s, {} N is "
                                         "not minimum phase; the Levinson fit is used there",
                                         j.band + 1, p, recs[i].speed_mps, recs[i].force_N),
                             static_cast<int>(done.load()), static_cast<int>(jobs.size()));
              }
              continue;
            }
            const Eigen::VectorXd phi =
                unified ? basis(m.NormSpeed(recs[i].speed_mps), m.NormForce(recs[i].force_N))
                        : basis(0, 0);
            for (Eigen::Index t = 0; t < terms; ++t) {
              rhs.segment(t * M, M) += phi(t) * g[u];
              for (Eigen::Index s = 0; s < terms; ++s)
                A.block(t * M, s * M, M, M) += (phi(t) * phi(s)) * G[u];
            }
          }
          if (per_cell) {
            for (const auto& a : f.a_cell) f.cell_ar.emplace_back(a.data(), a.data() + p);
            f.w.resize(0);  // the network itself has no linear weights
          } else {
            const double lambda = o.linear_ridge * A.trace() / static_cast<double>(nlin);
            A.diagonal().array() += lambda;
            for (Eigen::Index t = 0; t < terms; ++t)
              if (terms > 1 && !active[static_cast<std::size_t>(t)]) {  // fitted as zero
                A.middleRows(t * M, M).setZero();
                A.middleCols(t * M, M).setZero();
                A.block(t * M, t * M, M, M).setIdentity();
                rhs.segment(t * M, M).setZero();
              }
            f.w = A.ldlt().solve(rhs);
            if (!unified && !renderer::IsStableAr(std::span<const double>(f.w.data(), M))) {
              // Γ_D's covariance-method fit at its cell need not be minimum phase: Levinson's is.
              const auto& x = sig[j.band][use.front()];
              const auto end = all_rows ? x.size() : rows_of(j, use.front(), false).second;
              f.w = Eigen::Map<const Eigen::VectorXd>(
                  FitAr(
                      std::vector<double>(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(end)),
                      M)
                      .coeffs.data(),
                  M);
            }
            // The AR coefficients at each training cell: the M x terms weights times phi.
            const Eigen::Map<const Eigen::MatrixXd> W(f.w.data(), M, terms);
            for (const auto i : use)
              f.a_cell[static_cast<std::size_t>(cell_of[i])] =
                  W * (unified ? basis(m.NormSpeed(recs[i].speed_mps), m.NormForce(recs[i].force_N))
                               : basis(0, 0));
          }
          for (Eigen::Index rr = 0; rr < total; ++rr)
            f.ylin(rr) = X.row(rr).head(M).dot(f.a_cell[row_cell[static_cast<std::size_t>(rr)]]);
          return f;
        };
        LinearFit lin_train = fit_linear(false);
        // Stable wherever the model plays, at fit time: the condition basis's filter over a
        // fine grid of the hull; where it is not, per-cell AR fits mixed in LSF form (stable by
        // construction) before the network learns what the linear part leaves.
        if (const auto hull = unified && !per_cell && nlin > 0
                                  ? ConditionBasisMaxRadius(Eigen::Map<const Eigen::MatrixXd>(
                                        lin_train.w.data(), M, terms))
                                  : NeuralPoleRadius{};
            !(hull.radius < 1)) {
          if (o.progress)
            o.progress(fmt::format("band {}: the condition basis has a pole at radius {:.3f}; "
                                   "fitted per cell and mixed in LSF form instead",
                                   j.band + 1, hull.radius),
                       static_cast<int>(done.load()), static_cast<int>(jobs.size()));
          per_cell = true, terms = 1, nlin = M;
          choose_p_lin();
          lin_train = fit_linear(false);
        }
        // Before the input noise below: the refit, like the first fit, is on clean histories.
        const LinearFit lin_all = refit && nlin > 0 ? fit_linear(true) : LinearFit{};
        const Eigen::VectorXd& wlin = lin_train.w;
        const Eigen::VectorXd& ylin = lin_train.ylin;
        const Eigen::MatrixXd Xclean = nlin > 0 ? X : Eigen::MatrixXd();
        const Eigen::VectorXd y_mlp = y - ylin;  // what the MLP learns
        // Input noise (see NeuralFitOptions::input_noise).
        const double in_noise = o.input_noise;
        if (in_noise > 0) {
          Rng nr(o.train.seed + 31 * k);
          for (Eigen::Index rr = 0; rr < total; ++rr)
            for (int q = 0; q < M; ++q) X(rr, q) += in_noise * nr.Normal();
        }
        std::vector<int> layers{inputs};
        const auto& hidden = (unified || j.band == 0) ? o.hidden_large : o.hidden_small;
        layers.insert(layers.end(), hidden.begin(), hidden.end());
        layers.push_back(1);
        Mlp net(layers, o.train.seed + 1000 * k);
        MlpTrainOptions to = o.train;
        to.validation_fraction =
            total > 0 ? static_cast<double>(nval) / static_cast<double>(total) : 0.2;
        to.seed = o.train.seed + k;
        const std::string name =
            unified ? fmt::format("band {}", j.band + 1)
                    : fmt::format("band {} cell ({} m/s, {} N)", j.band + 1,
                                  m.speeds_mps[static_cast<std::size_t>(j.cell) / nf],
                                  m.forces_N[static_cast<std::size_t>(j.cell) % nf]);
        to.progress = nullptr;
        if (o.progress)  // every 5th epoch: training can take minutes per network
          to.progress = [&, name](int epoch, double val_mse) {
            if (epoch % 5 == 0)
              o.progress(fmt::format("{}: epoch {}/{}, validation MSE {:.4f}", name, epoch,
                                     o.train.max_epochs, val_mse),
                         static_cast<int>(done.load()), static_cast<int>(jobs.size()));
          };
        // Zero output layer: the network starts as exactly the linear part (its output is 0),
        // so training can only move away from the linear predictor where the data ask for it.
        if (nlin > 0) net.params().tail(layers[layers.size() - 2] + 1).setZero();
        net.Train(X, y_mlp, to);
        renderer::NeuralNet out{
            layers,
            std::vector<double>(net.params().data(), net.params().data() + net.params().size()),
            std::vector<double>(wlin.data(), wlin.data() + wlin.size())};
        // Sigma per cell for the network with (mlp) or without its nonlinear part: the one-step
        // residual RMS on every row of the cell's recording (with a linear part on the clean
        // histories the synthesis feeds it), then calibrated: a trained predictor shrinks
        // toward zero, so free-running synthesis driven by the one-step residual would have
        // too little power. Sigma is scaled until the free-running signal has the recording's
        // RMS inside the band (what the crossovers pass; three fixed-point passes).
        auto sigmas = [&](bool mlp, const LinearFit& lin) {
          std::vector<double> sigma(cells, 0.0);
          const Eigen::VectorXd p = !mlp       ? lin.ylin
                                    : nlin > 0 ? Eigen::VectorXd(net.PredictRows(Xclean) + lin.ylin)
                                               : net.PredictRows(X);
          std::vector<double> se(cells, 0.0), cnt(cells, 0.0);
          Eigen::Index row = 0;
          for (const bool val : {false, true})
            for (const auto i : use) {
              const auto [a, b] = rows_of(j, i, val);
              for (std::size_t t = a; t < b; ++t, ++row) {
                const auto c = static_cast<std::size_t>(cell_of[i]);
                se[c] += (p(row) - y(row)) * (p(row) - y(row));
                cnt[c] += 1;
              }
            }
          for (std::size_t c = 0; c < cells; ++c)
            if (cnt[c] > 0) sigma[c] = std::sqrt(se[c] / cnt[c]);
          auto predict = [&](const Eigen::VectorXd& in, std::size_t c) {
            double v = mlp ? net.Predict(in) : 0.0;
            if (nlin > 0) v += in.head(M).dot(lin.a_cell[c]);
            return v;
          };
          const double rate_dec = m.sample_rate_hz / band.decimation;
          auto in_band_rms = [&](const std::vector<double>& x) {
            const auto bx = BandSplit(x, rate_dec, band.lo_hz, band.hi_hz);
            double q = 0;
            for (const double v : bx) q += v * v;
            return std::sqrt(q / static_cast<double>(std::max<std::size_t>(1, bx.size())));
          };
          for (const auto i : use) {
            const auto c = static_cast<std::size_t>(cell_of[i]);
            const double target = in_band_rms(sig[j.band][i]);
            Rng rng(o.train.seed + 7919 * k + c);
            Eigen::VectorXd in = Eigen::VectorXd::Zero(inputs);
            if (unified) {
              in(M) = m.NormSpeed(recs[i].speed_mps);
              in(M + 1) = m.NormForce(recs[i].force_N);
            }
            std::vector<double> run;
            for (int pass = 0; pass < 3 && target > 0; ++pass) {
              in.head(M).setZero();
              run.clear();
              const int warm = 300, steps = 3000;
              for (int t = 0; t < warm + steps; ++t) {
                double yv = predict(in, c) + sigma[c] * rng.Normal();
                yv = std::clamp(std::isfinite(yv) ? yv : 0.0, -10.0, 10.0);
                for (int q = M - 1; q > 0; --q) in(q) = in(q - 1);
                in(0) = yv;
                if (t >= warm) run.push_back(yv);
              }
              const double got = in_band_rms(run);
              if (!(got > 0)) break;
              sigma[c] *= std::clamp(target / got, 0.25, 4.0);
            }
          }
          return sigma;
        };
        const auto with_mlp = sigmas(true, lin_train);
        for (const auto i : use)
          band.sigma[static_cast<std::size_t>(cell_of[i])] =
              with_mlp[static_cast<std::size_t>(cell_of[i])];
        // The linear part alone (the network's output 0) as selected on validation data
        // (fitted on the training rows), and as returned when selected (refit_linear_part:
        // the same least squares on every row, sigma recalibrated for it).
        auto set_linear_alone = [&](std::vector<renderer::NeuralBand>& to_bands,
                                    const LinearFit& lin) {
          const auto without = sigmas(false, lin);
          for (const auto i : use)
            to_bands[j.band].sigma[static_cast<std::size_t>(cell_of[i])] =
                without[static_cast<std::size_t>(cell_of[i])];
          renderer::NeuralNet net0{layers, std::vector<double>(out.params.size(), 0.0),
                                   std::vector<double>(lin.w.data(), lin.w.data() + lin.w.size())};
          to_bands[j.band].nets[unified ? 0 : static_cast<std::size_t>(j.cell)] = std::move(net0);
          to_bands[j.band].cell_ar = lin.cell_ar;
        };
        if (nlin > 0) set_linear_alone(linear_only, lin_train);
        if (nlin > 0 && refit) {
          // The refit must stay a stable filter wherever the model plays, as the training-rows
          // fit is (above; Γ_D's at its cell, where its linear weights are one AR(M)): a refit
          // that is not keeps the training-rows fit (per-cell Levinson fits always are).
          bool stable = true;
          std::string where;
          if (!per_cell) {
            const auto hull = ConditionBasisMaxRadius(
                Eigen::Map<const Eigen::MatrixXd>(lin_all.w.data(), M, terms), unified ? 41 : 1);
            stable = hull.radius < 1;
            if (!stable) where = fmt::format(" (pole radius {:.3f})", hull.radius);
          }
          set_linear_alone(linear_refit, stable ? lin_all : lin_train);
          if (o.progress && !stable)
            o.progress(fmt::format("{}: the linear part refitted on every row is not a stable "
                                   "filter{}; if the linear parts alone are kept, this one keeps "
                                   "its training-rows fit",
                                   name, where),
                       static_cast<int>(done.load()), static_cast<int>(jobs.size()));
        }
        band.nets[unified ? 0 : static_cast<std::size_t>(j.cell)] = std::move(out);
        band.cell_ar = lin_train.cell_ar;
        if (o.progress)
          o.progress(name + ": trained", static_cast<int>(++done), static_cast<int>(jobs.size()));
      } catch (...) {
        std::lock_guard<std::mutex> lock(err_mu);
        if (!error) error = std::current_exception();
      }
    }
  };
  const int threads = o.threads > 0 ? o.threads : std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  renderer::FillNeuralCellLsf(&m);  // once here, not in every synthesizer
  for (std::size_t b = 0; b < m.bands.size(); ++b) linear_only[b].cell_lsf = m.bands[b].cell_lsf;
  if (o.linear_part && o.validate_nonlinear_part) {
    // Model selection on validation data: free-running E_s (the Fig. 3.7 measure) of each
    // variant against the last validation_fraction of every recording, which no linear part
    // was fitted on; both variants driven by the same noise (seed per recording).
    auto validation_es = [&](const std::vector<renderer::NeuralBand>& bands) {
      return ValidationEs(m, bands, recs, pre, o.train.validation_fraction, o.train.seed);
    };
    const double es_mlp = validation_es(m.bands), es_lin = validation_es(linear_only);
    const bool keep = !(es_lin <= es_mlp);
    if (!keep) {
      m.bands = std::move(refit ? linear_refit : linear_only);
      if (refit) renderer::FillNeuralCellLsf(&m);  // the refitted cell_ar's LSFs
    }
    if (o.progress)
      o.progress(fmt::format("validation E_s: {:.4f} with the nonlinear part, {:.4f} with the "
                             "linear part alone: {} kept{}",
                             es_mlp, es_lin, keep ? "nonlinear part" : "linear part alone",
                             !keep && refit ? ", refitted on every row" : ""),
                 static_cast<int>(jobs.size()), static_cast<int>(jobs.size()));
  }
  RequireStableLinearParts(m, [&](const std::string& what) {
    if (o.progress) o.progress(what, static_cast<int>(jobs.size()), static_cast<int>(jobs.size()));
  });
  renderer::ValidateNeuralModel(m);
  return m;
}

}  // namespace hapticlab::modeling
