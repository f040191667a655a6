#pragma once
/// @file The model-versus-measurement workbench (DESIGN.md §4), one header per responsibility:
///  - workbench_replay.hpp    a measurement prepared for replay (frames, units, windows)
///  - workbench_model.hpp     effects, parameters, models
///  - workbench_predict.hpp   prediction, residuals, errors
///  - workbench_fit.hpp       fitting with solver summaries
///  - workbench_bootstrap.hpp the friction fit's bias and error through the preprocessing
///  - workbench_compare.hpp   `compare`: errors by regime
///  - workbench_diagnose.hpp  `diagnose`: missing effects, unexplained residual
///  - workbench_io.hpp        model files
///  - workbench_sim.hpp       ground-truth simulator
/// See docs/workbench.md and effects/*.cpp.

#include "hapticlab/modeling/workbench_bootstrap.hpp"
#include "hapticlab/modeling/workbench_compare.hpp"
#include "hapticlab/modeling/workbench_diagnose.hpp"
#include "hapticlab/modeling/workbench_fit.hpp"
#include "hapticlab/modeling/workbench_io.hpp"
#include "hapticlab/modeling/workbench_model.hpp"
#include "hapticlab/modeling/workbench_predict.hpp"
#include "hapticlab/modeling/workbench_replay.hpp"
#include "hapticlab/modeling/workbench_sim.hpp"
#include "hapticlab/modeling/workbench_vibration.hpp"
