#include "hapticlab/devices/device.hpp"

namespace hapticlab::devices {

const char* ReadResultName(ReadResult r) {
  switch (r) {
    case ReadResult::kOk:
      return "ok";
    case ReadResult::kNoNewData:
      return "no-new-data";
    case ReadResult::kLost:
      return "lost";
  }
  return "?";
}

}  // namespace hapticlab::devices
