#pragma once
// Internal to FitNeural (neural.cpp, neural_linear.cpp): what the networks of one fit share,
// a network's regression rows, and its linear part.

#include <Eigen/Core>
#include <atomic>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "hapticlab/modeling/neural.hpp"

namespace hapticlab::modeling::neural_fit {

// One network to train: (band, cell) for Γ_D, (band) for Γ_U.
struct Job {
  std::size_t band;
  int cell;  // -1: unified
};

// What every network of one fit shares.
struct FitShared {
  const std::vector<Recording>& recs;
  const NeuralFitOptions& o;
  renderer::NeuralModel& m;
  bool unified = true;
  std::size_t nf = 0, cells = 0;
  std::vector<int> cell_of;  // grid cell of each recording
  // Per band, per recording: the signal its networks learn (decimated, in units of the band's
  // RMS).
  std::vector<std::vector<std::vector<double>>> sig;
  std::vector<Job> jobs;
  // The same networks without their nonlinear part (output 0: the linear part alone), with
  // their own calibrated sigma; kept when it synthesizes the validation data better.
  std::vector<renderer::NeuralBand> linear_only;
  // The linear parts refitted on every row of every recording, returned in place of
  // linear_only when validation keeps the linear parts alone (NeuralFitOptions::refit_linear_part).
  bool refit = false;
  std::vector<renderer::NeuralBand> linear_refit;
  std::atomic<std::size_t> done{0};

  void Progress(const std::string& what) const {
    if (o.progress) o.progress(what, static_cast<int>(done.load()), static_cast<int>(jobs.size()));
  }
  // Pairs of recording i for job j: training rows are the first 80 %, validation the last 20 %.
  std::pair<std::size_t, std::size_t> RowsOf(const Job& j, std::size_t i, bool validation) const {
    const auto& x = sig[j.band][i];
    const int M = m.bands[j.band].history;
    const std::size_t first = static_cast<std::size_t>(M),
                      n = x.size() > first ? x.size() - first : 0;
    const std::size_t cut =
        first + n -
        static_cast<std::size_t>(std::floor(o.train.validation_fraction * static_cast<double>(n)));
    return validation ? std::make_pair(cut, x.size()) : std::make_pair(first, cut);
  }
};

// A job's regression rows: every used recording's training part, then every validation part.
struct JobRows {
  std::vector<std::size_t> use;  // the recordings the network learns from
  int M = 0, inputs = 0;
  Eigen::Index total = 0, nval = 0;
  Eigen::MatrixXd X;  // histories (and Γ_U's scaled condition)
  Eigen::VectorXd y;
  std::vector<std::size_t> row_cell;  // grid cell per row
};

// How a job's linear part is formed.
struct LinearForm {
  bool per_cell = false;   // per-cell AR fits mixed in LSF form (Γ_U's stability fallback)
  Eigen::Index terms = 1;  // condition-basis terms (Γ_U 9, Γ_D 1)
  Eigen::Index nlin = 0;   // the network's linear weights (0: no linear part)
  Eigen::Index p_lin = 0;  // per_cell: the cells' AR order
};

// The linear part fitted on the training rows (all_rows false: the first 80 % of every
// recording, what the networks are trained beside and the model selection compares) or on
// every row (the refit of the linear part alone once validation has chosen it).
struct LinearFit {
  Eigen::VectorXd w;                         // the network's linear weights (terms x M)
  std::vector<Eigen::VectorXd> a_cell;       // the AR(M) at each training cell
  std::vector<std::vector<double>> cell_ar;  // per_cell: the band's NeuralBand::cell_ar
  Eigen::VectorXd ylin;                      // its one-step prediction of every row
};

/// The linear part on the job's rows (all_rows: every row, else the training rows) in `form`.
LinearFit FitLinear(const FitShared& s, const Job& j, const JobRows& rows, const LinearForm& form,
                    bool all_rows);
/// The linear part on the training rows, stable wherever the model plays: Γ_U's condition
/// basis is checked over a fine grid of the hull; where its largest pole radius is not below
/// NeuralFitOptions::max_condition_basis_radius (at most 1), the band is fitted per cell and
/// mixed in LSF form instead (stable by construction). Sets `form`.
LinearFit FitStableLinear(const FitShared& s, const Job& j, const JobRows& rows, LinearForm* form);

}  // namespace hapticlab::modeling::neural_fit
