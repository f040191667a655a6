#include "hapticlab/modeling/mlp.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/modeling/vibration.hpp"

namespace hapticlab::modeling::mlp_test {
namespace {

TEST(Mlp, BackpropagationMatchesFiniteDifferences) {
  Mlp net({5, 7, 4, 3, 1}, 3);
  Rng rng(1);
  for (Eigen::Index i = 0; i < net.params().size(); ++i) net.params()(i) += 0.1 * rng.Normal();
  Eigen::VectorXd x(5);
  for (int i = 0; i < 5; ++i) x(i) = rng.Normal();
  Eigen::VectorXd g;
  net.Gradient(x, 0.7, &g);
  const double h = 1e-6;
  double worst = 0;
  for (Eigen::Index i = 0; i < net.params().size(); ++i) {
    const double p0 = net.params()(i);
    net.params()(i) = p0 + h;
    const double up = 0.5 * std::pow(net.Predict(x) - 0.7, 2);
    net.params()(i) = p0 - h;
    const double dn = 0.5 * std::pow(net.Predict(x) - 0.7, 2);
    net.params()(i) = p0;
    worst = std::max(worst, std::abs((up - dn) / (2 * h) - g(i)) / std::max(1e-6, std::abs(g(i))));
  }
  EXPECT_LT(worst, 1e-5);
}

TEST(Mlp, LearnsANonlinearArProcessBetterThanALinearFit) {
  // x[k] = 0.5 x[k-1] - 0.4 x[k-2] + 0.8 tanh(3 x[k-1]) x[k-2] + e, e ~ N(0, 0.3^2).
  Rng rng(7);
  std::vector<double> x(30000, 0.0);
  for (std::size_t k = 2; k < x.size(); ++k)
    x[k] = 0.5 * x[k - 1] - 0.4 * x[k - 2] + 0.8 * std::tanh(3 * x[k - 1]) * x[k - 2] +
           0.3 * rng.Normal();
  const int M = 4;
  const Eigen::Index n = static_cast<Eigen::Index>(x.size()) - M;
  Eigen::MatrixXd X(n, M);
  Eigen::VectorXd y(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int j = 0; j < M; ++j) X(i, j) = x[static_cast<std::size_t>(i + M - 1 - j)];
    y(i) = x[static_cast<std::size_t>(i + M)];
  }
  // Train on the first 20000 samples (with its own validation split); test on the rest.
  const Eigen::Index ntr = 20000;
  Mlp net({M, 16, 8, 1}, 11);
  const auto s = net.Train(X.topRows(ntr), y.head(ntr),
                           {.max_epochs = 60, .batch = 32, .learning_rate = 3e-3, .seed = 5});
  // Linear AR(M) fit by Levinson-Durbin on the same training samples.
  const std::vector<double> train(x.begin(), x.begin() + ntr + M);
  const auto ar = FitAr(train, M);
  double mlp_mse = 0, lin_mse = 0;
  for (Eigen::Index i = ntr; i < n; ++i) {
    double lin = 0;
    for (int j = 0; j < M; ++j) lin += ar.coeffs[static_cast<std::size_t>(j)] * X(i, j);
    mlp_mse += std::pow(net.Predict(X.row(i).transpose()) - y(i), 2);
    lin_mse += std::pow(lin - y(i), 2);
  }
  mlp_mse /= static_cast<double>(n - ntr);
  lin_mse /= static_cast<double>(n - ntr);
  std::printf("held-out one-step MSE: MLP %.4f, linear AR(%d) %.4f, noise floor %.4f (%d epochs)\n",
              mlp_mse, M, lin_mse, 0.09, s.epochs);
  EXPECT_LT(mlp_mse, 0.9 * lin_mse);
  EXPECT_LT(mlp_mse, 0.09 * 1.15);  // close to the innovation variance
}

}  // namespace
}  // namespace hapticlab::modeling::mlp_test

namespace hapticlab::modeling::mlp_test {
namespace {

TEST(Mlp, BatchGradientIsTheMeanOfSampleGradients) {
  Mlp net({6, 9, 5, 1}, 4);
  Rng rng(3);
  for (Eigen::Index i = 0; i < net.params().size(); ++i) net.params()(i) += 0.2 * rng.Normal();
  Eigen::MatrixXd X(20, 6);
  Eigen::VectorXd y(20);
  for (Eigen::Index i = 0; i < 20; ++i) {
    for (int j = 0; j < 6; ++j) X(i, j) = rng.Normal();
    y(i) = rng.Normal();
  }
  const std::vector<Eigen::Index> rows = {3, 7, 7, 0, 19, 11};
  Eigen::VectorXd g, gi, mean = Eigen::VectorXd::Zero(net.params().size());
  double loss = 0;
  for (const auto r : rows) {
    loss += net.Gradient(X.row(r).transpose(), y(r), &gi);
    mean += gi;
  }
  mean /= static_cast<double>(rows.size());
  const double bl = net.BatchGradient(X, y, rows, &g);
  EXPECT_NEAR(bl, loss / static_cast<double>(rows.size()), 1e-12);
  EXPECT_LT((g - mean).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::VectorXd p = net.PredictRows(X);
  for (Eigen::Index i = 0; i < 20; ++i) EXPECT_NEAR(p(i), net.Predict(X.row(i).transpose()), 1e-12);
}

}  // namespace
}  // namespace hapticlab::modeling::mlp_test
