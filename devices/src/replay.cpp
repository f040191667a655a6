#include "hapticlab/devices/replay.hpp"

#include "hapticlab/core/status.hpp"

namespace hapticlab::devices {

ReplayDevice::ReplayDevice(std::vector<TrajectorySample> samples, std::function<double()> clock,
                           DeviceCapabilities caps)
    : samples_(std::move(samples)), clock_(std::move(clock)), caps_(std::move(caps)) {
  HL_REQUIRE(!samples_.empty(), "replay needs at least one sample");
  for (std::size_t i = 1; i < samples_.size(); ++i)
    HL_REQUIRE(samples_[i].t_s >= samples_[i - 1].t_s, "replay samples must be in time order");
  caps_.name = caps_.name.empty() ? "replay" : caps_.name;
  // Room for a 4 kHz loop over the whole trajectory, plus margin.
  const double span = samples_.back().t_s - samples_.front().t_s;
  forces_.reserve(static_cast<std::size_t>(span * 4000 * 1.5) + 1024);
}

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

ReadResult ReplayDevice::Read(DeviceSample* out) noexcept {
  const double now = clock_() + samples_.front().t_s;
  if (now > samples_.back().t_s) {
    finished_.store(true);
    return ReadResult::kLost;
  }
  while (next_ + 1 < samples_.size() && samples_[next_ + 1].t_s <= now) ++next_;
  out->state.p_m = samples_[next_].p_m;
  out->state.v_mps = samples_[next_].v_mps;
  out->t_s = now - samples_.front().t_s;
  return ReadResult::kOk;
}

void ReplayDevice::WriteForce(const Eigen::Vector3d& force_N) noexcept {
  if (forces_.size() < forces_.capacity()) forces_.push_back(force_N);
}

}  // namespace hapticlab::devices
