#pragma once
/// @file The simulated rig as devices. A simulated hand holds the stylus of a simulated
/// haptic device and strokes a sample: on a real side the sample is ground-truth physics
/// (TruthSample), on a virtual side there is nothing physical under the stylus and all the
/// hand feels is the device's force and the actuator's vibration. The devices have their
/// own frame, encoder resolution, force saturation and link faults; the real-time engine
/// drives them exactly as it drives hardware, so every simulated trial runs the real tick,
/// watchdog and recording code.
///
/// Frames: the hand works in the sample's frame (x, y on the sample's base plane, +z out of
/// it); `device_from_sample` (the pose of the sample in the device frame, the rig's truth)
/// maps it to the device frame, where the device reports positions and receives forces.
///
/// Threads: SimDevice::Read/WriteForce run on the force loop, SimActuator::Write on the
/// vibration loop (one each); actuator samples reach the hand through a lock-free queue that
/// the force loop drains once per force period. On a real side the engine runs no vibration loop,
/// and the truth's contact vibration is produced by the force loop. Begin/Finish are called
/// between runs. Everything on the loops is allocation-free and noexcept.

#include <Eigen/Geometry>
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/core/spsc_queue.hpp"
#include "hapticlab/devices/clock.hpp"
#include "hapticlab/devices/device.hpp"
#include "hapticlab/devices/velocity_filter.hpp"
#include "hapticlab/sim/sim_lab.hpp"

namespace hapticlab::sim {

namespace internal {
class TruthGeometry;
}
class FalconTwinTransport;

/// Ground-truth physics of a real sample (the richer model the simulated lab's virtual
/// renderings are compared with; sim_lab.hpp describes it), in the sample frame.
class TruthSample {
 public:
  /// `vibration_rate_hz`: the rate Vibration() is called at.
  TruthSample(const MaterialProfile& p, std::uint64_t seed, double vibration_rate_hz);
  struct Contact {
    Eigen::Vector3d force_N = Eigen::Vector3d::Zero();  ///< on the stylus [N, sample frame]
    double normal_N = 0;                                ///< normal force magnitude [N]
    double penetration_m = 0;                           ///< depth below the local surface [m]
    double micro_dd = 0;   ///< acceleration the micro-geometry imposes at 1 m/s [1/m]
    double speed_mps = 0;  ///< tangential speed [m/s]
  };
  /// Contact at the stylus state (`vz_mps`: the stylus' normal velocity).
  Contact At(const Eigen::Vector3d& p_m, const Eigen::Vector3d& v_mps) const noexcept;
  /// The next contact-vibration sample [m/s^2] (resonant noise plus the micro-geometry's
  /// acceleration), zero out of contact.
  double Vibration(const Contact& c) noexcept;
  /// Highest point of the texture above the base [m] (where a stroke starts).
  double top_m() const { return top_m_; }
  const MaterialProfile& profile() const { return p_; }

 private:
  MaterialProfile p_;
  std::shared_ptr<const internal::TruthGeometry> geo_;
  double top_m_ = 0, offset_m_ = 0;
  Rng rng_;
  double c1_ = 0, c2_ = 0, var_ = 1, a1_ = 0, a2_ = 0;
};

/// A participant's hand on the stylus: follows a stroke on the sample's surface (a
/// back-and-forth path at constant speed), presses with integral control of the normal force
/// it feels (a ~20 rad/s loop), never pushes more than `max_descent_m` below where it
/// expects the surface, and accumulates the perceptual features of what it felt.
class Hand {
 public:
  struct Options {
    double max_descent_m = 0.01;  ///< how far below the expected surface a person pushes [m]
    double mass_kg = 0.15;        ///< hand + stylus mass that force fluctuations shake [kg]
    double contact_N = 0.05;      ///< felt force that counts as meeting the surface [N]
  };
  Hand();
  explicit Hand(const Options& o);
  /// Begins a stimulus: the stroke on a sample whose top is `top_m` above its base
  /// [sample frame], placed at `device_from_sample` (the truth), touching `truth` (null on a
  /// virtual side). `stiffness_N_per_m` sets the hand's force-loop gain. Not real-time.
  void Begin(const Stroke& s, const Eigen::Isometry3d& device_from_sample, double top_m,
             double stiffness_N_per_m, TruthSample* truth, double force_rate_hz,
             double vibration_rate_hz);
  /// The features of what the hand felt since Begin (call after the run stopped).
  Features Finish() noexcept;
  /// A person touching a point and holding still (setting up a rig by touch): from now to
  /// the next Begin or Hold, the stylus tip rests at `p_sample_m` [sample frame] of a sample
  /// placed at `device_from_sample` (the truth), whatever force the device pushes with. Not
  /// real-time; call between reads.
  void Hold(const Eigen::Isometry3d& device_from_sample, const Eigen::Vector3d& p_sample_m);

  // --- called by the simulated devices on the loops ---
  /// Moves to time `t_s` (seconds since the stimulus began) with the force felt since the
  /// last step; returns the stylus tip in the device frame.
  ToolState Step(double t_s) noexcept;
  /// The device pushes with `force_N` [N, device frame] from now to the next step.
  void Push(const Eigen::Vector3d& force_device_N) noexcept;
  /// One actuator sample reaches the hand [m/s^2].
  void FeelVibration(double acc_mps2) noexcept;

  /// Ticks on which the hand felt more than 0.3 N normal force, and ticks stepped (for tests).
  std::uint64_t contact_ticks() const { return contact_ticks_; }
  std::uint64_t ticks() const { return ticks_; }
  /// The stylus in the sample frame at the last step (for tests).
  const Eigen::Vector3d& p_sample_m() const { return p_; }

 private:
  void FlushInterval() noexcept;  // the felt vibration of the last force period
  Options o_;
  Stroke s_;
  SpscQueue<double> actuator_{4096};
  Eigen::Isometry3d device_from_sample_ = Eigen::Isometry3d::Identity();
  TruthSample* truth_ = nullptr;
  TruthSample::Contact contact_;
  FeatureAccumulator acc_;
  renderer::Biquad shake_hp_[3];
  double top_m_ = 0, gain_ = 0, ux_ = 1, uy_ = 0, z_m_ = 0, vz_mps_ = 0, t_s_ = 0, fn_felt_N_ = 0;
  double z_contact_m_ = 0, fr_ = 1000, vr_ = 10000;
  int vib_per_tick_ = 10;
  double shake_last_ = 0;
  bool touched_ = false, pending_ = false, interval_open_ = false, holding_ = false;
  Eigen::Vector3d p_ = Eigen::Vector3d::Zero(), v_ = Eigen::Vector3d::Zero();
  std::uint64_t contact_ticks_ = 0, ticks_ = 0;
};

/// A generic simulated haptic device (`--device sim`): reports the stylus the hand holds,
/// quantized to its encoder resolution, with velocity from the filtered difference of
/// positions like a real device; saturates forces at its limit; its link can return empty
/// reads at random and drop out for a while.
struct SimDeviceModel {
  std::string name = "sim";
  double max_force_N = 8.0;
  double max_stiffness_N_per_m = 3000;
  double max_rate_hz = 4000;
  double encoder_resolution_m = 1e-6;  ///< position quantum [m]
  double velocity_cutoff_hz = 300;     ///< low-pass of the differentiated position [Hz]
  double empty_read_probability = 0;   ///< link: a read with no new data
  std::uint64_t seed = 1;
};

class SimDevice final : public devices::HapticDevice {
 public:
  /// `clock`: the engine's virtual clock (borrowed), or null for the real clock (seconds
  /// since SetTimeBase). The hand is borrowed.
  SimDevice(const SimDeviceModel& m, Hand& hand, const devices::Clock* clock);
  devices::DeviceCapabilities Capabilities() const override;
  devices::ReadResult Read(DeviceSample* out) noexcept override;
  void WriteForce(const Eigen::Vector3d& force_N) noexcept override;
  void SetTimeBase(std::chrono::steady_clock::time_point t0) noexcept override;
  /// The link drops out (every read lost) from `start_s` for `duration_s` of the next run.
  void InjectDropout(double start_s, double duration_s) noexcept {
    dropout_start_s_ = start_s;
    dropout_s_ = duration_s;
  }
  /// Forgets the differentiation state (a new run).
  void Reset() noexcept;
  std::uint64_t reads() const { return reads_.load(std::memory_order_relaxed); }
  std::uint64_t empty_reads() const { return empty_reads_; }
  std::uint64_t lost_reads() const { return lost_reads_; }

 private:
  double Time() const noexcept;
  SimDeviceModel m_;
  Hand& hand_;
  const devices::Clock* clock_;
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
  Rng rng_;
  devices::VelocityFilter velocity_;
  double dropout_start_s_ = -1, dropout_s_ = 0;
  std::atomic<std::uint64_t> reads_{0};
  std::uint64_t empty_reads_ = 0, lost_reads_ = 0;
};

/// The vibrotactile actuator on the simulated stylus: what it plays reaches the hand.
class SimActuator final : public devices::Actuator {
 public:
  SimActuator(Hand& hand, double rate_hz) : hand_(hand), rate_hz_(rate_hz) {}
  double SampleRateHz() const override { return rate_hz_; }
  void Write(double acc_mps2) noexcept override { hand_.FeelVibration(acc_mps2); }

 private:
  Hand& hand_;
  double rate_hz_;
};

/// A whole simulated rig: the clock the engine steps, the hand, a device and an actuator, and
/// where the two samples truly are (device_from_sample, 0 left, 1 right). The device is the
/// generic SimDevice unless another back-end (a twin) is put in `device`.
struct SimRig {
  SimRig(const SimDeviceModel& m, const std::array<Eigen::Isometry3d, 2>& true_device_from_sample,
         double vibration_rate_hz = 10000);
  devices::VirtualClock clock;
  Hand hand;
  SimActuator actuator;
  std::unique_ptr<SimDevice> generic;       ///< the generic device (null when a twin replaced it)
  devices::HapticDevice* device = nullptr;  ///< what the engine drives
  FalconTwinTransport* twin = nullptr;      ///< the Falcon twin's link, when the device is one
  std::array<Eigen::Isometry3d, 2> true_device_from_sample;
};

/// The generic rig's sample poses: both samples flat on the table, left at x = -3 cm and
/// right at x = +3 cm of the device origin (device frame z up).
std::array<Eigen::Isometry3d, 2> DefaultSamplePoses();

}  // namespace hapticlab::sim
