#include "hapticlab/modeling/mlp.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/core/status.hpp"

namespace hapticlab::modeling {

Mlp::Mlp(std::vector<int> layers, std::uint64_t seed) : layers_(std::move(layers)) {
  HL_REQUIRE(layers_.size() >= 2 && layers_.back() == 1, "MLP needs >= 2 layers and one output");
  Eigen::Index n = 0;
  for (std::size_t l = 0; l + 1 < layers_.size(); ++l) {
    offset_.push_back(n);
    n += static_cast<Eigen::Index>(layers_[l + 1]) * (layers_[l] + 1);
  }
  params_.resize(n);
  // Glorot-uniform weights, zero biases.
  Rng rng(seed);
  for (std::size_t l = 0; l + 1 < layers_.size(); ++l) {
    const int in = layers_[l], out = layers_[l + 1];
    const double a = std::sqrt(6.0 / (in + out));
    for (Eigen::Index k = 0; k < static_cast<Eigen::Index>(out) * in; ++k)
      params_(offset_[l] + k) = rng.Uniform(-a, a);
    for (int k = 0; k < out; ++k) params_(offset_[l] + static_cast<Eigen::Index>(out) * in + k) = 0;
  }
}

double Mlp::Predict(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  Eigen::VectorXd a = x;
  for (std::size_t l = 0; l + 1 < layers_.size(); ++l) {
    const int in = layers_[l], out = layers_[l + 1];
    const Eigen::Map<const Eigen::MatrixXd> W(params_.data() + offset_[l], out, in);
    const Eigen::Map<const Eigen::VectorXd> b(
        params_.data() + offset_[l] + static_cast<Eigen::Index>(out) * in, out);
    Eigen::VectorXd z = W * a + b;
    a = l + 2 < layers_.size() ? Eigen::VectorXd(z.array().tanh()) : z;
  }
  return a(0);
}

double Mlp::Gradient(const Eigen::Ref<const Eigen::VectorXd>& x, double target,
                     Eigen::VectorXd* grad) const {
  const std::size_t L = layers_.size() - 1;
  std::vector<Eigen::VectorXd> act(L + 1);
  act[0] = x;
  for (std::size_t l = 0; l < L; ++l) {
    const int in = layers_[l], out = layers_[l + 1];
    const Eigen::Map<const Eigen::MatrixXd> W(params_.data() + offset_[l], out, in);
    const Eigen::Map<const Eigen::VectorXd> b(
        params_.data() + offset_[l] + static_cast<Eigen::Index>(out) * in, out);
    Eigen::VectorXd z = W * act[l] + b;
    act[l + 1] = l + 1 < L ? Eigen::VectorXd(z.array().tanh()) : z;
  }
  const double err = act[L](0) - target;
  grad->setZero(params_.size());
  Eigen::VectorXd delta = Eigen::VectorXd::Constant(1, err);  // dLoss/dz of the output layer
  for (std::size_t l = L; l-- > 0;) {
    const int in = layers_[l], out = layers_[l + 1];
    Eigen::Map<Eigen::MatrixXd> gw(grad->data() + offset_[l], out, in);
    Eigen::Map<Eigen::VectorXd> gb(grad->data() + offset_[l] + static_cast<Eigen::Index>(out) * in,
                                   out);
    gw = delta * act[l].transpose();
    gb = delta;
    if (l > 0) {
      const Eigen::Map<const Eigen::MatrixXd> W(params_.data() + offset_[l], out, in);
      delta = (W.transpose() * delta).array() * (1 - act[l].array().square());
    }
  }
  return 0.5 * err * err;
}

double Mlp::BatchGradient(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                          const std::vector<Eigen::Index>& rows, Eigen::VectorXd* grad) const {
  const std::size_t L = layers_.size() - 1;
  const auto B = static_cast<Eigen::Index>(rows.size());
  std::vector<Eigen::MatrixXd> act(L + 1);
  act[0].resize(layers_[0], B);
  Eigen::VectorXd target(B);
  for (Eigen::Index k = 0; k < B; ++k) {
    act[0].col(k) = X.row(rows[static_cast<std::size_t>(k)]).transpose();
    target(k) = y(rows[static_cast<std::size_t>(k)]);
  }
  for (std::size_t l = 0; l < L; ++l) {
    const int in = layers_[l], out = layers_[l + 1];
    const Eigen::Map<const Eigen::MatrixXd> W(params_.data() + offset_[l], out, in);
    const Eigen::Map<const Eigen::VectorXd> b(
        params_.data() + offset_[l] + static_cast<Eigen::Index>(out) * in, out);
    act[l + 1].noalias() = W * act[l];
    act[l + 1].colwise() += b;
    if (l + 1 < L) act[l + 1] = act[l + 1].array().tanh().matrix();
  }
  const Eigen::RowVectorXd err = act[L].row(0) - target.transpose();
  const double loss = 0.5 * err.squaredNorm() / static_cast<double>(B);
  grad->setZero(params_.size());
  Eigen::MatrixXd delta = err / static_cast<double>(B);  // 1 x B: dLoss/dz of the output
  for (std::size_t l = L; l-- > 0;) {
    const int in = layers_[l], out = layers_[l + 1];
    Eigen::Map<Eigen::MatrixXd> gw(grad->data() + offset_[l], out, in);
    Eigen::Map<Eigen::VectorXd> gb(grad->data() + offset_[l] + static_cast<Eigen::Index>(out) * in,
                                   out);
    gw.noalias() = delta * act[l].transpose();
    gb = delta.rowwise().sum();
    if (l > 0) {
      const Eigen::Map<const Eigen::MatrixXd> W(params_.data() + offset_[l], out, in);
      Eigen::MatrixXd back = W.transpose() * delta;
      delta = back.array() * (1 - act[l].array().square());
    }
  }
  return loss;
}

Eigen::VectorXd Mlp::PredictRows(const Eigen::MatrixXd& X) const {
  Eigen::MatrixXd a = X.transpose();
  const std::size_t L = layers_.size() - 1;
  for (std::size_t l = 0; l < L; ++l) {
    const int in = layers_[l], out = layers_[l + 1];
    const Eigen::Map<const Eigen::MatrixXd> W(params_.data() + offset_[l], out, in);
    const Eigen::Map<const Eigen::VectorXd> b(
        params_.data() + offset_[l] + static_cast<Eigen::Index>(out) * in, out);
    Eigen::MatrixXd z = W * a;
    z.colwise() += b;
    a = l + 1 < L ? Eigen::MatrixXd(z.array().tanh()) : z;
  }
  return a.row(0).transpose();
}

MlpTrainSummary Mlp::Train(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                           const MlpTrainOptions& o) {
  const Eigen::Index n = X.rows();
  const auto nval =
      static_cast<Eigen::Index>(std::floor(o.validation_fraction * static_cast<double>(n)));
  const Eigen::Index ntr = n - nval;
  if (ntr < o.batch) throw InputError("", 0, "samples", "too few samples for one mini-batch");
  auto mse = [&](Eigen::Index from, Eigen::Index to) {
    if (to <= from) return 0.0;
    const Eigen::VectorXd p = PredictRows(X.middleRows(from, to - from));
    return (p - y.segment(from, to - from)).squaredNorm() / static_cast<double>(to - from);
  };
  Rng rng(o.seed);
  Eigen::VectorXd m = Eigen::VectorXd::Zero(params_.size()), v = m, g(params_.size());
  std::vector<Eigen::Index> batch_rows;
  std::vector<Eigen::Index> order(static_cast<std::size_t>(ntr));
  std::iota(order.begin(), order.end(), 0);
  MlpTrainSummary s;
  double best = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_params = params_;
  int since = 0;
  long step = 0;
  for (int epoch = 1; epoch <= o.max_epochs; ++epoch) {
    rng.Shuffle(order);
    for (Eigen::Index start = 0; start + o.batch <= ntr; start += o.batch) {
      batch_rows.assign(order.begin() + start, order.begin() + start + o.batch);
      BatchGradient(X, y, batch_rows, &g);
      ++step;
      m = o.beta1 * m + (1 - o.beta1) * g;
      v = o.beta2 * v + (1 - o.beta2) * g.cwiseProduct(g);
      const double c1 = 1 - std::pow(o.beta1, static_cast<double>(step)),
                   c2 = 1 - std::pow(o.beta2, static_cast<double>(step));
      params_.array() -= o.learning_rate * (m.array() / c1) / ((v.array() / c2).sqrt() + o.epsilon);
    }
    s.epochs = epoch;
    const double val = nval > 0 ? mse(ntr, n) : mse(0, ntr);
    if (o.progress) o.progress(epoch, val);
    if (val < best) {
      best = val;
      best_params = params_;
      since = 0;
    } else if (++since >= o.patience) {
      s.early_stopped = true;
      break;
    }
  }
  params_ = best_params;
  s.train_mse = mse(0, ntr);
  s.validation_mse = nval > 0 ? mse(ntr, n) : s.train_mse;
  return s;
}

}  // namespace hapticlab::modeling
