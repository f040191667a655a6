#pragma once
// The built-in device back-ends (private to runner): each is one file in this folder defining
// `RigBackend backends::<Name>()`, and one line in HL_BUILT_IN_BACKENDS below, which declares
// it here and registers it (backend_registry.cpp; registry order is this order). The folder's
// files are compiled by a glob (runner/CMakeLists.txt). docs/hardware.md, "Adding a device
// back-end".

#include "hapticlab/runner/open_rig.hpp"

// One line per back-end.
#define HL_BUILT_IN_BACKENDS(X) \
  X(Sim)                        \
  X(FalconTwin)                 \
  X(Falcon)                     \
  X(Dhd)                        \
  X(OpenHaptics)

namespace hapticlab::runner::backends {

#define HL_DECLARE_BACKEND(Name) RigBackend Name();
HL_BUILT_IN_BACKENDS(HL_DECLARE_BACKEND)
#undef HL_DECLARE_BACKEND

}  // namespace hapticlab::runner::backends
