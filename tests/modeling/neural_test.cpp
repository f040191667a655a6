// The neural texture model's fit (dissertation ch. III.3, issue #10; modeling/src/neural.cpp):
// the thesis's structure, progress, the validated nonlinear part, and free-running synthesis of a
// known nonlinear process. Synthesis and the model file: tests/renderer/neural*_test.cpp;
// the Fig. 3.7 tables: neural_cv_test.cpp.

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "neural_fixture.hpp"

namespace hapticlab::modeling::neural_test {
namespace {

TEST(Neural, ModelHasTheThesisStructure) {
  const auto o = NeuralFitOptions{};
  ASSERT_EQ(o.bands.size(), 4u);
  const double lo[] = {20, 100, 200, 500}, hi[] = {100, 200, 500, 1000};
  const int g[] = {8, 4, 1, 1};
  for (std::size_t b = 0; b < 4; ++b) {
    EXPECT_EQ(o.bands[b].lo_hz, lo[b]);
    EXPECT_EQ(o.bands[b].hi_hz, hi[b]);
    EXPECT_EQ(o.bands[b].decimation, g[b]);
    EXPECT_EQ(o.bands[b].history, 50);
    EXPECT_LE(hi[b], 2000.0 / (2 * g[b]))
        << "band " << b << " must not alias at its decimated rate";
    // The interpolator (flat to 0.4 of its input rate) must pass a decimated band whole.
    if (g[b] > 1) {
      EXPECT_LE(hi[b], 0.4 * 2000.0 / g[b]) << "band " << b;
    }
  }
  EXPECT_EQ(o.hidden_large, (std::vector<int>{30, 25, 15, 5}));
  EXPECT_EQ(o.hidden_small, (std::vector<int>{30, 15, 5}));
  const auto& u = SmallModel(renderer::NeuralTopology::kUnified);
  const auto& d = SmallModel(renderer::NeuralTopology::kDecomposed);
  for (const auto& b : u.bands) {
    EXPECT_EQ(b.nets.size(), 1u);
    EXPECT_EQ(b.nets[0].layers.front(), b.history + 2)
        << "speed and force are two extra inputs of Γ_U";
  }
  for (const auto& b : d.bands) {
    EXPECT_EQ(b.nets.size(), 4u) << "one network per cell of the 2 x 2 grid";
    EXPECT_EQ(b.nets[0].layers.front(), b.history);
  }
  EXPECT_EQ(d.bands[0].nets[0].layers.size(), 4u);  // 12 -> 8 -> 4 -> 1 (band 1: the large shape)
  EXPECT_EQ(d.bands[1].nets[0].layers.size(), 3u);  // 12 -> 6 -> 1
}

TEST(Neural, TrainingReportsProgressPerEpochAndPerNetwork) {
  const auto recs = CornerGrid(70);
  NeuralFitOptions o = Quick(renderer::NeuralTopology::kUnified);
  o.train.max_epochs = 5;
  o.train.patience = 10;  // all five epochs run
  o.hidden_large = {6};
  for (auto& b : o.bands) b.history = 8;
  std::mutex mu;
  std::vector<std::string> lines;
  o.progress = [&](const std::string& what, int done, int total) {
    std::lock_guard<std::mutex> lock(mu);
    lines.push_back(fmt::format("{}/{} {}", done, total, what));
  };
  FitNeural(recs, o);
  int epochs = 0, trained = 0;
  for (const auto& l : lines) {
    epochs += l.find("epoch 5/5, validation MSE") != std::string::npos;
    trained += l.find(": trained") != std::string::npos;
  }
  EXPECT_EQ(epochs, 4) << "one report at epoch 5 of each band's network";
  EXPECT_EQ(trained, 4);
  // The last network to finish reports 4 of 4 (which band that is depends on the threads).
  EXPECT_TRUE(std::any_of(lines.begin(), lines.end(), [](const std::string& l) {
    return l.rfind("4/4 band ", 0) == 0 && l.find(": trained") != std::string::npos;
  })) << fmt::format("{}", fmt::join(lines, "\n"));
}

// The nonlinear part is kept only when the free-running model synthesizes the recordings'
// validation parts better with it (NeuralFitOptions::validate_nonlinear_part): the decision
// is reported, and the returned networks are the reported variant (linear part alone: every
// MLP parameter zero, so the network's output is exactly its linear part).
TEST(Neural, TheNonlinearPartIsKeptOnlyWhenValidationFavoursIt) {
  const auto recs = CornerGrid(90);
  NeuralFitOptions o = Quick(renderer::NeuralTopology::kUnified);
  o.train.max_epochs = 3;
  o.hidden_large = {6};
  for (auto& b : o.bands) b.history = 8;
  std::string decision;
  o.progress = [&](const std::string& what, int, int) {
    if (what.rfind("validation E_s: ", 0) == 0) decision = what;
  };
  auto mlp_is_zero = [](const renderer::NeuralModel& m) {
    for (const auto& b : m.bands)
      for (const auto& n : b.nets) {
        EXPECT_EQ(n.linear.size(), 9u * static_cast<std::size_t>(b.history));
        if (std::any_of(n.params.begin(), n.params.end(), [](double p) { return p != 0; }))
          return false;
      }
    return true;
  };
  const auto chosen = FitNeural(recs, o);
  ASSERT_FALSE(decision.empty()) << "the selection is reported";
  double es_mlp = 0, es_lin = 0;
  ASSERT_EQ(std::sscanf(decision.c_str(), "validation E_s: %lf with the nonlinear part, %lf",
                        &es_mlp, &es_lin),
            2)
      << decision;
  const bool linear_kept = decision.find("linear part alone kept") != std::string::npos;
  EXPECT_EQ(linear_kept, es_lin <= es_mlp) << decision;
  EXPECT_EQ(mlp_is_zero(chosen), linear_kept) << decision;
  o.validate_nonlinear_part = false;
  decision.clear();
  const auto all = FitNeural(recs, o);
  EXPECT_TRUE(decision.empty());
  EXPECT_FALSE(mlp_is_zero(all)) << "trained networks are kept as trained";
  // The linear parts are the training rows' fit either way unless the linear part alone is
  // kept and refitted on every row (the next test).
  o.validate_nonlinear_part = true;
  o.refit_linear_part = false;
  const auto unrefitted = FitNeural(recs, o);
  for (std::size_t b = 0; b < all.bands.size(); ++b) {
    EXPECT_EQ(all.bands[b].nets[0].linear, unrefitted.bands[b].nets[0].linear);
    if (!linear_kept) {
      EXPECT_EQ(all.bands[b].nets[0].linear, chosen.bands[b].nets[0].linear);
    }
  }
}

// When validation keeps the linear part alone, it is refitted on every row of every recording
// (NeuralFitOptions::refit_linear_part), as the LPC bank fits whole recordings. Reference: on a
// 2 x 2 grid the biquadratic basis takes any value at the four nodes, so the AR at each node is
// that recording's own least-squares AR(M) (covariance method, written here with Eigen) on the
// band's signal: for band 4 (γ = 1, low-passed to 1000 Hz: the preprocessed recording less its
// Nyquist-frequency bin).
TEST(Neural, TheLinearPartKeptAloneIsRefittedOnEveryRow) {
  const auto recs = CornerGrid(90);
  NeuralFitOptions o = Quick(renderer::NeuralTopology::kUnified);
  o.train.max_epochs = 3;
  o.hidden_large = {6};
  const int M = 8;
  for (auto& b : o.bands) b.history = M;
  std::string decision;
  o.progress = [&](const std::string& what, int, int) {
    if (what.rfind("validation E_s: ", 0) == 0) decision = what;
  };
  const auto m = FitNeural(recs, o);
  ASSERT_NE(decision.find("linear part alone kept"), std::string::npos)
      << "this data set must exercise the refit: " << decision;
  const auto& band = m.bands[3];
  ASSERT_EQ(band.decimation, 1);
  ASSERT_EQ(band.nets[0].linear.size(), 9u * M);
  const Eigen::Map<const Eigen::MatrixXd> W(band.nets[0].linear.data(), M, 9);
  for (const auto& r : recs) {
    std::vector<double> x = Preprocess(r, o.preprocess);
    if (x.size() % 2 == 0) {  // remove the Nyquist-frequency bin (the ideal low-pass)
      double c = 0;
      for (std::size_t t = 0; t < x.size(); ++t) c += (t % 2 == 0 ? 1.0 : -1.0) * x[t];
      c /= static_cast<double>(x.size());
      for (std::size_t t = 0; t < x.size(); ++t) x[t] -= (t % 2 == 0 ? 1.0 : -1.0) * c;
    }
    // Least squares of x[t] on x[t-1..t-M]: on every row, and on the first 80 % (the training
    // rows, what the fit used before the refit).
    auto ls = [&](std::size_t rows) {
      Eigen::MatrixXd X(static_cast<Eigen::Index>(rows), M);
      Eigen::VectorXd y(static_cast<Eigen::Index>(rows));
      for (std::size_t i = 0; i < rows; ++i) {
        const std::size_t t = M + i;
        for (int q = 0; q < M; ++q)
          X(static_cast<Eigen::Index>(i), q) = x[t - 1 - static_cast<std::size_t>(q)];
        y(static_cast<Eigen::Index>(i)) = x[t];
      }
      return Eigen::VectorXd(X.colPivHouseholderQr().solve(y));
    };
    const std::size_t n = x.size() - M;
    const Eigen::VectorXd a_all = ls(n), a_train = ls(n - n / 5);
    const double v = m.NormSpeed(r.speed_mps), f = m.NormForce(r.force_N);
    Eigen::VectorXd phi(9);
    phi << 1, v, f, v * v, v * f, f * f, v * v * f, v * f * f, v * v * f * f;
    const Eigen::VectorXd a = W * phi;
    // The ridge (1e-6 of the mean diagonal) moves the solution by far less than the 20 % of
    // rows that the refit adds.
    EXPECT_LT((a - a_all).norm(), 1e-3 * a_all.norm()) << r.file;
    EXPECT_GT((a_train - a_all).norm(), 1e-2 * a_all.norm()) << r.file;
  }
}

// Free-running synthesis of a known nonlinear AR process: the noise-driven MLP reproduces
// its spectrum on held-out data better than a linear AR fit of the same order.
TEST(Neural, FreeRunningMlpMatchesANonlinearProcessBetterThanLinearAr) {
  // x[k] = 0.5 x[k-1] - 0.4 x[k-2] + 0.8 tanh(3 x[k-1]) x[k-2] + 0.3 e
  Rng rng(21);
  std::vector<double> x(60000, 0.0);
  for (std::size_t k = 2; k < x.size(); ++k)
    x[k] = 0.5 * x[k - 1] - 0.4 * x[k - 2] + 0.8 * std::tanh(3 * x[k - 1]) * x[k - 2] +
           0.3 * rng.Normal();
  const int M = 6;
  const std::size_t ntr = 30000;
  Eigen::MatrixXd X(static_cast<Eigen::Index>(ntr - M), M);
  Eigen::VectorXd y(static_cast<Eigen::Index>(ntr - M));
  for (std::size_t i = M; i < ntr; ++i) {
    for (int j = 0; j < M; ++j)
      X(static_cast<Eigen::Index>(i - M), j) = x[i - 1 - static_cast<std::size_t>(j)];
    y(static_cast<Eigen::Index>(i - M)) = x[i];
  }
  Mlp net({M, 16, 8, 1}, 5);
  net.Train(X, y, {.max_epochs = 40, .batch = 64, .learning_rate = 3e-3, .seed = 2});
  const double sigma =
      std::sqrt((net.PredictRows(X) - y).squaredNorm() / static_cast<double>(y.size()));
  const auto ar = FitAr(std::vector<double>(x.begin(), x.begin() + ntr), M);
  const std::vector<double> held(x.begin() + ntr, x.end());
  // Free-run both, driven by their residual noise.
  Rng n1(5), n2(6);
  std::vector<double> s_mlp(held.size() + 2000, 0.0), s_ar(held.size() + 2000, 0.0);
  Eigen::VectorXd in = Eigen::VectorXd::Zero(M);
  for (std::size_t k = static_cast<std::size_t>(M); k < s_mlp.size(); ++k) {
    for (int j = 0; j < M; ++j) in(j) = s_mlp[k - 1 - static_cast<std::size_t>(j)];
    s_mlp[k] = net.Predict(in) + sigma * n1.Normal();
    double a = 0;
    for (int j = 0; j < M; ++j)
      a += ar.coeffs[static_cast<std::size_t>(j)] * s_ar[k - 1 - static_cast<std::size_t>(j)];
    s_ar[k] = a + std::sqrt(ar.variance) * n2.Normal();
  }
  const std::vector<double> m1(s_mlp.begin() + 2000, s_mlp.end()),
      m2(s_ar.begin() + 2000, s_ar.end());
  const double es_mlp = SpectralError(held, m1, 256), es_ar = SpectralError(held, m2, 256);
  auto rms = [](const std::vector<double>& v) {
    double q = 0;
    for (const double a : v) q += a * a;
    return std::sqrt(q / static_cast<double>(v.size()));
  };
  std::printf(
      "held-out E_s: free-running MLP %.3f, linear AR(%d) %.3f (rms held %.3f mlp %.3f ar %.3f, "
      "sigma %.3f)\n",
      es_mlp, M, es_ar, rms(held), rms(m1), rms(m2), sigma);
  EXPECT_LT(es_mlp, es_ar);
}
}  // namespace
}  // namespace hapticlab::modeling::neural_test
