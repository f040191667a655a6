#pragma once
/// @file A small multilayer perceptron for the neural texture model (dissertation ch. III.3):
/// tanh hidden layers, a linear scalar output, back-propagation, and Adam [Kingma & Ba 2015,
/// arXiv:1412.6980] with mini-batches and early stopping. Written with Eigen: no C++ neural
/// network framework is packaged in Debian that earns its weight for networks this small.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

namespace hapticlab::modeling {

struct MlpTrainOptions {
  int max_epochs = 200;
  int batch = 64;
  double learning_rate = 1e-3;
  double beta1 = 0.9, beta2 = 0.999, epsilon = 1e-8;
  double validation_fraction = 0.2;  ///< the last part of the data, held out for early stopping
  int patience = 15;                 ///< epochs without validation improvement before stopping
  /// Called after every epoch (epoch, validation MSE); may be empty.
  std::function<void(int, double)> progress;
  std::uint64_t seed = 1;  ///< initialisation and shuffling
};

struct MlpTrainSummary {
  int epochs = 0;
  double train_mse = 0, validation_mse = 0;  ///< of the best (restored) parameters
  bool early_stopped = false;
};

class Mlp {
 public:
  /// @param layers sizes from input to output, e.g. {50, 30, 25, 15, 5, 1} (output size 1)
  Mlp(std::vector<int> layers, std::uint64_t seed);
  double Predict(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  /// Loss 0.5 (f(x) - target)^2 and its gradient with respect to every parameter.
  double Gradient(const Eigen::Ref<const Eigen::VectorXd>& x, double target,
                  Eigen::VectorXd* grad) const;
  /// Mean loss over the given rows of X and its gradient (matrix form: one pass per layer for
  /// the whole mini-batch). Equals the mean of Gradient over the rows.
  double BatchGradient(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                       const std::vector<Eigen::Index>& rows, Eigen::VectorXd* grad) const;
  /// Predictions for every row of X.
  Eigen::VectorXd PredictRows(const Eigen::MatrixXd& X) const;
  /// Trains on rows of X (n x inputs) against y with Adam; restores the best validation weights.
  MlpTrainSummary Train(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                        const MlpTrainOptions& o);
  Eigen::VectorXd& params() { return params_; }
  const Eigen::VectorXd& params() const { return params_; }
  const std::vector<int>& layers() const { return layers_; }

 private:
  std::vector<int> layers_;
  std::vector<Eigen::Index> offset_;  // start of W_l in params_; b_l follows W_l
  Eigen::VectorXd params_;
};

}  // namespace hapticlab::modeling
